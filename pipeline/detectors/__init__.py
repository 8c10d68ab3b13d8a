"""Detectors: each turns one sensor's frame into ``DetectedPersons`` in that sensor's frame. ``DETECTORS``: the
built-in ones by the type name a scenario gives them (their parameters are declared on each class)."""

from .laser_segments import SegmentDetector
from .learned_segments import LearnedSegmentDetector
from .legs import LegDetector
from .rgbd import RgbdPeopleDetector
from .wall_camera import WallCameraDetector

DETECTORS: dict[str, type] = {"laser_segments": SegmentDetector, "laser_learned": LearnedSegmentDetector,
                              "laser_legs": LegDetector, "wall_people": WallCameraDetector,
                              "rgbd_people": RgbdPeopleDetector}
