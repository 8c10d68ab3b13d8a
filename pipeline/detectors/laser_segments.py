"""Laser people detection: jump-distance segmentation and a geometric segment classifier (seed 000 Sec. II-A).

A segment is a run of consecutive returns whose neighbours are closer than the jump distance. It is taken for a
person when it has enough points, a person-like width, and bulges towards the sensor (a leg pair or hip is round,
a wall fragment is flat). Everything is computed on arrays over beams and segments at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
        labels, p = self.segments(scan)
        if len(p) == 0:
            return DetectedPersons.empty(scan.stamp, scan.frame, "laser2d")
        starts = np.flatnonzero(np.concatenate([[True], np.diff(labels) > 0]))
        ends = np.concatenate([starts[1:], [len(p)]]) - 1
        count = ends - starts + 1
        first, last = p[starts], p[ends]
        chord = last - first
        width = np.linalg.norm(chord, axis=1)
        # depth of each point behind its segment's chord, towards the sensor counted positive
        normal = np.stack([chord[:, 1], -chord[:, 0]], 1) / np.maximum(width, 1e-9)[:, None]
        normal *= np.where(np.einsum("ij,ij->i", normal, first) > 0, -1.0, 1.0)[:, None]
        bulge_pt = np.einsum("ij,ij->i", p - first[labels], normal[labels])
        # the mean over the interior points (the chord's ends lie on it by construction), not the largest depth:
        # one noisy return must not make a flat wall piece look round
        bulge = np.add.reduceat(bulge_pt, starts) / np.maximum(count - 2, 1)
        centroid = np.add.reduceat(p, starts) / count[:, None]
        keep = ((count >= self.min_points) & (width >= self.min_width) & (width <= self.max_width)
                & (bulge >= self.min_bulge))
        c, w = centroid[keep], width[keep]
        # the visible arc's centroid lies pi/4 r in front of a round body's centre (r = width / 2)
        ray = c / np.maximum(np.linalg.norm(c, axis=1), 1e-9)[:, None]
        centre = c + ray * (np.pi / 8) * w[:, None]
        out = DetectedPersons.on_floor(scan.stamp, scan.frame, "laser2d", self._next_id, centre,
                                       self.position_variance)
        self._next_id += len(centre)
        return out
