"""The social-force terms (accelerations in m/s^2), each a compiled kernel on arrays, so each can be tested alone.

Agent-agent terms run over neighbour pairs (i, j): one evaluation gives the force j exerts on i and the one i exerts
on j. The scalar forms (``moussaid_pair``, ``seen_weight``) are shared with the environments' worlds
(``crowdsim.envs.world``), so both simulate one force model from one implementation.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from pipeline.compiled import kernel
from scenarios.wall_grid import WallGrid, away_from_wall, near_walls

LEAF_SIZE = 16  # points up to which a k-d tree node is a leaf (cKDTree's default)
NEGLIGIBLE = 0.005  # m/s^2: an interaction weaker than this (0.1% of Moussaid's A) is not computed
EVERY_PAIR = 200  # persons up to which every pair is tested directly, in their own order (see pair_order)
NO_PAIRS = np.zeros((0, 2), np.int64)  # the pairs argument of the Moussaid force, which needs none
NO_ORDER = np.zeros(0, np.int64)  # the order argument of Helbing & Molnar's, which needs none
NO_FORCE = np.zeros((0, 2))  # no random force
GROUP_VISION_DEG = 90.0  # half-angle of a group member's vision (Moussaid et al. 2010)
GROUP_MARGIN = 0.3  # m beyond the two radii within which group members repel (Moussaid et al. 2010)


@kernel
def seen_weight(hx, hy, fx, fy, cos_half, out_of_view):
    """Helbing & Molnar 1995 anisotropy: weight 1 when the force's source lies within the field of view of a walker
    heading (hx, hy) (a force pointing against the heading, within half the field of view ``cos_half`` = cos(phi)),
    ``out_of_view`` (c) otherwise."""
    if -(hx * fx + hy * fy) >= math.sqrt(fx * fx + fy * fy) * cos_half:
        return 1.0
    return out_of_view


@kernel
def moussaid_reach(strength, gamma):
    """How far (in units of |D|) the Moussaid force can stay above NEGLIGIBLE: A exp(-d / (gamma |D|)) bounds it."""
    return gamma * math.log(strength / NEGLIGIBLE) if strength > NEGLIGIBLE else 0.0


@kernel
def moussaid_pair(dx, dy, dvx, dvy, strength, lam, gamma, n, n_prime, reach):
    """Moussaid, Helbing et al. 2009 (Proc. R. Soc. B 276) between persons i and j, the form PedSim uses, from
    their differences j - i in position (dx, dy) and velocity (dvx, dvy).

    With e the unit vector from i to j and d their distance, the interaction vector D = lam (v_i - v_j) + e
    points along t = D / |D|; B = gamma |D|; theta is the signed angle from t to e. The force decelerates i along t
    and turns it away from j's side:
        f = -A exp(-d / B) [exp(-(n' B theta)^2) t + K exp(-(n B theta)^2) n_left],  K = sign(theta).
    Returns the braking part (bx, by) and the turning part (sx, sy) of the force on i. Seen from j, D and t change
    sign while |D|, B and theta do not, so j feels -(b + s): one evaluation gives both. At theta = 0 (a perfectly
    symmetric head-on meeting) there is no turning term, as in the paper (K = theta / |theta|); the random force
    breaks such ties. A pair whose force cannot reach NEGLIGIBLE (d >= ``reach`` |D|) gives zeros."""
    d, ex, ey, Dx, Dy, nD = _moussaid_geometry(dx, dy, dvx, dvy, lam)
    if not d < reach * nD:
        return 0.0, 0.0, 0.0, 0.0
    return _moussaid_within(d, ex, ey, Dx, Dy, nD, strength, gamma, n, n_prime)


@kernel
def _moussaid_geometry(dx, dy, dvx, dvy, lam):
    """``moussaid_pair``'s distance d, unit vector e, interaction vector D and |D| of the differences j - i."""
    d = max(math.sqrt(dx * dx + dy * dy), 1e-9)
    ex, ey = dx / d, dy / d
    Dx, Dy = ex - lam * dvx, ey - lam * dvy
    return d, ex, ey, Dx, Dy, math.sqrt(Dx * Dx + Dy * Dy)


@kernel
def _moussaid_within(d, ex, ey, Dx, Dy, nD, strength, gamma, n, n_prime):
    """``moussaid_pair`` for a pair within its reach, from its distance d, unit vector e, interaction vector D and
    |D| (for callers that tested the reach themselves)."""
    nD = max(nD, 1e-9)
    tx, ty = Dx / nD, Dy / nD
    theta = math.atan2(tx * ey - ty * ex, tx * ex + ty * ey)
    B = gamma * nD
    base = -strength * math.exp(-d / B)
    along = base * math.exp(-(n_prime * B * theta) ** 2)
    side = base * np.sign(theta) * math.exp(-(n * B * theta) ** 2)
    return along * tx, along * ty, -side * ty, side * tx  # n_left = (-t_y, t_x)


@kernel
def moussaid2009(pos, vel, order, interaction_range, strength, lam, gamma, n, n_prime, walking, direction, fov_deg,
                 out_of_view):
    """``moussaid_pair`` summed per person [n, 2] over every two persons within ``interaction_range``. The turning
    term steers walkers round each other, so persons not ``walking`` (standing people) feel only the braking term,
    else they would circle each other. Each force is weighted by the field of view round the person's walking
    ``direction`` (Helbing & Molnar 1995): people react less to those behind, which is what makes a dense crowd slow
    down (else pushes from behind cancel the braking from the front).

    The pairs are taken as places a < b in ``order`` (a permutation of the persons, ``pair_order``'s): a by a, and
    for each a its b in turn, so each person's forces are added up in the order of their partners there, which fixes
    the sums' last bits. Up to ``EVERY_PAIR`` persons every two are tested; beyond, a grid of cells gives each a its
    partners, whose reach is tested all at once (numba vectorizes it, without branches: 20% off at 5,000) and
    whose forces are sorted into that order, without a list of pairs."""
    total = np.zeros((len(pos), 2))
    reach = moussaid_reach(strength, gamma)
    cos_half = math.cos(math.radians(fov_deg) / 2)
    range2 = interaction_range * interaction_range
    if len(pos) <= EVERY_PAIR:
        for a in range(len(pos)):
            for b in range(a + 1, len(pos)):
                i, j = min(order[a], order[b]), max(order[a], order[b])
                dx, dy = pos[j, 0] - pos[i, 0], pos[j, 1] - pos[i, 1]
                if dx * dx + dy * dy <= range2:
                    bx, by, sx, sy = moussaid_pair(dx, dy, vel[j, 0] - vel[i, 0], vel[j, 1] - vel[i, 1], strength, lam,
                                                   gamma, n, n_prime, reach)
                    _add_moussaid(total, i, j, bx, by, sx, sy, walking, direction, cos_half, out_of_view)
        return total
    start, ranks, cell, columns, rows, x0, y0 = _rank_grid(pos, order, interaction_range)
    # each a's partners after it within range (rank, differences j - i in position and velocity), then moussaid_pair's
    # geometry of each and whether it is within reach, and the forces of those within reach, sorted by rank
    near, diff, seen = np.empty(len(pos), np.int64), np.empty((4, len(pos))), np.empty(len(pos), np.bool_)
    geometry, within_at = np.empty((6, len(pos))), np.empty(len(pos), np.int64)  # moussaid_pair's d, e, D, |D|
    later, parts = np.empty(len(pos), np.int64), np.empty((len(pos), 4))
    margin = interaction_range * (1.0 + 1e-9)  # the cells to scan hold every partner in range, despite rounding
    for a in range(len(pos)):
        p = order[a]
        x, y = pos[p, 0], pos[p, 1]
        found = 0
        for row in range(max(int((y - margin - y0) / cell), 0), min(int((y + margin - y0) / cell), rows - 1) + 1):
            for column in range(max(int((x - margin - x0) / cell), 0),
                                min(int((x + margin - x0) / cell), columns - 1) + 1):
                c = row * columns + column
                for q in range(start[c + 1] - 1, start[c] - 1, -1):  # the cell's ranks, descending: those after a
                    b = ranks[q]
                    if b <= a:
                        break
                    i, j = min(p, order[b]), max(p, order[b])
                    dx, dy = pos[j, 0] - pos[i, 0], pos[j, 1] - pos[i, 1]
                    near[found] = b  # written always, kept (not written over) only when within range: no branch
                    diff[0, found], diff[1, found] = dx, dy
                    diff[2, found], diff[3, found] = vel[j, 0] - vel[i, 0], vel[j, 1] - vel[i, 1]
                    found += dx * dx + dy * dy <= range2
        for k in range(found):  # moussaid_pair's test of reach, its operations on all at once (vectorized)
            d, ex, ey, Dx, Dy, nD = _moussaid_geometry(diff[0, k], diff[1, k], diff[2, k], diff[3, k], lam)
            geometry[0, k], geometry[1, k], geometry[2, k] = d, ex, ey
            geometry[3, k], geometry[4, k], geometry[5, k] = Dx, Dy, nD
            seen[k] = d < reach * nD
        within = 0
        for k in range(found):  # those within reach, listed without a branch
            near[within], within_at[within] = near[k], k
            within += seen[k]
        count = 0
        for w in range(within):
            k = within_at[w]
            bx, by, sx, sy = _moussaid_within(geometry[0, k], geometry[1, k], geometry[2, k], geometry[3, k],
                                              geometry[4, k], geometry[5, k], strength, gamma, n, n_prime)
            if bx == 0.0 and by == 0.0 and sx == 0.0 and sy == 0.0:  # negligible: none kept
                continue
            b, m = near[w], count  # inserted among the partners kept so far, by rank
            while m > 0 and later[m - 1] > b:
                later[m] = later[m - 1]
                parts[m, 0], parts[m, 1], parts[m, 2], parts[m, 3] = (parts[m - 1, 0], parts[m - 1, 1],
                                                                      parts[m - 1, 2], parts[m - 1, 3])
                m -= 1
            later[m] = b
            parts[m, 0], parts[m, 1], parts[m, 2], parts[m, 3] = bx, by, sx, sy
            count += 1
        for k in range(count):
            i, j = min(p, order[later[k]]), max(p, order[later[k]])
            _add_moussaid(total, i, j, parts[k, 0], parts[k, 1], parts[k, 2], parts[k, 3], walking, direction,
                          cos_half, out_of_view)
    return total


@kernel
def _rank_grid(pos, order, reach):
    """Square cells of side ``reach`` over the persons (larger ones where they are spread so far apart that there
    would be more than 4 a person, plus 1024), each listing the ranks in ``order`` of the persons in it, ascending:
    cell c's are ``ranks[start[c]:start[c + 1]]``, cell c = row x columns + column from the corner (x0, y0). A
    person's partners within the reach lie in about 3 x 3 cells: at 0.25 persons/m^2 scanning those costs half what
    cells of half the reach do, at 1.25 as much. Returns start, ranks, cell, columns, rows, x0, y0."""
    x0, y0, x1, y1 = pos[0, 0], pos[0, 1], pos[0, 0], pos[0, 1]
    for p in range(len(pos)):
        x0, y0, x1, y1 = min(x0, pos[p, 0]), min(y0, pos[p, 1]), max(x1, pos[p, 0]), max(y1, pos[p, 1])
    cell = reach
    while ((x1 - x0) / cell + 1) * ((y1 - y0) / cell + 1) > 4 * len(pos) + 1024:
        cell *= 2
    columns, rows = int((x1 - x0) / cell) + 1, int((y1 - y0) / cell) + 1
    of = np.empty(len(pos), np.int64)
    start = np.zeros(columns * rows + 1, np.int64)
    for p in range(len(pos)):
        row = min(max(int((pos[p, 1] - y0) / cell), 0), rows - 1)
        of[p] = row * columns + min(max(int((pos[p, 0] - x0) / cell), 0), columns - 1)
        start[of[p] + 1] += 1
    for c in range(columns * rows):
        start[c + 1] += start[c]
    ranks, filled = np.empty(len(pos), np.int64), start[:-1].copy()
    for a in range(len(pos)):
        ranks[filled[of[order[a]]]] = a
        filled[of[order[a]]] += 1
    return start, ranks, cell, columns, rows, x0, y0


@kernel
def _add_moussaid(total, i, j, bx, by, sx, sy, walking, direction, cos_half, out_of_view):
    """The pair (i, j)'s forces on both (``moussaid_pair``'s braking and turning parts on i), each with its own
    turning flag and view weight, added to ``total``; nothing for a negligible pair."""
    if bx == 0.0 and by == 0.0 and sx == 0.0 and sy == 0.0:  # negligible
        return
    for who, sign in ((i, 1.0), (j, -1.0)):
        turn = 1.0 if walking[who] else 0.0
        fx, fy = sign * (bx + turn * sx), sign * (by + turn * sy)
        w = seen_weight(direction[who, 0], direction[who, 1], fx, fy, cos_half, out_of_view)
        total[who, 0] += w * fx
        total[who, 1] += w * fy


@kernel
def helbing_molnar1995(pos, vel, direction, pairs, strength, sigma, step_time, fov_deg, out_of_view):
    """Helbing & Molnar 1995 elliptical repulsion V(b) = V0 exp(-b / sigma), with
    2b = sqrt((|r| + |r - s e_j|)^2 - s^2), s = |v_j| step_time, and the field-of-view weighting, summed per person
    over both directions of each unordered pair [m, 2]."""
    total = np.zeros((len(pos), 2))
    cos_half = math.cos(math.radians(fov_deg) / 2)
    for k in range(2 * len(pairs)):
        i, j = (pairs[k, 0], pairs[k, 1]) if k < len(pairs) else (pairs[k - len(pairs), 1], pairs[k - len(pairs), 0])
        rx, ry = pos[i, 0] - pos[j, 0], pos[i, 1] - pos[j, 1]
        vx, vy = vel[j, 0], vel[j, 1]
        step = math.sqrt(vx * vx + vy * vy) * step_time
        yx, yy = rx - step_time * vx, ry - step_time * vy  # r - s e_j
        nr = max(math.sqrt(rx * rx + ry * ry), 1e-6)
        ny = max(math.sqrt(yx * yx + yy * yy), 1e-6)
        b = 0.5 * math.sqrt(max((nr + ny) ** 2 - step ** 2, 0.0))
        b = max(b, 0.05)  # keeps the gradient finite when i stands exactly in j's path
        mag = strength / sigma * math.exp(-b / sigma) * (nr + ny) / (4 * b)
        fx, fy = mag * (rx / nr + yx / ny), mag * (ry / nr + yy / ny)
        w = seen_weight(direction[i, 0], direction[i, 1], fx, fy, cos_half, out_of_view)
        total[i, 0] += w * fx
        total[i, 1] += w * fy
    return total


def neighbour_pairs(pos: np.ndarray, reach: float) -> np.ndarray:
    """Unordered index pairs [m, 2] of persons within ``reach`` of each other, from a k-d tree (O(N log N))."""
    if len(pos) < 2:
        return np.zeros((0, 2), np.int64)
    return _tree(pos).query_pairs(reach, output_type="ndarray")


def pair_order(pos: np.ndarray) -> np.ndarray:
    """The order [n] in which ``moussaid2009`` sums each person's pair forces: the persons' own up to
    ``EVERY_PAIR``, beyond it the leaves of ``neighbour_pairs``' k-d tree, left to right (``leaf_order``). The tree's
    pairs list each person's partners in that order (a traversal meets the pairs of one leaf with the others' leaves
    left to right), so the forces come out as they did when summed over its list, bit for bit, without the list."""
    pos = np.ascontiguousarray(pos, dtype=float)
    if pos.ndim != 2 or pos.shape[1] != 2:
        raise ValueError(f"pos: expected [n, 2] positions, got shape {pos.shape}")
    if len(pos) <= EVERY_PAIR:
        return np.arange(len(pos))
    return leaf_order(pos)


def _tree(pos: np.ndarray) -> cKDTree:
    # an unbalanced tree builds faster and queries no slower for crowds
    return cKDTree(pos, leafsize=LEAF_SIZE, balanced_tree=False, compact_nodes=False)


@kernel
def leaf_order(pos):
    """The persons [n] in the order of the leaves of their k-d tree ``_tree``, as scipy's cKDTree builds it
    (``indices``; scipy 1.17's build.cxx without balancing or compact nodes, leaves of up to 16): each node splits
    its points on the wider side of its box at the box's midpoint (slid onto the nearest point where all lie on one
    side), std::partition's way, and hands each half its half of the box. In a kernel it costs a quarter of building
    the tree."""
    indices = np.arange(len(pos))
    if len(pos) == 0:
        return indices
    # the nodes still to split: start, end and box (x0, y0, x1, y1); disjoint, of 17 points or more each
    start, end = np.empty(len(pos) // 17 + 2, np.int64), np.empty(len(pos) // 17 + 2, np.int64)
    box = np.empty((len(pos) // 17 + 2, 4))
    start[0], end[0] = 0, len(pos)
    box[0, 0], box[0, 1], box[0, 2], box[0, 3] = pos[0, 0], pos[0, 1], pos[0, 0], pos[0, 1]
    for p in range(len(pos)):
        box[0, 0], box[0, 1] = min(box[0, 0], pos[p, 0]), min(box[0, 1], pos[p, 1])
        box[0, 2], box[0, 3] = max(box[0, 2], pos[p, 0]), max(box[0, 3], pos[p, 1])
    top = 0 if len(pos) > LEAF_SIZE else -1
    while top >= 0:
        lo, hi = start[top], end[top]
        x0, y0, x1, y1 = box[top, 0], box[top, 1], box[top, 2], box[top, 3]
        top -= 1
        d = 1 if y1 - y0 > x1 - x0 and y1 - y0 > 0 else 0
        low, high = (x0, x1) if d == 0 else (y0, y1)
        if high == low:  # all points alike: a leaf
            continue
        split = (high + low) / 2
        q = _partition(indices, pos, d, split, lo, hi)
        if q == lo:  # none below the midpoint: split just above the lowest point
            first = indices[lo]
            for k in range(lo + 1, hi):
                if pos[indices[k], d] < pos[first, d]:
                    first = indices[k]
            split = np.nextafter(pos[first, d], np.inf)
            q = _partition(indices, pos, d, split, lo, hi)
        elif q == hi:  # none at or above it: split at the highest point
            last = indices[lo]
            for k in range(lo + 1, hi):
                if pos[last, d] < pos[indices[k], d]:
                    last = indices[k]
            split = pos[last, d]
            q = _partition(indices, pos, d, split, lo, hi)
        top += 1
        if q == lo or q == hi:  # all alike along d: again, with the box flat there
            start[top], end[top] = lo, hi
            box[top, 0], box[top, 1], box[top, 2], box[top, 3] = x0, y0, x1, y1
            box[top, d], box[top, d + 2] = pos[indices[lo], d], pos[indices[lo], d]
            continue
        start[top], end[top] = lo, q  # the lower half, its box below the split
        box[top, 0], box[top, 1], box[top, 2], box[top, 3] = x0, y0, x1, y1
        box[top, d + 2] = split
        if q - lo <= LEAF_SIZE:
            top -= 1
        top += 1
        start[top], end[top] = q, hi  # the upper half, its box above it
        box[top, 0], box[top, 1], box[top, 2], box[top, 3] = x0, y0, x1, y1
        box[top, d] = split
        if hi - q <= LEAF_SIZE:
            top -= 1
    return indices


@kernel
def _partition(indices, pos, d, split, lo, hi):
    """libstdc++'s std::partition of ``indices[lo:hi]`` by ``not pos[., d] >= split`` (those first, from both ends
    inwards, swapping); returns where the rest start."""
    first, last = lo, hi
    while True:
        while True:
            if first == last:
                return first
            if not pos[indices[first], d] >= split:
                first += 1
            else:
                break
        last -= 1
        while True:
            if first == last:
                return first
            if pos[indices[last], d] >= split:
                last -= 1
            else:
                break
        indices[first], indices[last] = indices[last], indices[first]
        first += 1


def wall_force(pos: np.ndarray, radius: np.ndarray, direction: np.ndarray, grid: WallGrid, strength: float,
               length: float, reach: float, fov_deg: float, out_of_view: float) -> np.ndarray:
    """Wall repulsion A exp(-(d - r) / B) on the gap between body and wall (Helbing, Farkas & Vicsek 2000: A = 2000 N
    on 80 kg, B = 0.08 m) from every wall of ``grid`` nearer than ``reach``, summed, each weighted by the field of
    view; a corner shared by two segments repels once."""
    return grid_wall_force(pos, radius, direction, strength, length, reach, fov_deg, out_of_view, *grid.arrays())


@kernel
def grid_wall_force(pos, radius, direction, strength, length, reach, fov_deg, out_of_view, walls, origin, cell,
                    columns, rows, start, members):
    """``wall_force`` on the grid's arrays (``WallGrid.arrays``), for callers that are kernels themselves."""
    f = np.zeros((len(pos), 2))
    cos_half = math.cos(math.radians(fov_deg) / 2)
    seen, near = np.full(len(walls), -1, np.int64), np.empty(len(walls), np.int64)
    corners = np.empty((len(walls), 2))  # the closest wall points already counted, in micrometres
    for i in range(len(pos)):
        x, y = pos[i, 0], pos[i, 1]
        kept = 0
        for k in range(near_walls(x, y, reach, walls, origin, cell, columns, rows, start, members, seen, i, near)):
            wx, wy, dist = away_from_wall(x, y, walls, near[k])
            if not dist < reach:
                continue
            cx, cy = math.floor((x - wx) * 1e6 + 0.5), math.floor((y - wy) * 1e6 + 0.5)
            counted = False
            for q in range(kept):
                counted |= corners[q, 0] == cx and corners[q, 1] == cy
            if counted:  # a corner where two segments meet is one wall point, not two
                continue
            corners[kept, 0], corners[kept, 1] = cx, cy
            kept += 1
            mag = strength * math.exp(-(dist - radius[i]) / length) / max(dist, 1e-9)
            w = seen_weight(direction[i, 0], direction[i, 1], mag * wx, mag * wy, cos_half, out_of_view)
            f[i, 0] += w * mag * wx
            f[i, 1] += w * mag * wy
    return f


@kernel
def obstacle_disc_force(pos, direction, cx, cy, radius, strength, length, fov_deg, out_of_view):
    """Repulsion from a disc (the robot) centred at (cx, cy): U/R exp(-gap/R) with gap the distance to its rim,
    weighted by the field of view."""
    f = np.zeros((len(pos), 2))
    cos_half = math.cos(math.radians(fov_deg) / 2)
    for i in range(len(pos)):
        ax, ay = pos[i, 0] - cx, pos[i, 1] - cy
        dist = max(math.sqrt(ax * ax + ay * ay), 1e-9)
        mag = strength / length * math.exp(-max(dist - radius, 0.0) / length) / dist
        fx, fy = mag * ax, mag * ay
        w = seen_weight(direction[i, 0], direction[i, 1], fx, fy, cos_half, out_of_view)
        f[i, 0], f[i, 1] = w * fx, w * fy
    return f


def group_forces(pos: np.ndarray, vel: np.ndarray, direction: np.ndarray, radius: np.ndarray, group: np.ndarray,
                 gaze: float, coherence: float, repulsion: float, vision_deg: float = GROUP_VISION_DEG,
                 margin: float = GROUP_MARGIN) -> np.ndarray:
    """Moussaid et al. 2010 (PLoS ONE 5(4) e10047) group terms for members of ``group`` >= 0.

    gaze: -beta1 alpha v, alpha the head rotation needed to keep the other members' centre in view (vision
    half-angle ``vision_deg``); coherence: beta2 towards the group's centre once farther than (N - 1) / 2 m;
    repulsion: beta3 away from each member nearer than the two radii plus ``margin``.
    """
    members, label, groups = group_labels(group)
    if len(members) < 2:  # no group of two: no force, and none of the work
        return np.zeros_like(pos)
    return group_members_forces(pos, vel, direction, radius, members, label, groups, gaze, coherence, repulsion,
                                math.radians(vision_deg), margin)


def group_labels(group: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The members (indices) of ``group`` >= 0, their groups numbered 0.. (``label``) and how many groups."""
    members = np.flatnonzero(group >= 0)
    if len(members) < 2:  # no group of two
        return members, members, 0
    ids, label = np.unique(group[members], return_inverse=True)
    return members, label.reshape(-1), len(ids)


@kernel
def group_members_forces(pos, vel, direction, radius, members, label, groups, gaze, coherence, repulsion, vision,
                         margin):
    """``group_forces`` for ``members`` (indices into the persons) of groups ``label`` (0 .. groups - 1)."""
    f = np.zeros((len(pos), 2))
    size = np.zeros(groups, np.int64)
    total = np.zeros((groups, 2))
    for k in range(len(members)):
        size[label[k]] += 1
        total[label[k], 0] += pos[members[k], 0]
        total[label[k], 1] += pos[members[k], 1]
    start = np.zeros(groups + 1, np.int64)  # each group's members, in order, at start[g]:start[g + 1] of ``order``
    for g in range(groups):
        start[g + 1] = start[g] + size[g]
    order, filled = np.empty(len(members), np.int64), start[:-1].copy()
    for k in range(len(members)):
        order[filled[label[k]]] = k
        filled[label[k]] += 1
    for k in range(len(members)):
        g, i = label[k], members[k]
        n = size[g]
        if n < 2:
            continue
        # coherence: towards the group's centre
        cx, cy = total[g, 0] / n - pos[i, 0], total[g, 1] / n - pos[i, 1]
        dist = math.sqrt(cx * cx + cy * cy)
        if dist > (n - 1) / 2:
            f[i, 0] += coherence * cx / dist
            f[i, 1] += coherence * cy / dist
        # gaze: the turn needed to keep the other members' centre in view
        ox, oy = (total[g, 0] - pos[i, 0]) / (n - 1) - pos[i, 0], (total[g, 1] - pos[i, 1]) / (n - 1) - pos[i, 1]
        cos = (direction[i, 0] * ox + direction[i, 1] * oy) / max(math.sqrt(ox * ox + oy * oy), 1e-9)
        alpha = max(math.acos(min(max(cos, -1.0), 1.0)) - vision, 0.0)
        f[i, 0] -= gaze * alpha * vel[i, 0]
        f[i, 1] -= gaze * alpha * vel[i, 1]
        # repulsion from each member too near
        for m in range(start[g], start[g + 1]):
            j = members[order[m]]
            if j == i:
                continue
            dx, dy = pos[i, 0] - pos[j, 0], pos[i, 1] - pos[j, 1]
            d = max(math.sqrt(dx * dx + dy * dy), 1e-9)
            if d < radius[i] + radius[j] + margin:
                f[i, 0] += repulsion * dx / d
                f[i, 1] += repulsion * dy / d
    return f
