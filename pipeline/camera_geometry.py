"""A calibrated camera and the floor: the homography between floor points and pixels, as a wall-camera tracker
projects a person's feet onto the ground plane (seed 001 Sec. 4.2-4.3: detections "projected to yield ground
positions").

A camera is its 3x3 matrix K (pinhole, pixel u covering [u, u + 1)) and its pose: the optical frame (x right, y down,
z forward) as a 4x4 transform into the floor's frame, whose z = 0 is the floor.
"""

from __future__ import annotations

import numpy as np


def floor_homography(camera_matrix: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """The 3x3 map from floor points (x, y, 1) to image points (u, v, 1), up to scale."""
    rot, origin = pose[:3, :3], pose[:3, 3]
    # a floor point p = (x, y, 0) sits at rot^T (p - origin) in the optical frame
    return camera_matrix @ np.column_stack([rot.T[:, 0], rot.T[:, 1], -rot.T @ origin])


def image_to_floor(camera_matrix: np.ndarray, pose: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """The floor points [n, 2] seen at image points ``uv`` [n, 2]; NaN for points at or above the horizon."""
    uv = np.asarray(uv, float).reshape(-1, 2)
    g = np.column_stack([uv, np.ones(len(uv))]) @ np.linalg.inv(floor_homography(camera_matrix, pose)).T
    with np.errstate(divide="ignore", invalid="ignore"):
        xy = g[:, :2] / g[:, 2:]
    ahead = ((np.column_stack([xy, np.zeros(len(xy))]) - pose[:3, 3]) @ pose[:3, :3])[:, 2] > 0
    return np.where(ahead[:, None], xy, np.nan)
