"""What a policy observes, in the robot's frame (x forward, y left), as a ``Dict`` of float32 boxes.

Always ``velocity`` (the robot's executed v, omega), and for navigation ``goal`` (the goal's position), for
following ``tag`` (the tag sensor's reading of the target at this step: range in m, bearing in rad, and 1; zeros
when it read nothing: out of its 0.5-4.5 m coverage, or missed). Then the modes chosen at ``make``:

* ``truth``: the K nearest persons' exact positions, velocities and radii (``persons`` [K, 5]) and which rows hold
  someone (``persons_mask`` [K]): what CrowdNav's policies see; following adds the target's (``target`` [4]: x, y,
  vx, vy);
* ``laser``: the scan's ranges (``laser`` [beams]; no return reads the range limit);
* ``tracks``: the pipeline's K nearest tracks (``tracks`` [K, 8]: x, y, vx, vy, var_x, var_y, cov_xy, matched) and
  ``tracks_mask``: what the robot's own software believes, with its misses, false positives and id switches.

The bounds contain every observation: positions lie within the room (its diagonal bounds any offset), speeds and
variances are clipped to stated limits (a track's velocity to ``MAX_SPEED``, its variances to the pipeline's
``UNKNOWN_VARIANCE``).
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from pipeline.frames import inverse, rotate, rotate_covariances, rotation, transform_points
from pipeline.types import UNKNOWN_VARIANCE
from scenarios.typed import Scenario
from sensors.tag import TagSensor

MAX_SPEED = 5.0  # m/s: observed person and track speeds are clipped to this per axis (people walk below 2.6)
ROOM_DIAGONAL = float(np.hypot(14.0, 14.0))  # m, the largest room of ``layouts``


def _box(low, high, shape) -> spaces.Box:
    return spaces.Box(np.broadcast_to(np.float32(low), shape), np.broadcast_to(np.float32(high), shape),
                      dtype=np.float32)


class Observer:
    def __init__(self, config, scenario: Scenario):
        self.config = config
        robot, laser = scenario.robot, scenario.sensors.lasers[0]
        K, D = config.k_nearest, ROOM_DIAGONAL
        self.range_max = laser.range_max
        self.follow = config.task == "follow"
        parts = {"velocity": _box([-robot.max_speed, -robot.max_angular_speed],
                                  [robot.max_speed, robot.max_angular_speed], (2,))}
        if self.follow:
            parts["tag"] = _box([0.0, -np.pi, 0.0], [TagSensor.range_max, np.pi, 1.0], (3,))
        else:
            parts["goal"] = _box(-D, D, (2,))
        if "truth" in config.observation:
            parts["persons"] = _box([-D, -D, -MAX_SPEED, -MAX_SPEED, 0.0], [D, D, MAX_SPEED, MAX_SPEED, 1.0], (K, 5))
            parts["persons_mask"] = _box(0.0, 1.0, (K,))
            if self.follow:
                parts["target"] = _box([-D, -D, -MAX_SPEED, -MAX_SPEED], [D, D, MAX_SPEED, MAX_SPEED], (4,))
        if "laser" in config.observation:
            n = int(round(laser.fov_deg / laser.resolution_deg)) + (0 if laser.fov_deg >= 360 else 1)
            parts["laser"] = _box(0.0, self.range_max, (n,))
        if "tracks" in config.observation:
            V = UNKNOWN_VARIANCE
            parts["tracks"] = _box([-D, -D, -MAX_SPEED, -MAX_SPEED, 0.0, 0.0, -V, 0.0],
                                   [D, D, MAX_SPEED, MAX_SPEED, V, V, V, 1.0], (K, 8))
            parts["tracks_mask"] = _box(0.0, 1.0, (K,))
        self.space = spaces.Dict(parts)

    def __call__(self, episodes) -> dict[str, np.ndarray]:
        """The observations of every episode, batched [E, ...]."""
        w, K = episodes.worlds, self.config.k_nearest
        pose = w.robot_pose
        c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
        out = {"velocity": w.robot_velocity.copy()}
        if self.follow:
            out["tag"] = np.array([[0.0, 0.0, 0.0] if r is None else [r.range, r.bearing, 1.0]
                                   for r in episodes.tag_readings])
        else:
            gx, gy = w.goal[:, 0] - pose[:, 0], w.goal[:, 1] - pose[:, 1]
            out["goal"] = np.stack([c * gx + s * gy, -s * gx + c * gy], 1)
        if "truth" in self.config.observation:
            turn = (c - 1j * s)[:, None]  # world -> robot frame: a rotation by -yaw
            rel = (w.z - (pose[:, 0] + 1j * pose[:, 1])[:, None]) * turn
            vel = w.v * turn
            rows = np.stack([rel.real, rel.imag, vel.real, vel.imag, w.radius], axis=-1)
            out["persons"], out["persons_mask"] = _nearest(rows, np.abs(rel), K)
            if self.follow:
                out["target"] = rows[:, 0, :4]
        if "laser" in self.config.observation:
            ranges = np.stack([scan.ranges for scan in episodes.scans])
            out["laser"] = np.where(np.isfinite(ranges), ranges, self.range_max)
        if "tracks" in self.config.observation:
            out["tracks"], out["tracks_mask"] = self._tracks(episodes)
        space = self.space.spaces  # np.minimum/maximum: np.clip's wrapper costs more than the work here
        return {name: np.minimum(np.maximum(value, space[name].low), space[name].high).astype(np.float32)
                for name, value in out.items()}

    def _tracks(self, episodes) -> tuple[np.ndarray, np.ndarray]:
        K = self.config.k_nearest
        table = np.zeros((episodes.n, K, 8))
        mask = np.zeros((episodes.n, K))
        for k, tracks in enumerate(episodes.tracks):
            if tracks is None or len(tracks) == 0:
                continue
            base = inverse(episodes.odom_pose(k))  # odom -> base_link
            pos = transform_points(base, tracks.position)
            vel = rotate(base, tracks.velocity)
            cov = rotate_covariances(rotation(base), tracks.position_covariance)
            rows = np.column_stack([pos, vel, cov[:, 0, 0], cov[:, 1, 1], cov[:, 0, 1], tracks.is_matched])
            table[k], mask[k] = _nearest(rows[None], (pos * pos).sum(axis=1)[None], K)
        return table, mask


def _nearest(rows: np.ndarray, dist2: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` rows [E, n, f] of least ``dist2`` [E, n], nearest first, zero-padded, and the padding mask."""
    E, n, f = rows.shape
    order = np.argsort(dist2, axis=1, kind="stable")[:, :k]
    out = np.zeros((E, k, f))
    out[:, :min(n, k)] = rows[np.arange(E)[:, None], order]
    mask = np.zeros((E, k))
    mask[:, :min(n, k)] = 1.0
    return out, mask
