"""The pedestrian simulator (PedSim's equivalent): social forces, body contacts, behaviours, and the model's
validation against RiMEA and Weidmann."""

from .crowd import AgentStates, Crowd

__all__ = ["AgentStates", "Crowd"]
