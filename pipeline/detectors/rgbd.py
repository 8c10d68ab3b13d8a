"""Seed 003's RGB-D people detector (Munaro & Menegatti Sec. 3) on a robot's depth camera: the cloud in voxels, the
ground followed and removed, people candidates split at their heads, each a person where their head stands, with the
image box that would hold them from head to ground (and, with a HOG model, that box's HOG confidence, Sec. 3.1.2).

Work in progress (issue 17): the HOG stage waits for a model trained on the robot camera's images.
"""

from __future__ import annotations

import numpy as np

from pipeline.types import DepthFrame, DetectedPersons

from .ground import GroundTracker, head_position
from .head_clusters import ClusterLimits, candidates
from .hog import PERSON_SHARE
from .point_cloud import voxel_grid


def person_box(camera_matrix: np.ndarray, ground: np.ndarray, normal: np.ndarray, height: float) -> np.ndarray:
    """The image box (u0, v0, u1, v1) of the window that holds, in its middle three quarters of height, a person of
    ``height`` standing at the floor point ``ground`` (camera frame; ``normal`` the floor's up), half as wide as
    high."""
    ends = np.array([ground, ground + height * normal])
    uvw = ends @ camera_matrix.T
    (u_foot, v_foot), (u_head, v_head) = uvw[:, :2] / uvw[:, 2:]
    tall = (v_foot - v_head) / PERSON_SHARE
    middle = ((u_foot + u_head) / 2, (v_foot + v_head) / 2)
    return np.array([middle[0] - tall / 4, middle[1] - tall / 2, middle[0] + tall / 4, middle[1] + tall / 2])


class RgbdPeopleDetector:
    """People in a depth camera's cloud (module docstring)."""

    def __init__(self, voxel: float = 0.06, head_distance: float = 0.3, up=(0.0, -1.0, 0.0),
                 max_tilt_deg: float = 30.0, sub_clustering: bool = True, position_variance: float = 0.01):
        self.voxel = voxel
        self.limits = ClusterLimits(voxel=voxel, head_distance=head_distance)
        self.ground = GroundTracker(voxel, up, max_tilt_deg)
        self.sub_clustering = sub_clustering
        self.position_variance = position_variance
        self.reset()

    def reset(self) -> None:
        self.ground.reset()
        self._next_id = 0

    def people(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The floor points [k, 3] (camera frame) where the people of a cloud stand, and their heights [k]."""
        cloud = voxel_grid(points, self.voxel)
        floor = self.ground.update(cloud)
        if self.ground.plane is None:
            return np.zeros((0, 3)), np.zeros(0)
        above = cloud[~floor]
        found = [head_position(above[c], self.ground.plane)
                 for c in candidates(above, self.ground.plane, self.limits, self.sub_clustering)]
        if not found:
            return np.zeros((0, 3)), np.zeros(0)
        return np.array([p for p, _ in found]), np.array([h for _, h in found])

    def detect(self, frame: DepthFrame) -> DetectedPersons:
        where, _ = self.people(frame.points)
        n = len(where)
        cov = np.repeat(np.diag([self.position_variance] * 3)[None], n, axis=0)
        out = DetectedPersons(frame.stamp, frame.frame, "rgbd", np.arange(self._next_id, self._next_id + n),
                              where, cov, np.ones(n))
        self._next_id += n
        return out
