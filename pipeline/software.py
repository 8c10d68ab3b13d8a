"""The robot's software: the one detect -> map filter -> fusion -> track -> groups chain.

Detectors run as each sensor frame arrives (``receive``), as a robot's detector nodes run on each message, so a
frame's detections are placed with the pose of its own instant; the rest runs once per tracking cycle (``cycle``).
The simulation loop, the gym environments' ``tracks`` observation and the experiments' replays all go through it.
It sees only what a robot has: its sensors' frames, where each sensor was (its calibration on the odometry pose, or
through the localisation for a fixed camera) and the localisation in the map.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .assemble import Pipeline
from .fusion import to_frame
from .types import CameraFrame, DepthFrame, DetectedPersons, SocialRelations, TrackedGroups, TrackedPersons

TRACKING_FRAME = "odom"


@dataclass
class Perception:
    """What one cycle of the robot's software made."""

    detections: DetectedPersons  # fused, in the tracking frame
    tracks: TrackedPersons
    relations: SocialRelations
    groups: TrackedGroups
    # each detector's own output since the previous cycle (sensor, or sensor/batch, -> its detections in the tracking
    # frame, after the map filter when there is one), before the fusion
    detector_outputs: dict[str, DetectedPersons] = field(default_factory=dict)


@dataclass
class SoftwareTiming:
    """Seconds spent in the tracker and the group stage, and the cycles run."""

    tracker_s: float = 0.0
    groups_s: float = 0.0
    cycles: int = 0


class RobotSoftware:
    """The parts of a ``Pipeline`` run in order. ``groups=False`` leaves the group stage out (the gym environments
    observe tracks only)."""

    def __init__(self, parts: Pipeline, groups: bool = True):
        self.parts = parts  # made, so at their start
        self.with_groups = groups
        self._waiting: dict[str, DetectedPersons] = {}
        self.timing = SoftwareTiming()

    def reset(self) -> None:
        """Every part starts over, and nothing waits for a cycle."""
        self.parts.reset()
        self._waiting = {}
        self.timing = SoftwareTiming()

    def detects(self, sensor: str) -> bool:
        return sensor in self.parts.detectors

    def receive(self, frame, sensor_pose: np.ndarray, world_T_odom: np.ndarray | None = None) -> None:
        """Run the detector of ``frame``'s sensor (if it has one) on it. Its detections, brought into the tracking
        frame with ``sensor_pose`` (the sensor's pose there: (x, y, yaw), or a 4x4 for a camera) and, with a map
        filter, rid of those on the map (placed there through the localisation ``world_T_odom``), wait for the next
        cycle; a sensor's latest replace its earlier ones. A detector that gives several named batches (a camera's
        foreground blobs and HOG windows) has each wait as ``sensor/name``."""
        detector = self.parts.detectors.get(frame.frame)
        if detector is None:
            return
        found = detector.detect(frame)
        for name, batch in (found.items() if isinstance(found, dict) else ((None, found),)):
            detections = to_frame(batch, sensor_pose, TRACKING_FRAME)
            if self.parts.map_filter is not None:
                detections = self.parts.map_filter.filter(detections, world_T_odom)
            self._waiting[frame.frame if name is None else f"{frame.frame}/{name}"] = detections

    def cycle(self, stamp: float, images: list[CameraFrame | DepthFrame] = ()) -> Perception:
        """Fuse what waits (none: no detections), track, and group. ``images``, the camera frames since the previous
        cycle, go first to a tracker that weighs colour (one with a ``see`` method)."""
        outputs, self._waiting = self._waiting, {}
        detections = (self.parts.fusion.fuse(outputs) if outputs
                      else DetectedPersons.empty(stamp, TRACKING_FRAME, "none"))
        tracker = self.parts.tracker
        t0 = time.perf_counter()
        if images and hasattr(tracker, "see"):
            tracker.see(list(images))
        tracks = tracker.update(stamp, detections)
        t1 = time.perf_counter()
        self.timing.tracker_s += t1 - t0
        self.timing.cycles += 1
        if self.with_groups:
            relations, groups = self.parts.groups.update(stamp, tracks)
            self.timing.groups_s += time.perf_counter() - t1
        else:
            relations, groups = SocialRelations(stamp), TrackedGroups(stamp, TRACKING_FRAME)
        return Perception(detections, tracks, relations, groups, outputs)
