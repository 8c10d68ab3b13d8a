"""Following one person who wears a tag, among passers-by (seed 001 Sec. 3.2 and 7; its ref [5], Germa et al.,
CVIU 2010).

Only the user wears a tag, so the tag tells the user from the passers-by, but it is coarse (seed 001: "a coarse
position estimate (range and azimuth)"); the people tracks are precise but anonymous. The follower therefore picks
the track that agrees with the tag, keeps following that track id while it lives (the tag is not needed between
its readings), and asks the tag again when the track is lost or when ``switch_readings`` readings in a row disagree
with it while agreeing with another track (the tracker swapped the user's identity; one reading in a hundred
disagrees with the right track by chance, at the gate's 0.99). Of the tracks a reading agrees with, a coarse tag's
gate holds the passers-by near the user too, so it takes the one nearest to where the follower expects the user. Without a track it heads for where the user was last
known to be (the track's last position, or a later tag reading), moved on at the track's last velocity for up to
``predict_time``: a user who walked out of the tag's range while hidden is looked for where they were going, not
where they were.

It drives with any planner (pipeline/navigation/planners.py) to a goal on the line from the robot to the user and
treats the user as the goal, not as a passer-by: the planner sees the other tracks only (seed 001 Sec. 7: zones
around the passers-by, the user's position as the goal). The goal lies short of the user by the band's centre less
the distance the planner's braking leaves behind a goal moving at the user's speed (v^2 / 2a plus its goal
tolerance; planners.py brakes as v <= sqrt(2 a s)), at least the band's near edge: so the robot rides at the band's
centre behind a walking user, and stops at it behind one who stands. It sets off when the user is beyond the band's
far edge, or beyond its centre and walking away; it stops when it has reached its goal, and stands turning to face
the user (a robot that cannot back away should not turn its back on the user).
"""

from __future__ import annotations

import numpy as np

from pipeline.frames import transform_points, wrap_angle
from pipeline.types import TagReading, TrackedPersons

from .nd import drive
from .planners import Planner

WALKING = 0.25
"""m/s: a user tracked faster than this walks (the security zones' standing speed, zones.py)."""

SWITCH_READINGS = 2
"""Readings in a row that must disagree with the followed track, and agree with another, to switch to that one."""

PREDICT_TIME = 3.0
"""s: how long a lost user is assumed to walk on at their last tracked velocity (an assumption: about the time a
passer-by takes to walk past and uncover them, 2 m at 1.34 m/s; a user who turned meanwhile is found by the tag)."""

GATE_CHI2 = 9.21
"""A track agrees with a tag reading when its range and bearing differences, normalised by the tag's stated errors
and the track's position covariance along and across the line of sight, give a squared Mahalanobis distance of at
most the chi-square 0.99 quantile with 2 degrees of freedom."""


class PersonFollower:
    """Follow the tagged person with ``planner``, staying ``band`` = (near, far) metres behind (default 1-2 m)."""

    def __init__(self, planner: Planner, band: tuple[float, float] = (1.0, 2.0), gate_chi2: float = GATE_CHI2,
                 predict_time: float = PREDICT_TIME, switch_readings: int = SWITCH_READINGS):
        near, far = band
        if not 0 < near < far < np.inf:
            raise ValueError(f"person follower: band must be (near, far) with 0 < near < far m, got {band!r}")
        if not gate_chi2 > 0:
            raise ValueError(f"person follower: gate_chi2 must be > 0, got {gate_chi2!r}")
        if not 0 <= predict_time < np.inf:
            raise ValueError(f"person follower: predict_time must be a finite number of s >= 0, got {predict_time!r}")
        self.planner, self.band, self.gate = planner, (float(near), float(far)), float(gate_chi2)
        self.predict_time = float(predict_time)
        if not (isinstance(switch_readings, (int, np.integer)) and switch_readings >= 1):
            raise ValueError(f"person follower: switch_readings must be a whole number >= 1, got {switch_readings!r}")
        self.switch_readings = int(switch_readings)
        self.reset()

    def reset(self) -> None:
        self.planner.reset()
        self.target_track = -1
        self._estimate: np.ndarray | None = None  # odom, where the user was last known to be
        self._estimate_stamp = 0.0
        self._velocity = np.zeros(2)  # odom, the user's velocity as last tracked
        self._driving = False
        self._disagreed = 0  # readings in a row that disagreed with the followed track

    def command(self, stamp: float, pose: np.ndarray, velocity: np.ndarray, obstacles: np.ndarray,
                tracks: TrackedPersons, tag: TagReading | None) -> tuple[float, float]:
        """(v, omega) for the next tick; ``pose``, ``obstacles`` and ``tracks`` in odom, ``tag`` in base_link (None
        when the tag sensor gave nothing this tick)."""
        pose = np.asarray(pose, float)
        expected = self._expected(stamp)
        if tag is not None:
            local = tag.range * np.array([[np.cos(tag.bearing), np.sin(tag.bearing)]])
            self._estimate, self._estimate_stamp = transform_points(pose, local)[0], stamp
        self.target_track = self._associate(pose, tracks, tag, expected)
        mine = tracks.track_id == self.target_track
        if mine.any():
            target = tracks.position[mine][0]
            self._estimate, self._estimate_stamp, self._velocity = target.copy(), stamp, tracks.velocity[mine][0]
        elif self._estimate is None:
            return 0.0, 0.0
        else:
            target = self._expected(stamp)
        offset = target - pose[:2]
        distance = float(np.hypot(offset[0], offset[1]))
        near, far = self.band
        centre = (near + far) / 2
        tolerance = getattr(self.planner, "goal_tolerance", 0.0)
        speed = float(np.hypot(*self._velocity))
        aim = float(np.clip(centre - speed ** 2 / (2 * getattr(self.planner, "max_acceleration", np.inf)) - tolerance,
                            near, centre))
        away = speed >= WALKING and distance > 0 and float(offset @ self._velocity) > 0
        if distance > far or (distance > centre and away):
            self._driving = True
        elif distance <= aim + tolerance:
            self._driving = False
        if not self._driving:
            bearing = float(wrap_angle(np.arctan2(offset[1], offset[0]) - pose[2]))
            return drive(0.0, bearing, self.planner.max_angular_speed)
        goal = target - aim * offset / distance
        return self.planner.command(stamp, pose, velocity, obstacles, tracks.select(~mine), goal)

    def _expected(self, stamp: float) -> np.ndarray | None:
        """Where the user should be now (odom): last known there, walking on at the last tracked velocity for at
        most ``predict_time``; None before anything was known."""
        if self._estimate is None:
            return None
        return self._estimate + self._velocity * min(max(stamp - self._estimate_stamp, 0.0), self.predict_time)

    def _associate(self, pose: np.ndarray, tracks: TrackedPersons, tag: TagReading | None,
                   expected: np.ndarray | None) -> int:
        """The track id to follow: the current one while it lives and fewer than ``switch_readings`` readings in a
        row contradicted it, else of the tracks within the reading's gate the one nearest to where the user is
        expected (the nearest to the reading before anything was known), else none (-1)."""
        mine = tracks.track_id == self.target_track
        alive = self.target_track >= 0 and bool(mine.any())
        if tag is None or not len(tracks):
            return self.target_track if alive else -1
        rel = tracks.position - pose[:2]
        r = np.maximum(np.hypot(rel[:, 0], rel[:, 1]), 1e-6)
        along = rel / r[:, None]
        across = np.stack([-along[:, 1], along[:, 0]], axis=1)
        cov = tracks.position_covariance
        var_r = tag.range_sd ** 2 + np.einsum("ki,kij,kj->k", along, cov, along)
        var_b = tag.bearing_sd ** 2 + np.einsum("ki,kij,kj->k", across, cov, across) / r ** 2
        bearing = wrap_angle(np.arctan2(rel[:, 1], rel[:, 0]) - pose[2] - tag.bearing)
        d2 = _squared(r - tag.range, var_r) + _squared(bearing, var_b)
        if alive and d2[mine][0] <= self.gate:
            self._disagreed = 0
            return self.target_track
        agree = np.flatnonzero(d2 <= self.gate)
        if alive:
            self._disagreed += 1
            if self._disagreed < self.switch_readings or not agree.size:
                return self.target_track
        self._disagreed = 0
        if not agree.size:
            return self.target_track if alive else -1
        if expected is None:
            return int(tracks.track_id[agree[d2[agree].argmin()]])
        off = tracks.position[agree] - expected
        return int(tracks.track_id[agree[np.hypot(off[:, 0], off[:, 1]).argmin()]])


def _squared(diff: np.ndarray, var: np.ndarray) -> np.ndarray:
    """diff^2 / var, where a zero variance (no error stated, none in the track) allows no difference at all."""
    exact = np.where(diff == 0, 0.0, np.inf)
    return np.divide(diff ** 2, var, out=exact, where=var > 0)
