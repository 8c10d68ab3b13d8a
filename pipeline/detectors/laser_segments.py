"""Laser people detection: jump-distance segmentation and a geometric segment classifier (seed 000 Sec. II-A).

A segment is a run of consecutive returns whose neighbours are closer than the jump distance. It is taken for a
person when it has enough points, a person-like width, and bulges towards the sensor (a leg pair or hip is round,
a wall fragment is flat). Everything is computed on arrays over beams and segments at once.
"""

from __future__ import annotations

import numpy as np

from pipeline.types import DetectedPersons, LaserScan

from .segment_features import jump_segments


class SegmentDetector:
    """The ``laser_segments`` detector. Defaults: seed 000 Sec. 4.2 and IV-C (scenarios/format.py says which)."""

    def __init__(self, jump_distance: float = 0.4, min_points: int = 3, min_width: float = 0.1,
                 max_width: float = 0.9, min_bulge: float = 0.03, position_variance: float = 0.1):
        self.jump_distance, self.min_points, self.position_variance = jump_distance, min_points, position_variance
        self.min_width, self.max_width, self.min_bulge = min_width, max_width, min_bulge
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
