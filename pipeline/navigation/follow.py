"""Following one person who wears a tag, among passers-by (seed 001 Sec. 3.2 and 7; its ref [5], Germa et al.,
CVIU 2010).

Only the user wears a tag, so the tag tells the user from the passers-by, but it is coarse (seed 001: "a coarse
position estimate (range and azimuth)"); the people tracks are precise but anonymous. The follower therefore picks
the track that agrees with the tag, keeps following that track id while it lives (the tag is not needed between
its readings), and asks the tag again when the track is lost or when a reading disagrees with it while agreeing
with another track (the tracker swapped the user's identity). Without a track it heads for where the tag last put
the user.

It drives with any planner (pipeline/navigation/planners.py) to a goal on the line from the robot to the user, at
the band's centre distance from the user, and treats the user as the goal, not as a passer-by: the planner sees the
other tracks only (seed 001 Sec. 7: zones around the passers-by, the user's position as the goal). It sets off when
the user is farther than the band's far edge, stops at the band's centre, and stands turning to face the user in
between and nearer (a robot that cannot back away should not turn its back on the user).
"""

from __future__ import annotations

import numpy as np

from pipeline.frames import transform_points, wrap_angle
from pipeline.types import TagReading, TrackedPersons

from .nd import drive
from .planners import Planner

GATE_CHI2 = 9.21
"""A track agrees with a tag reading when its range and bearing differences, normalised by the tag's stated errors
and the track's position covariance along and across the line of sight, give a squared Mahalanobis distance of at
most the chi-square 0.99 quantile with 2 degrees of freedom."""


class PersonFollower:
    """Follow the tagged person with ``planner``, staying ``band`` = (near, far) metres behind (default 1-2 m)."""

    def __init__(self, planner: Planner, band: tuple[float, float] = (1.0, 2.0), gate_chi2: float = GATE_CHI2):
        near, far = band
        if not 0 < near < far < np.inf:
            raise ValueError(f"person follower: band must be (near, far) with 0 < near < far m, got {band!r}")
        if not gate_chi2 > 0:
            raise ValueError(f"person follower: gate_chi2 must be > 0, got {gate_chi2!r}")
        self.planner, self.band, self.gate = planner, (float(near), float(far)), float(gate_chi2)
        self.reset()

    def reset(self) -> None:
        self.planner.reset()
        self.target_track = -1
        self._estimate: np.ndarray | None = None  # odom, where the latest tag reading put the user
        self._driving = False

    def command(self, stamp: float, pose: np.ndarray, velocity: np.ndarray, obstacles: np.ndarray,
                tracks: TrackedPersons, tag: TagReading | None) -> tuple[float, float]:
        """(v, omega) for the next tick; ``pose``, ``obstacles`` and ``tracks`` in odom, ``tag`` in base_link (None
        when the tag sensor gave nothing this tick)."""
        pose = np.asarray(pose, float)
        if tag is not None:
            local = tag.range * np.array([[np.cos(tag.bearing), np.sin(tag.bearing)]])
            self._estimate = transform_points(pose, local)[0]
        self.target_track = self._associate(pose, tracks, tag)
        mine = tracks.track_id == self.target_track
        target = tracks.position[mine][0] if mine.any() else self._estimate
        if target is None:
            return 0.0, 0.0
        offset = target - pose[:2]
        distance = float(np.hypot(offset[0], offset[1]))
        centre = (self.band[0] + self.band[1]) / 2
        if distance > self.band[1]:
            self._driving = True
        elif distance <= centre:
            self._driving = False
        if not self._driving:
            bearing = float(wrap_angle(np.arctan2(offset[1], offset[0]) - pose[2]))
            return drive(0.0, bearing, self.planner.p["max_angular_speed"])
        goal = target - centre * offset / distance
        return self.planner.command(stamp, pose, velocity, obstacles, tracks.select(~mine), goal)

    def _associate(self, pose: np.ndarray, tracks: TrackedPersons, tag: TagReading | None) -> int:
        """The track id to follow: the current one while it lives and no reading contradicts it, else the track
        nearest to the reading within the gate, else none (-1)."""
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
            return self.target_track
        best = int(d2.argmin())
        if d2[best] <= self.gate:
            return int(tracks.track_id[best])
        return self.target_track if alive else -1


def _squared(diff: np.ndarray, var: np.ndarray) -> np.ndarray:
    """diff^2 / var, where a zero variance (no error stated, none in the track) allows no difference at all."""
    exact = np.where(diff == 0, 0.0, np.inf)
    return np.divide(diff ** 2, var, out=exact, where=var > 0)
