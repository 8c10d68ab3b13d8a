"""Map geometry on arrays: wall segments, point-to-segment vectors, point-in-polygon, line of sight."""

from __future__ import annotations

import numpy as np

from .wall_grid import WallGrid


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
    """For moves ``starts`` -> ``ends`` [n, 2]: True where the move crosses (or touches) any segment [m, 2, 2]
    (``WallGrid.crossed``; a crowd keeps its grid, one question here builds one)."""
    return WallGrid.of(segs).crossed(starts, ends)


def line_of_sight(origin: np.ndarray, points: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """For points [n, 2]: True where the straight line from ``origin`` crosses no segment."""
    return ~segments_cross(np.broadcast_to(np.asarray(origin, float), points.shape), points, segs)
