"""A sensor and a detector of one's own (docs/extending.md): radio beacons worn by everyone, read all round the robot
within a range, and a detector that turns a reading into DetectedPersons. Name them in a scenario:

    sensors:
      custom: [{type: beacons:Beacons, name: beacons, rate: 5.0, range: 6.0}]
    pipeline:
      detectors: {beacons: {type: beacons:BeaconDetector}}
"""

from dataclasses import dataclass

import numpy as np

from pipeline.frames import inverse, transform_points
from pipeline.types import DetectedPersons
from sensors.base import Periodic


@dataclass
class BeaconFrame:
    stamp: float
    frame: str  # the sensor's name: the detector of that name reads it
    ids: np.ndarray
    xy: np.ndarray  # [n, 2] base_link


class Beacons(Periodic):
    """Everyone within ``range`` m of the robot, exactly, in base_link, ``rate`` times a second. ``Periodic`` is the
    clock (start, due, captured); the loop calls capture when it is due."""

    def __init__(self, name: str, rate: float, range: float):
        self.name, self.period, self.range = name, 1.0 / rate, range
        self.stamps = []

    def capture(self, world, stamp):
        self.stamps.append(stamp)
        agents, pose = world.agents(), world.robot.pose  # a simulated sensor reads the true world
        near = np.hypot(*(agents.position - pose[:2]).T) <= self.range
        return BeaconFrame(stamp, self.name, agents.id[near], transform_points(inverse(pose), agents.position[near]))

    def pose_in_odom(self, world):
        return world.robot.odom_pose  # mounted at base_link: where odometry believes the robot is

    def shown(self, world, frame):
        """What the frame showed of each person alive (here 1 or 0), and whether they were in view."""
        amount = np.isin(world.agents().id, frame.ids).astype(float)
        return amount, amount > 0


class BeaconDetector:
    """A person per beacon, 0.1 m standard deviation, in the sensor's frame."""

    def __init__(self):
        self.frames = []

    def detect(self, frame: BeaconFrame) -> DetectedPersons:
        self.frames.append(frame)
        n = len(frame.ids)
        return DetectedPersons(frame.stamp, frame.frame, "beacon", frame.ids.astype(np.int64),
                               np.column_stack([frame.xy, np.zeros(n)]), np.tile(np.eye(3) * 0.01, (n, 1, 1)),
                               np.ones(n))

    def reset(self):
        self.frames = []
