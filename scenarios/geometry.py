"""Map geometry on arrays: wall segments, point-to-segment vectors, point-in-polygon, line of sight."""

from __future__ import annotations

import numpy as np


def wall_segments(scenario: dict) -> np.ndarray:
    """Every wall and obstacle edge of a scenario's map as segments [m, 2, 2] (a loaded scenario has them as
    ``scenario.map.segments``)."""
    return segments_of(scenario["map"]["walls"], scenario["map"]["obstacles"])


def segments_of(walls: list, obstacles: list) -> np.ndarray:
    """Wall polylines and obstacle polygons as segments [m, 2, 2] (obstacle polygons are closed)."""
    segs = []
    for line in walls:
        p = np.asarray(line, float)
        segs.append(np.stack([p[:-1], p[1:]], axis=1))
    for poly in obstacles:
        p = np.asarray(poly, float)
        segs.append(np.stack([p, np.roll(p, -1, axis=0)], axis=1))
    return np.concatenate(segs) if segs else np.zeros((0, 2, 2))


def closest_on_segments(points: np.ndarray, segs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vectors from the closest point of each segment to each point [n, m, 2], and their lengths [n, m]."""
    a, ab = segs[:, 0], segs[:, 1] - segs[:, 0]
    ap = points[:, None, :] - a[None]
    t = np.clip(np.einsum("nmk,mk->nm", ap, ab) / np.maximum(np.einsum("mk,mk->m", ab, ab), 1e-12), 0.0, 1.0)
    away = ap - t[..., None] * ab[None]
    return away, np.linalg.norm(away, axis=-1)


DENSE_PAIRS = 100_000  # points x segments up to which every pair is tested: below, a grid costs more than it saves


def near_segments(points: np.ndarray, segs: np.ndarray, reach: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (point, segment) whose bounding boxes, the segment's grown by ``reach``, overlap: the only
    pairs that can lie within ``reach`` of each other, in (point, segment) order. Cheap comparisons only, so exact
    work stays sparse; for many points and segments (a building's walls) only the pairs that share a cell of a
    uniform grid are tested, which finds the same pairs."""
    lo = np.minimum(segs[:, 0], segs[:, 1])
    hi = np.maximum(segs[:, 0], segs[:, 1])
    r = np.broadcast_to(np.asarray(reach, float), len(points))
    if len(points) * len(segs) <= DENSE_PAIRS:
        x, y, rp = points[:, 0:1], points[:, 1:2], r[:, None]
        return np.nonzero((x >= lo[:, 0] - rp) & (x <= hi[:, 0] + rp) & (y >= lo[:, 1] - rp) & (y <= hi[:, 1] + rp))
    p, s = _sharing_a_cell(points, r, lo, hi)
    x, y, rp = points[p, 0], points[p, 1], r[p]
    keep = (x >= lo[s, 0] - rp) & (x <= hi[s, 0] + rp) & (y >= lo[s, 1] - rp) & (y <= hi[s, 1] + rp)
    return p[keep], s[keep]


def _sharing_a_cell(points: np.ndarray, reach: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray,
                                                                                                      np.ndarray]:
    """The pairs (point, segment), in that order and each once, whose boxes (the point's grown by its reach) touch a
    common cell of a grid whose cells are twice the largest reach (at least 1 m) wide."""
    size = max(1.0, 2.0 * float(reach.max()))
    grown = reach[:, None] + 1e-9 * (1.0 + np.abs(points))  # (a box touching a cell's edge is found either side)
    origin = np.minimum(lo.min(axis=0), (points - grown).min(axis=0))
    s_lo, s_hi = np.floor((lo - origin) / size).astype(np.int64), np.floor((hi - origin) / size).astype(np.int64)
    p_lo = np.floor((points - grown - origin) / size).astype(np.int64)
    p_hi = np.floor((points + grown - origin) / size).astype(np.int64)
    columns = int(max(s_hi[:, 0].max(), p_hi[:, 0].max())) + 1
    seg, cell = _cells(s_lo, s_hi, columns)
    order = np.argsort(cell, kind="stable")
    seg, cell = seg[order], cell[order]
    point, pcell = _cells(p_lo, p_hi, columns)
    first, last = np.searchsorted(cell, pcell, "left"), np.searchsorted(cell, pcell, "right")
    count = last - first
    p = np.repeat(point, count)
    at = np.repeat(first - np.cumsum(count) + count, count) + np.arange(count.sum())
    key = np.unique(p * len(lo) + seg[at])
    return key // len(lo), key % len(lo)


def _cells(lo: np.ndarray, hi: np.ndarray, columns: int) -> tuple[np.ndarray, np.ndarray]:
    """For boxes spanning grid cells ``lo``..``hi`` [n, 2] (column, row): each (box, cell) it covers, the cell as
    row * columns + column."""
    span = hi - lo + 1
    count = span[:, 0] * span[:, 1]
    box = np.repeat(np.arange(len(lo)), count)
    k = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    column, row = lo[box, 0] + k % span[box, 0], lo[box, 1] + k // span[box, 0]
    return box, row * columns + column


def pair_vectors(points: np.ndarray, segs: np.ndarray, p: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For index pairs (p, s): the vector from segment s's closest point to point p, and its length."""
    a, ab = segs[s, 0], segs[s, 1] - segs[s, 0]
    ap = points[p] - a
    t = np.clip(np.einsum("kd,kd->k", ap, ab) / np.maximum(np.einsum("kd,kd->k", ab, ab), 1e-12), 0.0, 1.0)
    away = ap - t[:, None] * ab
    return away, np.linalg.norm(away, axis=1)


def inside_polygon(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd rule point-in-polygon for points [n, 2]."""
    x, y = points[:, 0:1], points[:, 1:2]
    a, b = poly, np.roll(poly, -1, axis=0)
    crosses = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (crosses & (x < xi)).sum(axis=1) % 2 == 1


def segments_cross(starts: np.ndarray, ends: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """For moves ``starts`` -> ``ends`` [n, 2]: True where the move crosses (or touches) any segment [m, 2, 2]."""
    out = np.zeros(len(starts), bool)
    if len(segs) == 0 or len(starts) == 0:
        return out
    mid = (starts + ends) / 2
    p, s = near_segments(mid, segs, np.linalg.norm(ends - starts, axis=1) / 2 + 1e-9)
    d = ends[p] - starts[p]
    a, e = segs[s, 0], segs[s, 1] - segs[s, 0]

    def cross(u, v):
        return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]

    denom = cross(d, e)
    oa = a - starts[p]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = cross(oa, e) / denom  # along the move
        u = cross(oa, d) / denom  # along the segment
    hit = (np.abs(denom) > 1e-12) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    out[p[hit]] = True
    return out


def line_of_sight(origin: np.ndarray, points: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """For points [n, 2]: True where the straight line from ``origin`` crosses no segment."""
    return ~segments_cross(np.broadcast_to(np.asarray(origin, float), points.shape), points, segs)
