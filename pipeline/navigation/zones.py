"""Security zones around tracked persons (seed 001 Sec. 7, Fig. 10-11), to be avoided as virtual obstacles.

Seed 001 puts around each passer-by a zone made of a disc of radius ``r`` and, ahead of the person along the
travel direction inferred by the tracker, a circular sector of radius ``R`` and opening ``omega``; its runs use
r = 0.5 m, R = 1.5 m, omega = 30 deg (Fig. 11's caption). A planner that keeps out of the sector crosses the
person's path behind rather than in front of them. The paper gives the shape only as a figure, so two readings are
made here and said where they matter:

* ``omega`` is the sector's full opening (its central angle, +-omega/2 about the heading), the usual meaning of a
  sector's angle. With the seed's values the sector is then 2 R sin(omega/2) = 0.78 m wide at its tip: a corridor
  about one walker wide (shoulder width ~0.5 m) along the path the person sweeps in the next second at 1.3 m/s.
  Read as a half angle (+-30 deg) it would be 1.5 m wide, three walkers, wider than the disc itself, and would
  block more than the person's path.
* A standing person (tracked speed below ``standing_speed``) has no travel direction and gets the disc alone. The
  default 0.25 m/s lies above what the project's tracker reports for a person standing still (NNT with its
  defaults, laser detections at 25 Hz scattered by 0.1 m and stated with the detector's 0.1 m^2: 99th percentile
  0.18 m/s, maximum 0.23 m/s over two minutes) and well below the slowest walker the crowd draws (0.6 m/s,
  scenarios/format.py ``speed_min``).
"""

from __future__ import annotations

import numpy as np

from pipeline.types import TrackedPersons


class SecurityZones:
    """The zones of seed 001 (``r``, ``R`` in m, ``omega`` the sector's full opening in rad, ``standing_speed`` in
    m/s), tested in batches: points against every zone, rays against every zone."""

    def __init__(self, r: float = 0.5, R: float = 1.5, omega: float = np.radians(30.0),
                 standing_speed: float = 0.25):
        if not (r > 0 and R > 0 and np.isfinite(r) and np.isfinite(R)):
            raise ValueError(f"security zone: r and R must be finite and > 0 m, got r={r}, R={R}")
        # the ray test treats the sector as a convex set: at most a half-disc
        if not 0 < omega <= np.pi:
            raise ValueError(f"security zone: omega must lie in (0, pi] rad, got {omega}")
        if not standing_speed >= 0:
            raise ValueError(f"security zone: standing_speed must be >= 0 m/s, got {standing_speed}")
        self.r, self.R, self.omega, self.standing_speed = float(r), float(R), float(omega), float(standing_speed)

    def of(self, tracks: TrackedPersons) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each track's zone: position [k, 2], heading [k] (rad, from the tracked velocity), walking [k]."""
        v = tracks.velocity
        speed = np.hypot(v[:, 0], v[:, 1])
        return tracks.position, np.arctan2(v[:, 1], v[:, 0]), speed >= self.standing_speed

    def contains(self, points: np.ndarray, tracks: TrackedPersons) -> np.ndarray:
        """Whether each point [m, 2] (in the tracks' frame) lies in some track's zone: bool [m]."""
        return self.inside_each(points, *self.of(tracks)).any(axis=1)

    def inside_each(self, points: np.ndarray, positions: np.ndarray, headings: np.ndarray,
                    walking: np.ndarray) -> np.ndarray:
        """Whether each point [..., m, 2] lies in each zone given as arrays (see ``of``; [..., k] and [..., k, 2]):
        bool [..., m, k]. Leading axes are batches (one robot against its own world's persons, for many worlds)."""
        rel = np.asarray(points, float)[..., :, None, :] - positions[..., None, :, :]  # [..., m, k, 2]
        d2 = np.einsum("...j,...j->...", rel, rel)
        headings, walking = headings[..., None, :], walking[..., None, :]
        along = rel[..., 0] * np.cos(headings) + rel[..., 1] * np.sin(headings)
        in_sector = walking & (d2 <= self.R ** 2) & (along >= np.cos(self.omega / 2) * np.sqrt(d2))
        return (d2 <= self.r ** 2) | in_sector

    def zone_ranges(self, origin: np.ndarray, angles: np.ndarray, positions: np.ndarray, headings: np.ndarray,
                    walking: np.ndarray) -> np.ndarray:
        """Distance [n] along each ray from ``origin`` at ``angles`` [n] to where it first enters a zone: inf where
        it enters none, 0 where it starts inside one. Zones fed to a planner this way read like a laser scan.

        Each zone is the union of two convex sets, the disc and the sector (the disc of radius R cut by the two
        half-planes of the sector's edges), so a ray enters each where the intervals of its parameter inside every
        constraint overlap. Only the (ray, zone) pairs whose ray meets the zone's bounding circle are solved, all at
        once.
        """
        u = np.stack([np.cos(angles), np.sin(angles)], axis=1)  # [n, 2]
        c = positions - np.asarray(origin, float)[None, :]  # [k, 2], each person relative to the origin
        along = u @ c.T  # [n, k]
        cc = np.einsum("kj,kj->k", c, c)
        reach2 = np.where(walking, max(self.r, self.R), self.r) ** 2
        # within the tangent cone of the bounding circle, or all round when the origin is inside that circle
        ray, zone = np.nonzero((along >= np.sqrt(np.maximum(cc - reach2, 0.0))) | (cc <= reach2))
        b, cc, px, py = -along[ray, zone], cc[zone], -c[zone, 0], -c[zone, 1]  # b = u.p, p = origin - person
        ux, uy = u[ray, 0], u[ray, 1]
        t_disc = _disc_entry(b, cc - self.r ** 2)
        lo, hi = _disc_interval(b, cc - self.R ** 2)
        for edge, sign in ((headings - self.omega / 2, 1.0), (headings + self.omega / 2, -1.0)):
            # inside the sector: the ray point q = p + t u lies counter-clockwise of the right edge and clockwise
            # of the left one: sign * cross(e, q) >= 0, linear in t
            ex, ey = np.cos(edge)[zone], np.sin(edge)[zone]
            g0 = sign * (ex * py - ey * px)
            g1 = sign * (ex * uy - ey * ux)
            with np.errstate(divide="ignore", invalid="ignore"):
                root = -g0 / g1
            lo = np.where(g1 > 0, np.maximum(lo, root), lo)
            hi = np.where(g1 < 0, np.minimum(hi, root), hi)
            hi = np.where((g1 == 0) & (g0 < 0), -np.inf, hi)
        t_sector = np.where(walking[zone] & (lo <= hi) & (hi >= 0), np.maximum(lo, 0.0), np.inf)
        ranges = np.full(len(u), np.inf)
        np.minimum.at(ranges, ray, np.minimum(t_disc, t_sector))
        return ranges


def _disc_interval(b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ray parameters [lo, hi] inside a disc, from b = u.p and c = |p|^2 - radius^2 (p: the ray origin
    relative to the centre); an empty interval (lo = inf, hi = -inf) where the line misses it."""
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0.0))
    hit = disc >= 0
    return np.where(hit, -b - root, np.inf), np.where(hit, -b + root, -np.inf)


def _disc_entry(b: np.ndarray, c: np.ndarray) -> np.ndarray:
    lo, hi = _disc_interval(b, c)
    return np.where(hi >= 0, np.maximum(lo, 0.0), np.inf)
