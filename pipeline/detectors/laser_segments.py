"""Laser people detection: jump-distance segmentation and a geometric segment classifier (seed 000 Sec. II-A).

A segment is a run of consecutive returns whose neighbours are closer than the jump distance. It is taken for a
person when it has enough points, a person-like width, and bulges towards the sensor (a leg pair or hip is round,
a wall fragment is flat). The segments are measured in one compiled pass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.compiled import kernel, segment_sum
from pipeline.params import param
from pipeline.types import DetectedPersons, LaserScan

from .segment_features import jump_segments

JUMP_DISTANCE = dict(default=0.4, doc="m, seed 000 Sec. 4.2: 0.4 m", min=0.0, exclusive_min=True)
MIN_POINTS = dict(default=3, doc="seed 000 Sec. IV-C: far echoes of fewer than 3 points are unreliable", min=1)
POSITION_VARIANCE = dict(default=0.1, doc="m^2, seed 000 Sec. IV-C: fixed R = diag(0.1, 0.1)", min=0.0,
                         exclusive_min=True)


@dataclass(eq=False)
class SegmentDetector:
    """The ``laser_segments`` detector."""

    jump_distance: float = param(**JUMP_DISTANCE)
    min_points: int = param(**MIN_POINTS)
    min_width: float = param(0.1, "m, narrowest segment taken for a person", min=0.0)
    max_width: float = param(0.9, "m, widest segment taken for a person", min=0.0)
    min_bulge: float = param(0.03, "m, least mean depth of the interior points behind the chord (walls are flat)",
                             min=0.0)
    position_variance: float = param(**POSITION_VARIANCE)

    def __post_init__(self):
        self.reset()

    def reset(self) -> None:
        """Detection ids start again from 0."""
        self._next_id = 0

    def segments(self, scan: LaserScan) -> tuple[np.ndarray, np.ndarray]:
        """Per valid return, its segment label; and the valid returns' points [k, 2] (sensor frame)."""
        seg = jump_segments(scan, self.jump_distance)
        return seg.label, seg.points

    def detect(self, scan: LaserScan) -> DetectedPersons:
        seg = jump_segments(scan, self.jump_distance)
        if len(seg.points) == 0:
            return DetectedPersons.empty(scan.stamp, scan.frame, "laser2d")
        centre = _person_centres(np.ascontiguousarray(seg.points), seg.start, seg.count, self.min_points,
                                 self.min_width, self.max_width, self.min_bulge)
        out = DetectedPersons.on_floor(scan.stamp, scan.frame, "laser2d", self._next_id, centre,
                                       self.position_variance)
        self._next_id += len(centre)
        return out


@kernel
def _person_centres(p, start, count, min_points, min_width, max_width, min_bulge):
    """The body centres [k, 2] of the segments (``count`` points of ``p`` from ``start``) taken for persons.

    A segment's bulge is the mean depth of its interior points behind its chord, towards the sensor counted positive:
    the mean, not the largest depth, so that one noisy return does not make a flat wall piece look round. The
    visible arc's centroid lies pi/4 r in front of a round body's centre (r = width / 2). The sums are numpy's
    (``segment_sum``), in the order ``np.add.reduceat`` adds."""
    centre, depth = np.empty((len(start), 2)), np.empty(len(p))
    x, y = p[:, 0].copy(), p[:, 1].copy()
    kept = 0
    for s in range(len(start)):
        a, n = start[s], count[s]
        fx, fy, cx, cy = p[a, 0], p[a, 1], p[a + n - 1, 0] - p[a, 0], p[a + n - 1, 1] - p[a, 1]
        width = math.sqrt(cx * cx + cy * cy)
        nx, ny = cy / max(width, 1e-9), -cx / max(width, 1e-9)
        if nx * fx + ny * fy > 0:  # the normal towards the sensor
            nx, ny = -nx, -ny
        for i in range(a, a + n):
            depth[i] = (p[i, 0] - fx) * nx + (p[i, 1] - fy) * ny
        bulge = segment_sum(depth, a, n) / max(n - 2, 1)
        if not (n >= min_points and width >= min_width and width <= max_width and bulge >= min_bulge):
            continue
        mx, my = segment_sum(x, a, n) / n, segment_sum(y, a, n) / n
        norm = max(math.sqrt(mx * mx + my * my), 1e-9)
        centre[kept, 0] = mx + mx / norm * (np.pi / 8) * width
        centre[kept, 1] = my + my / norm * (np.pi / 8) * width
        kept += 1
    return centre[:kept]
