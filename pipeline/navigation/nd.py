"""Nearness Diagram navigation (ND+, Minguez & Montano, IEEE T-RA 20(1), 2004) for a differential-drive disc robot.

Why ND: seed 001 Sec. 7 drives its robot with "the classical Nearness Diagram Navigation" over the laser scan and the
passers-by's security zones; ND is reactive, needs no map, and copes with dense, cluttered surroundings by choosing
among a few situations instead of summing forces.

One call (``NearnessDiagram.solve``), the obstacles and the goal in the robot frame:

1. sectors -- the plane around the robot is cut into ``sectors`` angular sectors; each keeps its nearest obstacle
   point (distance ``d``, infinite where empty).
2. gaps -- a discontinuity lies between neighbouring sectors whose nearest obstacles differ by more than the robot's
   diameter (the robot fits between them) or where one of the two is empty. Its deeper side starts a *region* (a
   valley of the nearness diagram) that runs to the next discontinuity.
3. free walking area -- the goal itself when it is in sight and reachable, else the rising discontinuity nearest
   to the goal's sector whose gap the robot can reach (the navigability test below).
4. situation and motion law -- from four binary criteria (safety: obstacles within the security distance ``ds`` of
   the robot's edge, ahead of its axle (step 5: the robot never drives backwards); their distribution: on one or both sides of the chosen direction; goal within the free area;
   free area wide or narrow):

   * HSGR (high safety, goal in region): head for the goal.
   * HSWR (high safety, wide region): pass the gap's edge at the robot's radius plus ds.
   * HSNR (high safety, narrow region): head for the region's middle.
   * LS1 (low safety, dangerous obstacles on one side): turn from the high-safety direction away from the nearest
     one, the more the nearer (its distance over ds weights the two). With the goal in the region this is the
     goal-directed low-safety case of the authors' code (their "LSG").
   * LS2 (dangerous obstacles on both sides): shift the high-safety direction towards the side of the farther one,
     by the imbalance of the two distances, to steer between them.

5. differential drive -- the direction theta (clipped to +-pi/2) becomes v = v_max c (1 - |theta|/(pi/2)) and
   omega = omega_max theta/(pi/2), c = the nearest dangerous obstacle's distance over ds (1 when there is none): the
   linear law of the authors' code (its holonomic branch) with its speed reduction near obstacles
   (``control_velocidad``); beyond +-pi/2 the robot turns in place.

The concrete laws (the wide-region offset, LS1's interpolation, LS2's shift, the navigability test) follow Minguez's
own implementation, distributed as Player's ``nd`` driver (playerproject/player, server/drivers/position/nd/nd.cc,
2003); the code here is written anew, vectorized over sectors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.frames import wrap_angle

HALF_PI = np.pi / 2


@dataclass
class NDResult:
    """A command with what produced it: the situation and the motion direction (rad, robot frame, before the
    +-pi/2 clip of the drive), for inspection and tests."""

    v: float
    omega: float
    direction: float
    situation: str  # HSGR, HSWR, HSNR, LS1, LS2, or "blocked" (no reachable region: stop)


def nearest_per_sector(points: np.ndarray, sectors: int, values: np.ndarray | None = None):
    """The nearest of ``points`` [m, 2] in each of ``sectors`` equal angular sectors about the origin, sector k
    spanning [-pi + k w, -pi + (k+1) w): distances [n] (inf where empty) and the points [n, 2] (NaN where empty);
    with ``values`` [m], also the nearest point's value per sector (NaN where empty)."""
    dist = np.hypot(points[:, 0], points[:, 1])
    sector = sector_of(np.arctan2(points[:, 1], points[:, 0]), sectors)
    d = np.full(sectors, np.inf)
    np.minimum.at(d, sector, dist)
    nearest = np.full((sectors, 2), np.nan)
    hit = dist == d[sector]  # of equally near points in a sector, one is kept
    nearest[sector[hit]] = points[hit]
    if values is None:
        return d, nearest
    value = np.full(sectors, np.nan)
    value[sector[hit]] = np.asarray(values, float)[hit]
    return d, nearest, value


def sector_of(angles, sectors: int):
    return np.floor((np.asarray(angles) + np.pi) * (sectors / (2 * np.pi))).astype(np.int64) % sectors


def drive(speed: float, direction: float, max_angular_speed: float) -> tuple[float, float]:
    """ND's differential-drive law: (v, omega) for a wanted motion ``direction`` (rad, robot frame) at ``speed``;
    beyond +-pi/2 the robot turns in place."""
    theta = float(np.clip(wrap_angle(direction), -HALF_PI, HALF_PI))
    return speed * (1.0 - abs(theta) / HALF_PI), max_angular_speed * theta / HALF_PI


class NearnessDiagram:
    """ND for a disc robot of ``radius`` (m) with speed limits ``max_speed`` (m/s) and ``max_angular_speed``
    (rad/s).

    ``security_distance`` ds = 0.5 m: the default ``avoid_dist`` of Player's nd driver (the authors' code's
    integration). ``sectors`` = 180 (2 deg each): the authors' ``SECTORES``. A region is wide when it spans more than
    ``wide_fraction`` = 1/4 of the sectors (90 deg), the authors' threshold. A gap is a discontinuity of at least
    the robot's diameter (ND's "the robot fits"; Player's driver sets it to the robot's width).
    """

    def __init__(self, radius: float, max_speed: float, max_angular_speed: float, security_distance: float = 0.5,
                 sectors: int = 180, wide_fraction: float = 0.25):
        if not (radius > 0 and max_speed >= 0 and max_angular_speed >= 0 and security_distance > 0):
            raise ValueError("nd: radius and security_distance must be > 0, the speeds >= 0; got "
                             f"radius={radius}, max_speed={max_speed}, max_angular_speed={max_angular_speed}, "
                             f"security_distance={security_distance}")
        if sectors < 8 or sectors % 4:
            raise ValueError(f"nd: sectors must be a multiple of 4, at least 8; got {sectors}")
        if not 0 < wide_fraction < 1:
            raise ValueError(f"nd: wide_fraction must lie in (0, 1); got {wide_fraction}")
        self.radius, self.max_speed, self.max_angular_speed = float(radius), float(max_speed), float(max_angular_speed)
        self.ds, self.n, self.wide_sectors = float(security_distance), int(sectors), wide_fraction * sectors
        self.gap = 2.0 * self.radius
        self.centres = -np.pi + (np.arange(self.n) + 0.5) * (2 * np.pi / self.n)

    def solve(self, points: np.ndarray, goal: np.ndarray, security: np.ndarray | None = None) -> NDResult:
        """The command towards ``goal`` [2] among obstacle ``points`` [m, 2] (NaN rows ignored), both in the robot
        frame. ``security`` [m]: each point's own security distance in place of ``security_distance`` (for points
        that are no physical obstacle but a margin kept already, a person's security zone say)."""
        n = self.n
        points = np.asarray(points, float).reshape(-1, 2)
        finite = np.isfinite(points).all(axis=1)
        if security is None:
            d, nearest = nearest_per_sector(points[finite], n)
            ds = self.ds
        else:
            d, nearest, ds = nearest_per_sector(points[finite], n, np.asarray(security, float)[finite])
            ds = np.where(np.isnan(ds), self.ds, ds)
        # an obstacle inside the robot's footprint reads as touching it, 1 cm out (the authors' code does the same)
        touching = d < self.radius + 0.01
        d[touching] = self.radius + 0.01
        nearest[touching] = d[touching, None] * np.stack([np.cos(self.centres[touching]),
                                                          np.sin(self.centres[touching])], axis=1)
        angle = np.where(np.isfinite(d), np.arctan2(nearest[:, 1], nearest[:, 0]), self.centres)
        goal_angle, goal_dist = float(np.arctan2(goal[1], goal[0])), float(np.hypot(goal[0], goal[1]))
        sg = int(sector_of(goal_angle, n))
        goal_in_sight = goal_dist <= d[sg]

        empty = np.isinf(d)
        finite = np.where(empty, 0.0, d)
        next_empty = _next(empty)
        jump = (empty != next_empty) | (~empty & ~next_empty & (np.abs(finite - _next(finite)) >= self.gap))
        bounds = np.flatnonzero(jump)  # a discontinuity between sector b and b + 1

        situation_free, theta_par = None, None
        if goal_in_sight and self._reachable(nearest, np.asarray(goal, float)):
            situation_free, theta_par = "HSGR", goal_angle
        elif bounds.size:
            theta_par, wide = self._gap_direction(d, nearest, angle, bounds, sg)
            if theta_par is not None:
                situation_free = "HSWR" if wide else "HSNR"
        if situation_free is None:
            return NDResult(0.0, 0.0, float("nan"), "blocked")

        # the dangerous obstacles: within ds of the robot's edge, on the left or right of the chosen direction
        ratio = (d - self.radius) / ds
        side = wrap_angle(angle - theta_par)
        # ahead of the axle only: this robot drives forwards (v >= 0) and turns on the spot, which sweeps nothing
        # beyond its disc, so what lies behind it cannot be hit by its motion (ND's holonomic robot could back into
        # it); counted all round, people passing behind the robot held it to a crawl in low safety
        danger = (ratio <= 1.0) & (np.cos(angle) > 0)
        left = np.where(danger & (side >= 0), ratio, np.inf)
        right = np.where(danger & (side < 0), ratio, np.inf)
        il, ir = int(left.argmin()), int(right.argmin())
        cl, cr = float(left[il]), float(right[ir])
        if np.isinf(cl) and np.isinf(cr):
            situation, theta = situation_free, theta_par
        elif np.isinf(cl) or np.isinf(cr):
            i, c = (il, cl) if np.isfinite(cl) else (ir, cr)
            away = theta_par + float(wrap_angle(angle[i] + np.pi - theta_par))
            situation, theta = "LS1", theta_par * c + away * (1.0 - c)
        else:
            par = float(np.clip(wrap_angle(theta_par), -HALF_PI, HALF_PI))
            k = (cl - cr) / (cl + cr) if cl + cr > 0 else 0.0
            situation, theta = "LS2", par + k * ((par + HALF_PI) if k < 0 else (HALF_PI - par))
        theta = float(wrap_angle(theta))
        v, omega = drive(self.max_speed * min(cl, cr, 1.0), theta, self.max_angular_speed)
        return NDResult(v, omega, theta, situation)

    def _gap_direction(self, d, nearest, angle, bounds, sg) -> tuple[float | None, bool]:
        """The direction through the reachable gap nearest to the goal's sector and whether its region is wide;
        (None, False) when no gap is reachable."""
        n = self.n
        depth_b, depth_next = d[bounds], d[(bounds + 1) % n]
        ccw = depth_next > depth_b  # the deeper (free) side is the next sector, counter-clockwise
        free = np.where(ccw, bounds + 1, bounds) % n
        obst = np.where(ccw, bounds, bounds + 1) % n
        # the region runs from the free side to the next discontinuity on that side (all round with only one)
        after, before = _next(bounds), np.concatenate((bounds[-1:], bounds[:-1]))
        width = np.where(ccw, (after - bounds) % n, (bounds - before) % n)
        width = np.where(width == 0, n, width)
        start = np.where(ccw, bounds + 1, bounds - width + 1) % n
        off = np.abs(free - sg) % n
        for i in np.argsort(np.minimum(off, n - off), kind="stable"):
            f, o, sign = free[i], obst[i], 1.0 if ccw[i] else -1.0
            if np.isfinite(d[f]):
                sub = (nearest[f] + nearest[o]) / 2
            else:  # beyond the edge, halfway to the free sector's bisector, just past the edge's range
                a = angle[o] + sign * abs(float(wrap_angle(self.centres[f] - angle[o]))) / 2
                sub = (d[o] + self.gap) * np.array([np.cos(a), np.sin(a)])
            if not self._reachable(nearest, sub):
                continue
            if width[i] > self.wide_sectors:
                return float(wrap_angle(angle[o] + sign * np.arctan2(self.radius + self.ds, d[o]))), True
            return float(self.centres[int((start[i] + (width[i] - 1) // 2) % n)]), False
        return None, False

    def _reachable(self, nearest: np.ndarray, sub: np.ndarray) -> bool:
        """ND's navigability test: the straight way to ``sub`` is closed if an obstacle lies within the robot's
        radius of it, or if two obstacles on either side of the way, within a diameter of it, are nearer to each
        other than the robot's diameter (it cannot pass between them)."""
        length = float(np.hypot(sub[0], sub[1]))
        if length == 0:
            return True
        pts = nearest[np.isfinite(nearest[:, 0])]
        ux, uy = sub / length
        x = pts[:, 0] * ux + pts[:, 1] * uy
        y = pts[:, 1] * ux - pts[:, 0] * uy
        near = (x >= 0) & (x < length) & (np.abs(y) <= self.gap)
        if (np.hypot(x[near] - length, y[near]) < self.gap / 2).any():
            return False
        left, right = pts[near & (y > 0)], pts[near & (y <= 0)]
        if not (left.size and right.size):
            return True
        sep = left[:, None, :] - right[None, :, :]
        return bool(np.einsum("ijk,ijk->ij", sep, sep).min() >= self.gap ** 2)


def _next(x: np.ndarray) -> np.ndarray:
    """Each element's successor, the last's being the first (np.roll(x, -1), at a fraction of its cost)."""
    return np.concatenate((x[1:], x[:1]))
