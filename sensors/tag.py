"""A tag sensor like seed 001's RFID: the range and bearing of the one tagged person, all around the robot.

Seed 001 Sec. 3.2 gives what its reader does: it detects the tag "around the robot (360 deg FOV) within the range of
0.5 m to 4.5 m" and yields "a coarse position estimate (range and azimuth)"; Fig. 3(c) shows it as a blob spanning
tens of degrees. Neither seed 001 nor what is at hand of its ref [5] (Germa et al., CVIU 2010) states the errors,
the detection rate or the read rate, so those defaults are assumptions, sized to "coarse":

* bearing sd 20 deg: a reader that locates the tag by which antennas of a ring around the robot receive it resolves
  about one antenna lobe (tens of degrees), as Fig. 3(c)'s blob shows;
* range sd 0.5 m: signal-strength ranging, an eighth of the 4 m span;
* detection probability 0.9 per read: body shadowing loses some reads;
* 5 Hz: a read cycle of a few antennas; well above the seed's 1 Hz system cycle (Sec. 7), so the tag is not
  what limits it.

Errors are Gaussian, drawn fresh per reading; the reported range is kept within the coverage, the bearing wrapped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.frames import inverse, transform_points, wrap_angle
from pipeline.params import ordered, param
from pipeline.types import TagReading

from .base import DUE_TOLERANCE


@dataclass(kw_only=True, eq=False)
class TagSensor:
    """Reads the tag at ``rate`` Hz from the robot's true pose: ``TagSensor(rng=..., **params)``."""

    rate: float = param(5.0, "Hz, readings per second (an assumption)", min=0.0, exclusive_min=True)
    range_min: float = param(0.5, "m, nearest tag read (seed 001 Sec. 3.2)", min=0.0)
    range_max: float = param(4.5, "m, farthest tag read (seed 001 Sec. 3.2)", min=0.0, exclusive_min=True)
    range_sd: float = param(0.5, "m, range error sd (an assumption: coarse)", min=0.0)
    bearing_sd_deg: float = param(20.0, "deg, bearing error sd (an assumption: one antenna lobe)", min=0.0)
    detection_probability: float = param(0.9, "chance a due reading is had (an assumption)", min=0.0, max=1.0)
    rng: np.random.Generator

    CHECKS = (ordered("range_min", "range_max", strict=True),)
    name = "tag"

    def __post_init__(self):
        self.period = 1.0 / self.rate
        self.bearing_sd = float(np.radians(self.bearing_sd_deg))
        self._next: float | None = None

    # as a Sensor (sensors/base.py): its own clock starts at its first read, and it has no detector nor visibility
    def start(self, t: float) -> None:
        pass

    def due(self, stamp: float) -> bool:
        return self._next is None or stamp >= self._next - DUE_TOLERANCE

    def captured(self, stamp: float) -> None:
        pass

    def capture(self, world, stamp: float) -> TagReading | None:
        return self.read(stamp, world.robot.pose, world.tagged_position())

    def pose_in_odom(self, world) -> None:
        return None

    def shown(self, world, reading) -> None:
        return None

    def read(self, stamp: float, robot_pose_world: np.ndarray, target_xy_world: np.ndarray | None) -> TagReading | None:
        """The reading due at ``stamp`` (None between reads, with no tagged person, out of coverage, or missed)."""
        if not self.due(stamp):
            return None
        self._next = (stamp if self._next is None else self._next) + self.period
        if self._next <= stamp:  # called after a pause: read at the rate from now on
            self._next = stamp + self.period
        if target_xy_world is None:
            return None
        rel = transform_points(inverse(np.asarray(robot_pose_world, float)),
                               np.asarray(target_xy_world, float).reshape(1, 2))[0]
        true_range = float(np.hypot(rel[0], rel[1]))
        if not self.range_min <= true_range <= self.range_max or self.rng.random() >= self.detection_probability:
            return None
        noise = self.rng.standard_normal(2)
        reported = float(np.clip(true_range + self.range_sd * noise[0], self.range_min, self.range_max))
        bearing = float(wrap_angle(np.arctan2(rel[1], rel[0]) + self.bearing_sd * noise[1]))
        return TagReading(stamp, reported, bearing, float(self.range_sd), self.bearing_sd)
