"""Rigid transforms, the one place for frame maths: 2D poses (x, y, yaw) composed, inverted and applied to points,
vectors and covariances, and 4x4 transforms for what a sensor sees in 3D.

The matrix forms (``points @ ...``) and the component forms (``compose``, ``inverse``) round differently in the last
bit (the matrix product may fuse a multiply and an add), so each function keeps the form its callers always had:
the same inputs give the same bits everywhere.
"""

from __future__ import annotations

import numpy as np

from .compiled import elementwise, kernel


@elementwise
def wrap_angle(a):
    """Angles wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - a, 2 * np.pi)


@kernel
def compose_pose(ax, ay, ath, bx, by, bth):
    """``compose`` of one pose a = (ax, ay, ath) and one b, for kernels: the pose (x, y, yaw) of a * b."""
    c, s = np.cos(ath), np.sin(ath)
    return ax + c * bx - s * by, ay + s * bx + c * by, wrap_angle(ath + bth)


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The pose of frame b (given in frame a) expressed in a's parent frame: a * b (poses [..., 3]: one pose and
    many, as many of each, or any shapes that broadcast)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.size != 3 and b.size != 3 and a.shape != b.shape:
        shape = np.broadcast_shapes(a.shape, b.shape)
        a, b = np.broadcast_to(a, shape), np.broadcast_to(b, shape)
    out = np.empty(a.shape if a.ndim >= b.ndim else b.shape)
    _compose_rows(a.reshape(-1, 3), b.reshape(-1, 3), out.reshape(-1, 3))
    return out


@kernel
def _compose_rows(a, b, out):
    """Each row of ``out`` [n, 3] the pose of a row of ``b`` in a row of ``a`` (a one-row ``a`` or ``b`` serves
    every row)."""
    for i in range(len(out)):
        j, k = min(i, len(a) - 1), min(i, len(b) - 1)
        out[i, 0], out[i, 1], out[i, 2] = compose_pose(a[j, 0], a[j, 1], a[j, 2], b[k, 0], b[k, 1], b[k, 2])


def inverse(a: np.ndarray) -> np.ndarray:
    """The pose of a's parent frame in frame a: a^-1 (one pose)."""
    c, s = np.cos(a[2]), np.sin(a[2])
    return np.array([-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]])


def rotation(pose, dim: int = 2) -> np.ndarray:
    """The rotation matrix of a pose: [2, 2] of a 2D pose's yaw, [3, 3] with ``dim`` 3 (about z: heights stay), or
    the [3, 3] block of a 4x4 transform."""
    if np.shape(pose) == (4, 4):
        return np.asarray(pose)[:3, :3]
    c, s = np.cos(pose[2]), np.sin(pose[2])
    if dim == 2:
        return np.array([[c, -s], [s, c]])
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def optical_rotation(yaw: float, pitch: float) -> np.ndarray:
    """The rotation [3, 3] whose columns are a camera's optical axes (x right, y down, z forward) in its parent's
    frame, for a camera looking along ``yaw`` and down by ``pitch`` (the scenario's keys)."""
    forward = np.array([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), -np.sin(pitch)])
    right = np.array([np.sin(yaw), -np.cos(yaw), 0.0])
    return np.column_stack([right, np.cross(forward, right), forward])


def rotate(pose, vectors: np.ndarray) -> np.ndarray:
    """Vectors [n, 2] (velocities, offsets) given in the frame of the 2D ``pose``, in its parent frame."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return vectors @ np.array([[c, s], [-s, c]])


def unrotate(pose, vectors: np.ndarray) -> np.ndarray:
    """Vectors [n, 2] given in the parent frame of the 2D ``pose``, in the pose's frame (``rotate`` undone)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return vectors @ np.array([[c, -s], [s, c]])


def transform_points(pose, points: np.ndarray) -> np.ndarray:
    """Points given in the frame ``pose`` describes, expressed in that pose's parent frame: [n, 2] for a 2D pose,
    [n, 3] for a 4x4 transform."""
    if np.shape(pose) == (4, 4):
        return points @ rotation(pose).T + pose[:3, 3]
    return rotate(pose, points) + pose[:2]


def to_frame(pose, points: np.ndarray) -> np.ndarray:
    """Points given in the parent frame of ``pose``, expressed in the pose's frame (``transform_points`` undone):
    [n, 2] for a 2D pose, [n, 3] for a 4x4 transform."""
    if np.shape(pose) == (4, 4):
        return (points - pose[:3, 3]) @ rotation(pose)
    return unrotate(pose, points - pose[:2])


def rotate_covariances(rot: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """Covariances [..., d, d] given in a frame turned by the rotation ``rot`` [d, d], in the parent frame
    (R C R^T); ``rot.T`` turns them back."""
    return rot @ covariance @ rot.T
