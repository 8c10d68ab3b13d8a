"""The social-force terms, each a pure function on arrays (accelerations in m/s^2), so each can be tested alone.

Agent-agent terms work on directed neighbour pairs (i, j): the force that j exerts on i, summed per i with
``np.bincount``. Nothing here loops over agents.
"""

from __future__ import annotations

import numpy as np

from scenarios.geometry import near_segments, pair_vectors
from scenarios.typed import Section


NEGLIGIBLE = 0.005  # m/s^2: an interaction weaker than this (0.1% of Moussaid's A) is not computed


def _sum_per_agent(i: np.ndarray, fx: np.ndarray, fy: np.ndarray, n: int) -> np.ndarray:
    return np.stack([np.bincount(i, fx, n), np.bincount(i, fy, n)], axis=1)


def desired_force(direction: np.ndarray, speed: np.ndarray, vel: np.ndarray, tau: float) -> np.ndarray:
    """Relaxation towards the desired velocity: (v0 e - v) / tau (Helbing & Molnar 1995)."""
    return (speed[:, None] * direction - vel) / tau


def moussaid2009(pos: np.ndarray, vel: np.ndarray, pairs: np.ndarray, strength: float, lam: float, gamma: float,
                 n: float, n_prime: float, walking: np.ndarray | None = None, direction: np.ndarray | None = None,
                 fov_deg: float = 360.0, out_of_view: float = 1.0) -> np.ndarray:
    """Moussaid, Helbing et al. 2009 (Proc. R. Soc. B 276) agent interaction, the form PedSim uses.

    With e the unit vector from i to j and d their distance, the interaction vector D = lam (v_i - v_j) + e
    points along t = D / |D|; B = gamma |D|; theta is the signed angle from t to e. The force decelerates i along t
    and turns it away from j's side:
        f = -A exp(-d / B) [exp(-(n' B theta)^2) t + K exp(-(n B theta)^2) n_left],  K = sign(theta).
    At theta = 0 (a perfectly symmetric head-on meeting) there is no turning term, as in the paper
    (K = theta / |theta|); the random force breaks such ties. The turning term steers walkers round each other, so
    agents not ``walking`` (standing people) feel only the braking term, else they would circle each other.

    ``pairs`` [m, 2] are unordered: seen from j, D and t change sign while |D|, B and theta do not, so one
    evaluation gives both forces (f_j = -f_i but for whose turning term applies). With ``direction`` (the walking
    directions) the field-of-view weighting of Helbing & Molnar 1995 applies: people react less to those behind,
    which is what makes a dense crowd slow down (else pushes from behind cancel the braking from the front).
    """
    count = len(pos)
    # single precision for the pair arithmetic: it is memory-bound, and forces need no more than 7 digits
    state = np.concatenate([pos, vel], axis=1).astype(np.float32)
    # one [m, 4] difference (j - i: position, velocity) instead of a temporary per component
    diff = np.take(state, pairs[:, 1], axis=0)
    diff -= np.take(state, pairs[:, 0], axis=0)
    lam, gamma, strength = np.float32(lam), np.float32(gamma), np.float32(strength)
    d = np.sqrt(np.einsum("ij,ij->i", diff[:, :2], diff[:, :2]))
    np.maximum(d, 1e-9, out=d)
    ex, ey = diff[:, 0] / d, diff[:, 1] / d
    Dx, Dy = ex - lam * diff[:, 2], ey - lam * diff[:, 3]  # lam (v_i - v_j) + e
    nD = np.sqrt(Dx * Dx + Dy * Dy)
    # neither term exceeds A exp(-d / B), B = gamma |D|: pairs whose force cannot reach NEGLIGIBLE m/s^2 are
    # dropped before the costly part (in a crowd walking one way, about 40% of the pairs within range)
    reach = np.float32(gamma * np.log(strength / NEGLIGIBLE) if strength > NEGLIGIBLE else 0.0)
    near = np.flatnonzero(d < reach * nD)
    d, ex, ey, Dx, Dy = d[near], ex[near], ey[near], Dx[near], Dy[near]
    nD = np.maximum(nD[near], 1e-9)
    tx, ty = Dx / nD, Dy / nD
    theta = np.arctan2(tx * ey - ty * ex, tx * ex + ty * ey)
    B = gamma * nD
    base = -strength * np.exp(-d / B)
    along = base * np.exp(-(n_prime * B * theta) ** 2)
    side = base * np.sign(theta) * np.exp(-(n * B * theta) ** 2)
    i, j = pairs[near, 0], pairs[near, 1]
    cos_half = np.float32(np.cos(np.radians(fov_deg) / 2))
    heading = None if direction is None or out_of_view >= 1.0 else direction.astype(np.float32)
    total = np.zeros((count, 2))
    # i feels f, j feels -f (t and n_left flip sign for j), each with its own turning flag and view weight
    for who, sign in ((i, 1.0), (j, -1.0)):
        turn = side if walking is None else side * walking[who]
        fx = sign * (along * tx - turn * ty)  # n_left = (-t_y, t_x)
        fy = sign * (along * ty + turn * tx)
        if heading is not None:  # in_view_weight, on components: this is the hot path
            seen = -(np.take(heading[:, 0], who) * fx + np.take(heading[:, 1], who) * fy) >= (
                np.sqrt(fx * fx + fy * fy) * cos_half)
            w = np.where(seen, np.float32(1.0), np.float32(out_of_view))
            fx, fy = fx * w, fy * w
        total += _sum_per_agent(who, fx, fy, count)
    return total


def moussaid2009_dense(z: np.ndarray, v: np.ndarray, e: np.ndarray, strength: float, lam: float, gamma: float,
                       n: float, n_prime: float, fov_deg: float, out_of_view: float) -> np.ndarray:
    """``moussaid2009`` between every two persons of each of many small worlds, everyone walking: positions,
    velocities and walking directions [E, N] as complex numbers x + iy; returns the forces [E, N] likewise.

    For worlds of a few tens of people the cost is the number of array calls, not their size: dense [E, N, N] arrays
    and complex numbers (a rotation by 90 degrees is a product by i, the signed angle from t to e that of conj(t) e)
    give the same force in a quarter of ``moussaid2009``'s calls (a test keeps the two equal)."""
    dz = z[:, None, :] - z[:, :, None]  # [e, i, j]: j - i
    d = np.abs(dz)
    d += _far(z.shape[1])  # no one pushes themselves
    dz /= d  # the unit vector e from i to j
    t = dz - lam * (v[:, None, :] - v[:, :, None])  # D = lam (v_i - v_j) + e
    B = np.abs(t)
    np.maximum(B, 1e-9, out=B)
    t /= B
    theta = np.angle(t.conjugate() * dz)
    B *= gamma
    base = np.exp(-d / B)
    base *= -strength
    B *= theta
    B *= B  # (B theta)^2
    f = base * np.exp(-n_prime * n_prime * B) + 1j * (base * np.sign(theta) * np.exp(-n * n * B))
    f *= t  # along t, and turning along n_left = i t
    if out_of_view < 1.0:
        seen = -(e.conjugate()[:, :, None] * f).real >= np.abs(f) * np.cos(np.radians(fov_deg) / 2)
        f *= np.where(seen, 1.0, out_of_view)
    return f.sum(axis=2)


_FAR = {}


def _far(n: int) -> np.ndarray:
    """An [n, n] matrix, 1e9 on the diagonal: added to distances, a person's pair with themselves is out of reach."""
    if n not in _FAR:
        _FAR[n] = np.eye(n) * 1e9
    return _FAR[n]


def pair_forces(p: Section, pos: np.ndarray, vel: np.ndarray, direction: np.ndarray, pairs: np.ndarray,
                walking: np.ndarray | None = None) -> np.ndarray:
    """The agent-agent force the crowd parameters ``p`` choose (``interaction``), over unordered neighbour
    ``pairs`` [m, 2], summed per agent."""
    if len(pairs) == 0:
        return np.zeros((len(pos), 2))
    if p.interaction == "moussaid2009":
        return moussaid2009(pos, vel, pairs, p.moussaid_strength, p.moussaid_lambda, p.moussaid_gamma,
                            p.moussaid_n, p.moussaid_n_prime, walking=walking, direction=direction,
                            fov_deg=p.fov_deg, out_of_view=p.out_of_view_weight)
    i = np.concatenate([pairs[:, 0], pairs[:, 1]])
    j = np.concatenate([pairs[:, 1], pairs[:, 0]])
    return helbing_molnar1995(pos, vel, direction, i, j, p.agent_strength, p.agent_range, p.step_time,
                              p.fov_deg, p.out_of_view_weight)


def in_view_weight(direction: np.ndarray, force: np.ndarray, fov_deg: float, out_of_view: float) -> np.ndarray:
    """Helbing & Molnar 1995 anisotropy: weight 1 when the force's source lies within the field of view (a force
    pointing against the walking direction), ``out_of_view`` (c) otherwise."""
    norm = np.linalg.norm(force, axis=-1)
    seen = np.einsum("...k,...k->...", direction, -force) >= norm * np.cos(np.radians(fov_deg) / 2)
    return np.where(seen, 1.0, out_of_view)


def helbing_molnar1995(pos: np.ndarray, vel: np.ndarray, direction: np.ndarray, i: np.ndarray, j: np.ndarray,
                       strength: float, sigma: float, step_time: float, fov_deg: float,
                       out_of_view: float) -> np.ndarray:
    """Helbing & Molnar 1995 elliptical repulsion V(b) = V0 exp(-b / sigma), with
    2b = sqrt((|r| + |r - s e_j|)^2 - s^2), s = |v_j| step_time, and the field-of-view weighting."""
    count = len(pos)
    rx, ry = pos[i, 0] - pos[j, 0], pos[i, 1] - pos[j, 1]
    vx, vy = vel[j, 0], vel[j, 1]
    step = np.sqrt(vx * vx + vy * vy) * step_time
    yx, yy = rx - step_time * vx, ry - step_time * vy  # r - s e_j
    nr = np.maximum(np.sqrt(rx * rx + ry * ry), 1e-6)
    ny = np.maximum(np.sqrt(yx * yx + yy * yy), 1e-6)
    b = 0.5 * np.sqrt(np.maximum((nr + ny) ** 2 - step**2, 0.0))
    b = np.maximum(b, 0.05)  # keeps the gradient finite when i stands exactly in j's path
    mag = strength / sigma * np.exp(-b / sigma) * (nr + ny) / (4 * b)
    fx = mag * (rx / nr + yx / ny)
    fy = mag * (ry / nr + yy / ny)
    w = in_view_weight(direction[i], np.stack([fx, fy], 1), fov_deg, out_of_view)
    return _sum_per_agent(i, w * fx, w * fy, count)


def wall_force(pos: np.ndarray, radius: np.ndarray, direction: np.ndarray, walls: np.ndarray, strength: float,
               length: float, reach: float, fov_deg: float, out_of_view: float) -> np.ndarray:
    """Wall repulsion A exp(-(d - r) / B) on the gap between body and wall (Helbing, Farkas & Vicsek 2000: A = 2000 N
    on 80 kg, B = 0.08 m) from every segment nearer than ``reach``, summed; a corner shared by two segments repels
    once."""
    if len(walls) == 0 or len(pos) == 0:
        return np.zeros_like(pos)
    p, s = near_segments(pos, walls, reach)
    away, dist = pair_vectors(pos, walls, p, s)
    near = dist < reach
    p, away, dist = p[near], away[near], dist[near]
    # a corner where two segments meet is one wall point, not two: count each (agent, closest point) once
    closest = np.round((pos[p] - away) / 1e-6)
    order = np.lexsort((closest[:, 1], closest[:, 0], p))
    same = np.zeros(len(order), bool)
    same[1:] = (p[order][1:] == p[order][:-1]) & (closest[order][1:] == closest[order][:-1]).all(axis=1)
    keep = order[~same]
    p, away, dist = p[keep], away[keep], dist[keep]
    f = (strength * np.exp(-(dist - radius[p]) / length) / np.maximum(dist, 1e-9))[:, None] * away
    f *= in_view_weight(direction[p], f, fov_deg, out_of_view)[:, None]
    return _sum_per_agent(p, f[:, 0], f[:, 1], len(pos))


def obstacle_disc_force(pos: np.ndarray, direction: np.ndarray, centre: np.ndarray, radius: float,
                        strength: float, length: float, fov_deg: float, out_of_view: float) -> np.ndarray:
    """Repulsion from a disc (the robot): U/R exp(-gap/R) with gap the distance to its rim."""
    away = pos - centre
    dist = np.maximum(np.linalg.norm(away, axis=1), 1e-9)
    gap = np.maximum(dist - radius, 0.0)
    f = (strength / length * np.exp(-gap / length))[:, None] * away / dist[:, None]
    return f * in_view_weight(direction, f, fov_deg, out_of_view)[:, None]


def group_forces(pos: np.ndarray, vel: np.ndarray, direction: np.ndarray, radius: np.ndarray, group: np.ndarray,
                 gaze: float, coherence: float, repulsion: float, vision_deg: float = 90.0,
                 margin: float = 0.3) -> np.ndarray:
    """Moussaid et al. 2010 (PLoS ONE 5(4) e10047) group terms for members of ``group`` >= 0.

    gaze: -beta1 alpha v, alpha the head rotation needed to keep the other members' centre in view (vision
    half-angle ``vision_deg``); coherence: beta2 towards the group's centre once farther than (N - 1) / 2 m;
    repulsion: beta3 away from each member nearer than the two radii plus ``margin``.
    """
    f = np.zeros_like(pos)
    idx = np.flatnonzero(group >= 0)
    if len(idx) < 2:  # no group of two: no force, and none of the work below (a crowd step's 0.3 ms at 100 agents)
        return f
    _, g, size = np.unique(group[idx], return_inverse=True, return_counts=True)
    size_i = size[g]
    total = np.stack([np.bincount(g, pos[idx, 0]), np.bincount(g, pos[idx, 1])], 1)
    centroid = total[g] / size_i[:, None]
    others = (total[g] - pos[idx]) / np.maximum(size_i - 1, 1)[:, None]  # centre of the other members
    # coherence
    to_c = centroid - pos[idx]
    dist_c = np.linalg.norm(to_c, axis=1)
    pull = (size_i > 1) & (dist_c > (size_i - 1) / 2)
    f[idx[pull]] += coherence * to_c[pull] / dist_c[pull, None]
    # gaze
    to_o = others - pos[idx]
    heading = direction[idx]
    cosang = np.einsum("ij,ij->i", heading, to_o) / np.maximum(np.linalg.norm(to_o, axis=1), 1e-9)
    alpha = np.maximum(np.arccos(np.clip(cosang, -1, 1)) - np.radians(vision_deg), 0.0)
    f[idx] += -gaze * alpha[:, None] * vel[idx] * (size_i > 1)[:, None]
    # repulsion between members
    a, b = pairs_within_groups(g)
    d = pos[idx[a]] - pos[idx[b]]
    dist = np.maximum(np.linalg.norm(d, axis=1), 1e-9)
    near = dist < radius[idx[a]] + radius[idx[b]] + margin
    push = repulsion * d[near] / dist[near, None]
    np.add.at(f, idx[a[near]], push)
    return f


def pairs_within_groups(group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every ordered pair (a, b), a != b, of indices whose ``group`` labels (0 .. G-1) are equal: a group of n
    gives n (n - 1) pairs, a group of one none. Each member's partners come in the group's order."""
    order = np.argsort(group, kind="stable")
    size = np.bincount(group)
    first = np.cumsum(size) - size  # where each group starts in ``order``
    partners = size[group]
    a = np.repeat(np.arange(len(group)), partners)
    rank = np.arange(len(a)) - np.repeat(np.cumsum(partners) - partners, partners)  # 0 .. n-1 within each member
    b = order[np.repeat(first[group], partners) + rank]
    other = a != b
    return a[other], b[other]
