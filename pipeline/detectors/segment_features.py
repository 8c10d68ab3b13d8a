"""Jump-distance segmentation of a 2D scan and the geometric features of its segments, for all segments at once.

The features are those of K. O. Arras, O. Martinez Mozos and W. Burgard, "Using boosted features for the detection
of people in 2D range data", ICRA 2007, which seed 000's segment classifiers compute ("Towards a robust people
tracking framework" Sec. II-A, "Taking a closer look" Sec. III-A: "a set of geometric 2D features on each segment",
citing that paper). Of the paper's 14 features the last, mean speed, needs range rates a single scan has not; the
13 others follow, in this order (the columns of ``segment_features``). A segment has n points x_1..x_n (sensor
frame, in beam order), mean x_bar:

 1. ``n_points``: n.
 2. ``std``: standard deviation, sigma = sqrt(1 / (n - 1) sum_j |x_j - x_bar|^2) (0 for n = 1).
 3. ``median_deviation``: mean average deviation from the median, 1 / n sum_j |x_j - x_med|, x_med the
    coordinate-wise median (a robust compactness measure).
 4. ``jump_prev``: jump distance from the preceding segment, |x_1 - last point of the segment before| (the
    laser's range_max for the scan's first segment: nothing nearer was seen).
 5. ``jump_next``: jump distance to the succeeding segment, |x_n - first point of the segment after| (range_max
    for the last).
 6. ``width``: |x_n - x_1|.
 7. ``linearity``: the residual sum of squares of the line fitted by orthogonal least squares, sum_j (x_j cos a +
    y_j sin a - r)^2 at the best (a, r): the smaller eigenvalue of the segment's scatter matrix (0 on a line).
 8. ``circularity``: sum_j (r_c - |x_j - x_c|)^2 for the circle (x_c, r_c) fitted by algebraic least squares (the
    paper's linear system: minimise sum_j (|x_j|^2 + a x_j + b y_j + c)^2). Exactly collinear points (and n < 3)
    have no circle: the line's residual is given, the limit of ever larger circles.
 9. ``radius``: r_c, at most ``MAX_RADIUS`` (which collinear points get).
10. ``boundary_length``: l = sum_{j>1} |x_j - x_{j-1}|.
11. ``boundary_regularity``: the standard deviation of those n - 1 distances (sample, 0 below 3 points).
12. ``mean_curvature``: the mean over the inner points of the discrete curvature k_j = 4 A_j / (d_a d_b d_c) of
    the triangle x_{j-1} x_j x_{j+1} (area A_j, sides d): the inverse of its circumradius (0 below 3 points).
13. ``mean_angular_difference``: the mean over the inner points of the angle beta_j in [0, pi] between the vectors
    x_{j-1} -> x_j and x_j -> x_{j+1} (0 on a line; 0 below 3 points).

Everything is computed on arrays over all returns of the scan, reduced per segment with ``np.add.reduceat``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.types import LaserScan

FEATURE_NAMES = ("n_points", "std", "median_deviation", "jump_prev", "jump_next", "width", "linearity",
                 "circularity", "radius", "boundary_length", "boundary_regularity", "mean_curvature",
                 "mean_angular_difference")
MAX_RADIUS = 100.0  # m: the radius given to collinear points (no circle) and the largest fitted one reported


@dataclass(frozen=True)
class Segments:
    """A scan's valid returns cut into segments: ``points`` [k, 2] (sensor frame, beam order), their ``beam``
    indices [k] and segment ``label`` [k] (0..m-1, ascending); per segment its first return ``start`` [m] and
    ``count`` [m]."""

    points: np.ndarray
    beam: np.ndarray
    label: np.ndarray
    start: np.ndarray
    count: np.ndarray

    @property
    def centroid(self) -> np.ndarray:
        """The mean of each segment's points [m, 2]."""
        if not len(self.start):
            return np.zeros((0, 2))
        return np.add.reduceat(self.points, self.start, axis=0) / self.count[:, None]


def jump_segments(scan: LaserScan, jump_distance: float) -> Segments:
    """Jump-distance segmentation (seed 000's ROS book chapter Sec. 3.2): consecutive returns farther apart than
    ``jump_distance`` start a new segment, and so does a beam that returned nothing."""
    idx = np.flatnonzero(scan.returned)
    p = scan.points()[idx]
    if len(p) == 0:
        empty = np.zeros(0, np.int64)
        return Segments(p, idx, empty, empty, empty)
    gap = np.linalg.norm(np.diff(p, axis=0), axis=1) > jump_distance
    gap |= np.diff(idx) > 1
    label = np.concatenate([[0], np.cumsum(gap)])
    start = np.flatnonzero(np.concatenate([[True], gap]))
    return Segments(p, idx, label, start, np.diff(np.append(start, len(p))))


def _segment_median(values: np.ndarray, seg: Segments) -> np.ndarray:
    """Per segment the median of ``values`` [k] (the mean of the two middle ones for an even count)."""
    order = np.lexsort((values, seg.label))
    s = values[order]
    return (s[seg.start + (seg.count - 1) // 2] + s[seg.start + seg.count // 2]) / 2


def segment_features(seg: Segments, range_max: float) -> np.ndarray:
    """The 13 features (module docstring, ``FEATURE_NAMES`` order) of every segment: [m, 13] float64."""
    m = len(seg.start)
    if m == 0:
        return np.zeros((0, len(FEATURE_NAMES)))
    p, lab, start, n = seg.points, seg.label, seg.start, seg.count
    end = start + n - 1
    nf = n.astype(float)

    def sums(v: np.ndarray) -> np.ndarray:
        return np.add.reduceat(v, start, axis=0)

    mean = sums(p) / nf[:, None]
    u = p - mean[lab]  # centred coordinates
    suu, svv, suv = sums(u[:, 0] ** 2), sums(u[:, 1] ** 2), sums(u[:, 0] * u[:, 1])
    std = np.sqrt((suu + svv) / np.maximum(nf - 1, 1))
    med = np.stack([_segment_median(p[:, 0], seg), _segment_median(p[:, 1], seg)], axis=1)
    median_dev = sums(np.linalg.norm(p - med[lab], axis=1)) / nf

    jump_prev = np.full(m, float(range_max))
    jump_next = np.full(m, float(range_max))
    jump_prev[1:] = jump_next[:-1] = np.linalg.norm(p[start[1:]] - p[end[:-1]], axis=1)
    width = np.linalg.norm(p[end] - p[start], axis=1)

    # orthogonal regression line: the residual is the scatter matrix's smaller eigenvalue
    half_trace = (suu + svv) / 2
    linearity = np.maximum(half_trace - np.hypot((suu - svv) / 2, suv), 0.0)

    # algebraic circle fit on centred points: 2 [[suu, suv], [suv, svv]] (a, b) = (sum u z, sum v z), z = |u|^2
    # gives the centre offset (a, b) and r^2 = a^2 + b^2 + mean z
    z = (u ** 2).sum(axis=1)
    suz, svz = sums(u[:, 0] * z), sums(u[:, 1] * z)
    det = suu * svv - suv ** 2
    circle = (det > 1e-12 * (suu + svv) ** 2) & (n >= 3)
    d = np.where(circle, det, 1.0)
    a = np.where(circle, (svv * suz - suv * svz) / (2 * d), 0.0)
    b = np.where(circle, (suu * svz - suv * suz) / (2 * d), 0.0)
    radius = np.where(circle, np.sqrt(a ** 2 + b ** 2 + sums(z) / nf), MAX_RADIUS)
    residual = radius[lab] - np.linalg.norm(u - np.stack([a, b], axis=1)[lab], axis=1)
    circularity = np.where(circle, sums(residual ** 2), linearity)
    radius = np.minimum(radius, MAX_RADIUS)

    # boundary: steps between consecutive points of the same segment
    step = np.linalg.norm(np.diff(p, axis=0), axis=1)
    inside = lab[1:] == lab[:-1]
    step_sum = np.bincount(lab[1:][inside], step[inside], minlength=m)
    step_mean = step_sum / np.maximum(nf - 1, 1)
    step_sq = np.bincount(lab[1:][inside], (step[inside] - step_mean[lab[1:][inside]]) ** 2, minlength=m)
    regularity = np.where(n >= 3, np.sqrt(step_sq / np.maximum(nf - 2, 1)), 0.0)

    # inner points x_j (neighbours in the same segment): triangle curvature and turning angle
    j = np.flatnonzero(inside[:-1] & inside[1:]) + 1
    da, db = step[j - 1], step[j]
    dc = np.linalg.norm(p[j + 1] - p[j - 1], axis=1)
    e0, e1 = p[j] - p[j - 1], p[j + 1] - p[j]
    cross = e0[:, 0] * e1[:, 1] - e0[:, 1] * e1[:, 0]
    dot = (e0 * e1).sum(axis=1)
    prod = da * db * dc
    curvature = np.divide(2 * np.abs(cross), prod, out=np.zeros_like(prod), where=prod > 0)  # 4 A, A = |cross| / 2
    angle = np.arctan2(np.abs(cross), dot)
    inner = np.maximum(nf - 2, 1)
    mean_curvature = np.bincount(lab[j], curvature, minlength=m) / inner
    mean_angle = np.bincount(lab[j], angle, minlength=m) / inner

    return np.stack([nf, std, median_dev, jump_prev, jump_next, width, linearity, circularity, radius, step_sum,
                     regularity, mean_curvature, mean_angle], axis=1)
