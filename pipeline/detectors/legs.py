"""Leg detection in a scan taken below the knees (seed 001 Sec. 4.1, after Xavier et al. 2005, "Fast line, arc/circle
and leg detection from laser scan data in a player driver").

Three steps, as seed 001 gives them: blob segmentation (consecutive returns closer than ``jump_distance``), blob
filtering by Xavier et al.'s geometric properties, and leg formation (each leg paired with the nearest other leg
within ``pair_distance``; the person at the pair's centre). The properties, per blob:

- the number of returns;
- the width, the distance between its first and last returns (the chord, the "mid point distance" of seed 001's
  list);
- the inscribed angles: at each interior return P of a blob with ends A and B, the angle APB. On a circular arc
  every inscribed angle is the same (half the arc not seen, 180 - arc seen / 2 degrees), so a leg has a mean angle
  between a half-circle's 90 degrees and a flat arc's and a small spread; a wall (180 degrees) or a corner (a spread
  of angles) does not;
- sharp structure: a blob whose smallest inscribed angle is sharper than ``sharp_angle_deg`` (a corner or a spike
  pointing at the sensor).

Seed 001 gives none of the thresholds (it refers to Xavier et al.); ours are this testbed's legs' (capsules of radius
0.06 m scaled 0.65-1.05, ``sensors/body.py``: 8-13 cm wide, up to 0.44 m apart in a stride at 0.38 m), chosen by F1 at
0.3 m over walkers in seed 001's room on training seeds (``crowdsim experiment seed001``'s notes give the figures).
Two legs that touch, as a person standing still holds them, make one blob wider than a leg: no person.
``raw_blobs`` gives the raw-blob observations of seed 001's likelihood (Sec. 5.2.4): every blob whose half-width lies in
[``blob_min_radius``, ``blob_max_radius``], which removes thin table legs and walls alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.params import ordered, param
from pipeline.types import DetectedPersons, LaserScan

from .segment_features import Segments, jump_segments


@dataclass(eq=False)
class LegDetector:
    """The ``laser_legs`` detector: persons from pairs of legs (and from single legs with ``single_legs``). Seed 001
    Sec. 4.1 gives the steps and Xavier et al. 2005's properties but no threshold: ours are chosen on this testbed's
    legs (the module docstring says how)."""

    jump_distance: float = param(0.08, "m, consecutive returns farther apart start a new blob", min=0.0,
                                 exclusive_min=True)
    min_points: int = param(3, "returns of a leg (an inscribed angle needs an interior one)", min=3)
    min_width: float = param(0.05, "m, narrowest leg (first to last return)", min=0.0, exclusive_min=True)
    max_width: float = param(0.15, "m, widest leg", min=0.0, exclusive_min=True)
    min_angle_deg: float = param(90.0, "deg, least mean inscribed angle (a half circle's)", min=0.0, max=180.0)
    max_angle_deg: float = param(160.0, "deg, largest mean inscribed angle (flatter is a wall)", min=0.0, max=180.0)
    max_angle_sd_deg: float = param(30.0, "deg, largest spread of the inscribed angles (a circle's: 0)", min=0.0)
    sharp_angle_deg: float = param(60.0, "deg, a blob with a sharper inscribed angle is a sharp structure, no leg",
                                   min=0.0, max=180.0)
    pair_distance: float = param(0.5, "m, farthest two legs of one person", min=0.0)
    single_legs: bool = param(True, "a leg without a partner is a person too (the other hidden behind it)")
    blobs: bool = param(False, "also give the raw blobs: the named batches `legs` and `blobs` (seed 001's l_b, which "
                               "the rjmcmc tracker's likelihood weighs)")
    blob_min_radius: float = param(0.03, "m, least half-width of a raw blob (thinner: a table leg)", min=0.0)
    blob_max_radius: float = param(0.3, "m, largest half-width of a raw blob (wider: a wall)", min=0.0)
    position_variance: float = param(0.05, "m^2, of each person's position", min=0.0, exclusive_min=True)

    CHECKS = (ordered("min_width", "max_width"), ordered("min_angle_deg", "max_angle_deg"))

    def __post_init__(self):
        self.reset()

    def reset(self) -> None:
        """Detection ids start again from 0."""
        self._next_id = 0

    def legs(self, scan: LaserScan) -> np.ndarray:
        """The centres [k, 2] (sensor frame) of the blobs that pass the leg filters."""
        return self._legs(jump_segments(scan, self.jump_distance))

    def raw_blobs(self, scan: LaserScan) -> DetectedPersons:
        """Seed 001's raw-blob observations: the centroids of the blobs of any shape with ``min_points`` returns or
        more whose half-width is within the radius band (no person is formed: a person may give one blob or two).
        Fewer returns are mostly pieces of a wall seen at a grazing angle, whose returns are farther apart than
        ``jump_distance``."""
        return self._blobs(scan, jump_segments(scan, self.jump_distance))

    def detect(self, scan: LaserScan) -> DetectedPersons | dict[str, DetectedPersons]:
        """The persons; with ``blobs``, the named batches {"legs": the persons, "blobs": the raw blobs}, from one
        segmentation."""
        seg = jump_segments(scan, self.jump_distance)
        people = self._persons(scan, pair_legs(self._legs(seg), self.pair_distance, self.single_legs), "laser2d")
        return {"legs": people, "blobs": self._blobs(scan, seg)} if self.blobs else people

    def _legs(self, seg: Segments) -> np.ndarray:
        if not len(seg.start):
            return np.zeros((0, 2))
        width = _widths(seg)
        mean, sd, least = inscribed_angles(seg)
        low, high, spread, sharp = np.radians([self.min_angle_deg, self.max_angle_deg, self.max_angle_sd_deg,
                                               self.sharp_angle_deg])
        keep = ((seg.count >= self.min_points) & (width >= self.min_width) & (width <= self.max_width)
                & (mean >= low) & (mean <= high) & (sd <= spread) & (least >= sharp))
        return arc_centres(seg.centroid[keep], width[keep])

    def _blobs(self, scan: LaserScan, seg: Segments) -> DetectedPersons:
        if not len(seg.start):
            return self._persons(scan, np.zeros((0, 2)), "laser_blobs")
        radius = _widths(seg) / 2
        keep = (seg.count >= self.min_points) & (radius >= self.blob_min_radius) & (radius <= self.blob_max_radius)
        return self._persons(scan, seg.centroid[keep], "laser_blobs")

    def _persons(self, scan: LaserScan, xy: np.ndarray, modality: str) -> DetectedPersons:
        out = DetectedPersons.on_floor(scan.stamp, scan.frame, modality, self._next_id, xy, self.position_variance)
        self._next_id += len(xy)
        return out


def _widths(seg: Segments) -> np.ndarray:
    """Per blob the distance from its first return to its last."""
    return np.linalg.norm(seg.points[seg.start + seg.count - 1] - seg.points[seg.start], axis=1)


def inscribed_angles(seg: Segments) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per blob the mean, the standard deviation and the smallest of the inscribed angles (rad) at its interior
    returns; blobs of fewer than three returns get nan, nan and pi."""
    m = len(seg.start)
    label, p = seg.label, seg.points
    interior = np.ones(len(p), bool)
    interior[seg.start] = interior[seg.start + seg.count - 1] = False
    k = np.flatnonzero(interior)
    a = p[seg.start[label[k]]] - p[k]
    b = p[seg.start[label[k]] + seg.count[label[k]] - 1] - p[k]
    cos = np.einsum("ij,ij->i", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-12)
    angle = np.arccos(np.clip(cos, -1.0, 1.0))
    n = np.bincount(label[k], minlength=m)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.bincount(label[k], angle, minlength=m) / n
        sd = np.sqrt(np.maximum(np.bincount(label[k], angle * angle, minlength=m) / n - mean * mean, 0.0))
    least = np.full(m, np.pi)
    np.minimum.at(least, label[k], angle)
    return mean, sd, least


def arc_centres(centroid: np.ndarray, width: np.ndarray) -> np.ndarray:
    """The centre of a round object from the centroid of its visible arc: the arc's centroid lies pi/4 r in front of
    the centre (r = width / 2), towards the sensor at the origin."""
    ray = centroid / np.maximum(np.linalg.norm(centroid, axis=1), 1e-9)[:, None]
    return centroid + ray * (np.pi / 8) * width[:, None]


def pair_legs(legs: np.ndarray, pair_distance: float, single_legs: bool) -> np.ndarray:
    """Persons [k, 2] from leg centres: the closest two legs within ``pair_distance`` first, each leg in one pair at
    most, a person at each pair's midpoint; a leg left alone is a person with ``single_legs`` (its partner hidden
    behind it)."""
    n = len(legs)
    if n < 2:
        return legs.copy() if single_legs else np.zeros((0, 2))
    i, j = np.triu_indices(n, 1)
    d = np.linalg.norm(legs[i] - legs[j], axis=1)
    order = np.argsort(d, kind="stable")
    used = np.zeros(n, bool)
    people = []
    for a, b, dist in zip(i[order].tolist(), j[order].tolist(), d[order].tolist()):
        if dist > pair_distance:
            break
        if not used[a] and not used[b]:
            used[a] = used[b] = True
            people.append((legs[a] + legs[b]) / 2)
    if single_legs:
        people.extend(legs[~used])
    return np.array(people).reshape(-1, 2)
