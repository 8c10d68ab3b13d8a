"""The MuJoCo scene and the robot's sensors."""

from .laser import Laser
from .scene import Scene, parts_at

__all__ = ["Laser", "Scene", "parts_at"]
