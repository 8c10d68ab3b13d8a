"""2D laser scanners ray-cast with MuJoCo: one batched ``mj_multiRay`` call per scan, and the range error of the
datasheets: a bias fixed per beam (the systematic error) plus Gaussian noise per return (the statistical error),
both by range band (see scenarios/laser_presets.py)."""

from __future__ import annotations

import mujoco
import numpy as np

from pipeline.frames import compose
from pipeline.types import LaserScan

from .scene import Scene


class Laser:
    """A planar laser mounted on the robot (``mount`` is its pose in base_link, ``height`` above the floor)."""

    def __init__(self, params: dict, scene: Scene, rng: np.random.Generator):
        self.p = params
        self.name = params["name"]
        self.scene = scene
        self.rng = rng
        self.mount = np.array(params["mount"], float)
        fov, res = np.radians(params["fov_deg"]), np.radians(params["resolution_deg"])
        full_circle = params["fov_deg"] >= 360.0
        # a full circle has no last beam: it would repeat the first
        self.n_beams = int(round(fov / res)) + (0 if full_circle else 1)
        if self.n_beams < 2:
            raise ValueError(f"laser {self.name}: fov_deg / resolution_deg gives {self.n_beams} beam(s); expected >= 2")
        self.angle_min = -fov / 2
        self.angle_increment = fov / (self.n_beams if full_circle else self.n_beams - 1)
        self.angles = self.angle_min + self.angle_increment * np.arange(self.n_beams)
        self.period = 1.0 / params["rate"]
        bands = params["noise"]
        self._band_edges = np.array([b["up_to"] for b in bands[:-1]])
        self._systematic = np.array([b["systematic"] for b in bands] or [0.0])
        self._statistical = np.array([b["statistical"] for b in bands] or [0.0])
        # where each beam's fixed bias lies within +- the systematic bound: drawn once, so a beam repeats its bias
        self._bias_share = rng.uniform(-1.0, 1.0, self.n_beams)
        self._vec = np.zeros((self.n_beams, 3))
        self._dist = np.zeros(self.n_beams)
        self._geom = np.zeros(self.n_beams, np.int32)
        self._groups = scene.groups_at(params["height"])  # only the body parts at the laser's height

    def pose_in(self, base_pose: np.ndarray) -> np.ndarray:
        """The laser's pose in the frame ``base_pose`` is given in."""
        return compose(base_pose, self.mount)

    def scan(self, stamp: float, robot_pose: np.ndarray) -> LaserScan:
        """Cast every beam from the laser's true pose; the scene must be synced to the same instant."""
        pose = self.pose_in(robot_pose)
        a = pose[2] + self.angles
        self._vec[:, 0] = np.cos(a)
        self._vec[:, 1] = np.sin(a)
        origin = np.array([pose[0], pose[1], self.p["height"]])
        m, d = self.scene.model, self.scene.data
        mujoco.mj_multiRay(m, d, origin, self._vec.reshape(-1), self._groups, 1, self.scene.robot_body, self._geom,
                           self._dist, None, self.n_beams, self.p["range_max"])
        hit = (self._dist >= self.p["range_min"]) & (self._dist <= self.p["range_max"])
        ranges = self._dist + self.range_error(self._dist)
        ranges = np.where(hit, np.clip(ranges, self.p["range_min"], self.p["range_max"]),
                          np.nan if self.p["no_return"] == "nan" else self.p["range_max"])
        person = np.where(hit, self.scene.person_of_geom(self._geom), -1)
        return LaserScan(stamp, self.name, self.angle_min, self.angle_increment, self.p["range_max"], ranges, person)

    def range_error(self, true_range: np.ndarray) -> np.ndarray:
        """Each beam's error at these true ranges: its fixed bias plus fresh Gaussian noise, by range band."""
        band = np.searchsorted(self._band_edges, true_range)
        noise = self.rng.standard_normal(self.n_beams) * self._statistical[band]
        return noise + self._bias_share * self._systematic[band]
