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

One compiled pass per segment computes them all (pipeline/compiled.py: per-call overhead made numpy's version cost
564 us a cycle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.compiled import kernel, segment_sum
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
    label, start = np.empty(len(p), np.int64), np.empty(len(p), np.int64)
    m = _cut(p, idx, float(jump_distance), label, start)
    return Segments(p, idx, label, start[:m], np.diff(np.append(start[:m], len(p))))


@kernel
def _cut(p, beam, jump_distance, label, start):
    """Each return's segment ``label`` and each segment's first return (``start``); the number of segments."""
    m = 1
    label[0], start[0] = 0, 0
    for i in range(1, len(p)):
        if _distance(p, i, i - 1) > jump_distance or beam[i] - beam[i - 1] > 1:
            start[m] = i
            m += 1
        label[i] = m - 1
    return m


def segment_features(seg: Segments, range_max: float) -> np.ndarray:
    """The 13 features (module docstring, ``FEATURE_NAMES`` order) of every segment: [m, 13] float64."""
    out = np.empty((len(seg.start), len(FEATURE_NAMES)))
    _features(np.ascontiguousarray(seg.points, np.float64), seg.start, seg.count, float(range_max), out)
    return out


@kernel
def _distance(p, i, j):
    """|p_i - p_j|."""
    dx, dy = p[i, 0] - p[j, 0], p[i, 1] - p[j, 1]
    return math.sqrt(dx * dx + dy * dy)


@kernel
def _median(values, lo, n, scratch):
    """The median of ``values[lo:lo + n]`` (the mean of the two middle ones for an even n), sorted in ``scratch`` by
    Shell's method with Ciura's gaps: a few loops, where numba's general sort takes seconds to compile."""
    scratch[:n] = values[lo:lo + n]
    for gap in (701, 301, 132, 57, 23, 10, 4, 1):
        for i in range(gap, n):
            v, j = scratch[i], i
            while j >= gap and scratch[j - gap] > v:
                scratch[j] = scratch[j - gap]
                j -= gap
            scratch[j] = v
    return (scratch[(n - 1) // 2] + scratch[n // 2]) / 2


@kernel
def _features(p, start, count, range_max, out):
    """``segment_features`` into ``out`` [m, 13]. The sums over a segment's points are numpy's pairwise sums
    (``segment_sum``), as the classifiers' training features were computed; the boundary's and the inner points'
    are running sums (as ``np.bincount`` gave them)."""
    x, y = p[:, 0].copy(), p[:, 1].copy()
    terms = np.empty((8, len(p)))  # per point: u^2, v^2, u v, u z, v z, z, |x - median|, circle residual^2
    xs, ys = np.empty(len(p)), np.empty(len(p))  # a segment's coordinates, sorted for the median
    for s in range(len(start)):
        a, n = start[s], count[s]
        e, nf = a + n - 1, float(n)
        mx, my = segment_sum(x, a, n) / nf, segment_sum(y, a, n) / nf
        # centred second and third moments: the spread, the regression line and the circle fit
        for i in range(a, a + n):
            u, v = x[i] - mx, y[i] - my
            z = u * u + v * v
            terms[0, i], terms[1, i], terms[2, i], terms[3, i], terms[4, i], terms[5, i] = u * u, v * v, u * v, u * z, \
                v * z, z
        suu, svv, suv = segment_sum(terms[0], a, n), segment_sum(terms[1], a, n), segment_sum(terms[2], a, n)
        suz, svz, sz = segment_sum(terms[3], a, n), segment_sum(terms[4], a, n), segment_sum(terms[5], a, n)
        medx, medy = _median(x, a, n, xs), _median(y, a, n, ys)
        for i in range(a, a + n):
            dx, dy = x[i] - medx, y[i] - medy
            terms[6, i] = math.sqrt(dx * dx + dy * dy)
        # orthogonal regression line: the residual is the scatter matrix's smaller eigenvalue
        linearity = max((suu + svv) / 2 - math.hypot((suu - svv) / 2, suv), 0.0)
        # algebraic circle fit on centred points: 2 [[suu, suv], [suv, svv]] (ca, cb) = (sum u z, sum v z), z = |u|^2,
        # gives the centre offset (ca, cb) and r^2 = ca^2 + cb^2 + mean z
        det = suu * svv - suv * suv
        if det > 1e-12 * (suu + svv) ** 2 and n >= 3:
            ca, cb = (svv * suz - suv * svz) / (2 * det), (suu * svz - suv * suz) / (2 * det)
            radius = math.sqrt(ca * ca + cb * cb + sz / nf)
            for i in range(a, a + n):
                dx, dy = x[i] - mx - ca, y[i] - my - cb
                r = radius - math.sqrt(dx * dx + dy * dy)
                terms[7, i] = r * r
            circularity = segment_sum(terms[7], a, n)
        else:
            radius, circularity = MAX_RADIUS, linearity
        # boundary: steps between consecutive points
        boundary = 0.0
        for i in range(a + 1, a + n):
            boundary += _distance(p, i, i - 1)
        step_mean = boundary / max(nf - 1.0, 1.0)
        spread = 0.0
        for i in range(a + 1, a + n):
            d = _distance(p, i, i - 1) - step_mean
            spread += d * d
        # inner points x_j: triangle curvature 4 A / (d_a d_b d_c), A = |cross| / 2, and turning angle
        curvature = angle = 0.0
        for j in range(a + 1, e):
            e0x, e0y = x[j] - x[j - 1], y[j] - y[j - 1]
            e1x, e1y = x[j + 1] - x[j], y[j + 1] - y[j]
            cross = e0x * e1y - e0y * e1x
            prod = _distance(p, j, j - 1) * _distance(p, j + 1, j) * _distance(p, j + 1, j - 1)
            if prod > 0:
                curvature += 2 * abs(cross) / prod
            angle += math.atan2(abs(cross), e0x * e1x + e0y * e1y)
        inner = max(nf - 2.0, 1.0)
        row = out[s]
        row[0], row[1], row[2] = nf, math.sqrt((suu + svv) / max(nf - 1.0, 1.0)), segment_sum(terms[6], a, n) / nf
        row[3] = range_max if s == 0 else _distance(p, a, a - 1)
        row[4] = range_max if s == len(start) - 1 else _distance(p, e + 1, e)
        row[5], row[6], row[7], row[8] = _distance(p, e, a), linearity, circularity, min(radius, MAX_RADIUS)
        row[9], row[11], row[12] = boundary, curvature / inner, angle / inner
        row[10] = math.sqrt(spread / max(nf - 2.0, 1.0)) if n >= 3 else 0.0
