"""2D rigid transforms as (x, y, yaw) poses: composition, inversion and batched point transforms."""

from __future__ import annotations

import numpy as np


def wrap_angle(a):
    """Angles wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(a, float), 2 * np.pi)


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The pose of frame b (given in frame a) expressed in a's parent frame: a * b (poses [..., 3])."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    out = np.empty(a.shape if a.ndim >= b.ndim else b.shape)  # one pose and many, or as many of each
    out[..., 0] = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    out[..., 1] = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    out[..., 2] = wrap_angle(a[..., 2] + b[..., 2])
    return out


def inverse(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a[2]), np.sin(a[2])
    return np.array([-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]])


def transform_points(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points [n, 2] given in the frame ``pose`` describes, expressed in that pose's parent frame."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return points @ np.array([[c, s], [-s, c]]) + pose[:2]
