"""Seed 000's occlusion test for ground truth (Sec. IV-B): "We ignore all correspondences where the groundtruth
track is physically occluded, which is determined by searching for associated laser points within a radius of
0.3 m of the annotated position, shifted towards the sensor origin by 0.2 m to take into account that the laser
sensor only perceives the surface of the person."

The simulation knows better (the beams that hit each person, ``visible``); this test is kept so that seed 000's
definition can be reproduced exactly. It can differ: a person right behind another has the front one's points
within 0.3 m of their shifted position and passes, though no beam reaches them.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

SHIFT, RADIUS = 0.2, 0.3  # m, seed 000 Sec. IV-B


def seed000_visible(positions: np.ndarray, origin: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Which persons at ``positions`` [n, 2] have a laser point of ``points`` [k, 2] (one laser at ``origin`` [2],
    all in one frame) within RADIUS of their position moved SHIFT towards that laser."""
    positions = np.asarray(positions, float).reshape(-1, 2)
    points = np.asarray(points, float).reshape(-1, 2)
    points = points[np.isfinite(points).all(axis=1)]
    if not len(points) or not len(positions):
        return np.zeros(len(positions), bool)
    towards = np.asarray(origin, float)[:2] - positions
    shifted = positions + SHIFT * towards / np.maximum(np.linalg.norm(towards, axis=1), 1e-9)[:, None]
    nearest, _ = cKDTree(points).query(shifted, distance_upper_bound=RADIUS)
    return np.isfinite(nearest)
