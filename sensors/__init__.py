"""The MuJoCo scene and the robot's sensors.

MuJoCo picks its OpenGL backend from ``MUJOCO_GL`` when it is first imported, so this package sets it first, unless
the user has: EGL where libEGL is installed (offscreen, no display or GPU needed with Mesa), else OSMesa, else none,
in which case cameras fall back to ray casting (sensors/camera.py says which ran).
"""

import ctypes.util
import os

if "MUJOCO_GL" not in os.environ:
    os.environ["MUJOCO_GL"] = ("egl" if ctypes.util.find_library("EGL")
                               else "osmesa" if ctypes.util.find_library("OSMesa") else "disable")

from .laser import Laser  # noqa: E402
from .scene import Scene, parts_at  # noqa: E402

__all__ = ["Laser", "Scene", "parts_at"]
