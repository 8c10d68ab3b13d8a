"""Evaluation of people tracking against the simulator's ground truth."""

from evaluation.clearmot import ClearMot, FrameResult

__all__ = ["ClearMot", "FrameResult"]
