"""``crowdsim.Error``: every error a user can cause derives from it (scenarios/errors.py says why it lives there)."""

from scenarios.errors import Error

__all__ = ["Error"]
