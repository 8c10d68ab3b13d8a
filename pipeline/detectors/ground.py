"""The ground plane under a robot's depth camera, followed from frame to frame (seed 003 Sec. 3: "updated at every
frame by considering as initial condition the estimation at the previous frame, thus allowing real time adaptation
to small changes in the floor slope or camera oscillations"), and a person's position from its head.

As in the authors' released code (PCL's ground-based people detection): the first plane by RANSAC, the floor taken
within two voxels of it; at each later frame the plane refitted by least squares to the points within two voxels of
the last one, when there are at least 300 of them at 6 cm voxels (fewer: the last plane is kept). The paper has the
user pick the first plane's three points; here RANSAC finds it, held to planes within ``max_tilt`` of ``up`` (the
camera's mounting gives the up direction in its frame).

A person's head centroid is a kernel (a frame has several people, each a few numpy calls of a few microseconds); the
heights above the plane stay numpy's, as the plane fit does.
"""

from __future__ import annotations

import numpy as np

from pipeline.compiled import kernel

from .point_cloud import fit_plane, plane_distance, ransac_plane

HEAD_SHARE = 1 / 8  # of a person's height: their head (PCL: "head is suppose to be 1/8 of the human height")
VIEW_SHIFT = 0.1  # m along the viewing ray: the head's centroid is on its surface (seed 003 Sec. 3.1.2)


class GroundTracker:
    """The plane (a, b, c, d), normal up, of the floor in the camera's frame."""

    def __init__(self, voxel: float = 0.06, up=(0.0, -1.0, 0.0), max_tilt_deg: float = 30.0,
                 iterations: int = 200, seed: int = 0):
        self.threshold = 2 * voxel
        self.min_inliers = int(round(300 * 0.06 / voxel))
        self.up = np.asarray(up, float) / np.linalg.norm(up)
        self.max_tilt = np.radians(max_tilt_deg)
        self.iterations, self.seed = iterations, seed
        self.reset()

    def reset(self) -> None:
        self.plane: np.ndarray | None = None
        self.rng = np.random.default_rng(self.seed)

    def update(self, points: np.ndarray) -> np.ndarray:
        """The floor's points among ``points`` (a mask), after updating the plane with them; all False while no
        plane is found."""
        if self.plane is None:
            self.plane, _ = ransac_plane(points, self.threshold, self.rng, self.iterations, self.up, self.max_tilt)
            if self.plane is None:
                return np.zeros(len(points), bool)
        else:
            near = np.abs(plane_distance(points, self.plane)) <= self.threshold
            if near.sum() >= self.min_inliers:
                plane = fit_plane(points[near])
                self.plane = plane if plane[:3] @ self.plane[:3] > 0 else -plane
        return np.abs(plane_distance(points, self.plane)) <= self.threshold


def head_position(points: np.ndarray, plane: np.ndarray) -> tuple[np.ndarray, float]:
    """Where a person candidate (its points, camera frame, the camera at the origin) stands: the centroid of its
    head (the top ``HEAD_SHARE`` of its height) moved ``VIEW_SHIFT`` further along the camera's ray, dropped onto the
    ground; and the candidate's height."""
    heights = plane_distance(points, plane)
    head, top = _shifted_head(points, heights)
    return head - plane_distance(head[None], plane)[0] * plane[:3], top


@kernel
def _shifted_head(points, heights):
    """``head_position``'s head centroid moved along its ray, not yet on the ground, and the highest height: summed
    in the order of the points, as numpy's mean and norm sum them."""
    top = heights.max()
    head, count = np.zeros(3), 0
    for i in range(len(points)):
        if heights[i] >= top * (1 - HEAD_SHARE):
            for k in range(3):
                head[k] += points[i, k]
            count += 1
    for k in range(3):
        head[k] /= count
    length = np.sqrt(head[0] * head[0] + head[1] * head[1] + head[2] * head[2])
    for k in range(3):
        head[k] += VIEW_SHIFT * head[k] / length
    return head, top
