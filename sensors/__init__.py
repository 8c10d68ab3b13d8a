"""The MuJoCo scene and the robot's sensors."""

from .laser import Laser
from .scene import Scene

__all__ = ["Laser", "Scene"]
