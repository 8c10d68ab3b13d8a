"""Seed 000's occlusion test for ground truth (Sec. IV-B): "We ignore all correspondences where the groundtruth
track is physically occluded, which is determined by searching for associated laser points within a radius of
0.3 m of the annotated position, shifted towards the sensor origin by 0.2 m to take into account that the laser
sensor only perceives the surface of the person."

The simulation knows better (the beams that hit each person, ``visible``); this test is kept so that seed 000's
definition can be reproduced exactly. It can differ: a person right behind another has the front one's points
within 0.3 m of their shifted position and passes, though no beam reaches them.
"""

from __future__ import annotations

import math

import numpy as np

from pipeline.compiled import kernel

SHIFT, RADIUS = 0.2, 0.3  # m, seed 000 Sec. IV-B
SECTORS = 360  # angular bins about the laser for the points: a person's disc of RADIUS spans a few at most


def seed000_visible(positions: np.ndarray, origin: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Which persons at ``positions`` [n, 2] have a laser point of ``points`` [k, 2] (one laser at ``origin`` [2],
    all in one frame; non-finite points are no points) strictly within RADIUS of their position moved SHIFT
    towards that laser."""
    positions = np.ascontiguousarray(positions, float).reshape(-1, 2)
    points = np.ascontiguousarray(points, float).reshape(-1, 2)
    origin = np.asarray(origin, float)[:2]
    return _visible(positions, float(origin[0]), float(origin[1]), points)


@kernel
def _visible(positions, ox, oy, points):
    """The points binned by their bearing from the laser, then for each person only the bins within the bearing
    a disc of RADIUS round its shifted position spans (all bins when the disc holds the laser)."""
    width = 2 * math.pi / SECTORS
    count = np.zeros(SECTORS + 1, np.int64)
    sector = np.full(len(points), -1, np.int64)
    for k in range(len(points)):
        x, y = points[k, 0], points[k, 1]
        if math.isfinite(x) and math.isfinite(y):
            sector[k] = min(int((math.atan2(y - oy, x - ox) + math.pi) / width), SECTORS - 1)
            count[sector[k] + 1] += 1
    for b in range(SECTORS):  # count[b]:count[b + 1] of ``order`` are sector b's points
        count[b + 1] += count[b]
    order, filled = np.empty(count[SECTORS], np.int64), count[:SECTORS].copy()
    for k in range(len(points)):
        if sector[k] >= 0:
            order[filled[sector[k]]] = k
            filled[sector[k]] += 1
    out = np.zeros(len(positions), np.bool_)
    for i in range(len(positions)):
        tx, ty = ox - positions[i, 0], oy - positions[i, 1]
        norm = max(math.sqrt(tx * tx + ty * ty), 1e-9)
        qx, qy = positions[i, 0] + SHIFT * tx / norm, positions[i, 1] + SHIFT * ty / norm
        rho = math.sqrt((qx - ox) ** 2 + (qy - oy) ** 2)
        if rho <= RADIUS:
            first, last = 0, SECTORS - 1
        else:
            bearing, half = math.atan2(qy - oy, qx - ox) + math.pi, math.asin(RADIUS / rho)
            first, last = int(math.floor((bearing - half) / width)) - 1, int(math.floor((bearing + half) / width)) + 1
            last = min(last, first + SECTORS - 1)
        for b in range(first, last + 1):
            s = b % SECTORS
            for m in range(count[s], count[s + 1]):
                k = order[m]
                if (points[k, 0] - qx) ** 2 + (points[k, 1] - qy) ** 2 < RADIUS * RADIUS:
                    out[i] = True
                    break
            if out[i]:
                break
    return out
