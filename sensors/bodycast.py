"""Exact ray casts against the people's bodies (torso cylinder, head sphere, two leg capsules), vectorized over rays.

The cameras use these for what OpenGL cannot give cheaply: each person's silhouette as it would show with nothing in
front (the visible fraction's denominator), and the people of a wall camera's image. Under Mesa every drawn geom
costs about 20 microseconds whatever its size on screen, so 75 people of four parts cost 6-7 ms a pass; the rays of
the pixels they cover cost a fraction of that, and the surfaces are the exact primitives the lasers see.

``cast_part`` casts rays against one part of many persons (the camera keeps the nearest part per pixel). Each
primitive takes ray origins relative to the primitive and directions ``d`` of any length, and returns the ray
parameter t of the first surface point o + t d with t >= 0 (inf where the ray misses). Single precision: relative
to each person, a millimetre is far below a pixel here.
"""

from __future__ import annotations

import numpy as np

from . import body

TORSO, HEAD, LEFT_LEG, RIGHT_LEG = range(4)  # the parts, in the order of ``part_box_corners``
F = np.float32


def ray_vertical_cylinder(px, py, oz, dx, dy, dz, r, z0, z1) -> np.ndarray:
    """A closed cylinder of radius r about the vertical axis through the origin, between heights z0 and z1
    (ray origin (px, py, oz) relative to the axis)."""
    a = dx * dx + dy * dy
    b = dx * px + dy * py  # half the linear coefficient
    c = px * px + py * py - r * r
    disc = b * b - a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        sq = np.sqrt(np.maximum(disc, 0))
        t0, t1 = (-b - sq) / a, (-b + sq) / a
        flat = a < 1e-12  # a vertical ray: inside the circle or not at all
        t0 = np.where(flat, np.where(c <= 0, -np.inf, np.inf), t0)
        t1 = np.where(flat, np.where(c <= 0, np.inf, -np.inf), t1)
        za, zb = (z0 - oz) / dz, (z1 - oz) / dz
        level = np.abs(dz) < 1e-12
        inside = (z0 <= oz) & (oz <= z1)
        tz0 = np.where(level, np.where(inside, -np.inf, np.inf), np.minimum(za, zb))
        tz1 = np.where(level, np.where(inside, np.inf, -np.inf), np.maximum(za, zb))
    enter = np.maximum(np.maximum(t0, tz0), 0)
    return np.where((disc >= 0) & (enter <= np.minimum(t1, tz1)), enter, np.inf).astype(F)


def ray_sphere(wx, wy, wz, dx, dy, dz, r) -> np.ndarray:
    """A sphere of radius r about the origin (ray origin w relative to the centre)."""
    a = dx * dx + dy * dy + dz * dz
    b = dx * wx + dy * wy + dz * wz  # half the linear coefficient
    disc = b * b - a * (wx * wx + wy * wy + wz * wz - r * r)
    sq = np.sqrt(np.maximum(disc, 0))
    t = np.maximum((-b - sq) / a, 0)
    return np.where((disc >= 0) & (-b + sq >= 0), t, np.inf).astype(F)


def ray_capsule(wx, wy, wz, dx, dy, dz, e, r, start_cap: bool = True) -> np.ndarray:
    """A capsule of radius r round the segment from the origin to e [n, 3] (ray origin w relative to its start).

    The capsule is the union of its side (the infinite cylinder round the segment's line, where the entry point
    projects onto the segment) and the spheres at the two ends, so its first hit is the nearest of theirs.
    ``start_cap=False`` leaves out the sphere at the start, for a capsule whose start lies inside another body."""
    ex, ey, ez = e[:, 0], e[:, 1], e[:, 2]
    A = dx * dx + dy * dy + dz * dz
    B = dx * ex + dy * ey + dz * ez
    C = ex * ex + ey * ey + ez * ez
    D = dx * wx + dy * wy + dz * wz
    E = ex * wx + ey * wy + ez * wz
    W = wx * wx + wy * wy + wz * wz
    # |w + t d|^2 - (E + t B)^2 / C = r^2, times C
    qa, qb, qc = A * C - B * B, C * D - E * B, C * W - E * E - r * r * C
    disc = qb * qb - qa * qc
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (-qb - np.sqrt(np.maximum(disc, 0))) / qa
        s = (E + t * B) / C
    side = np.where((disc >= 0) & (qa > 1e-12) & (t >= 0) & (s >= 0) & (s <= 1), t, np.inf).astype(F)
    side = np.minimum(side, ray_sphere(wx - ex, wy - ey, wz - ez, dx, dy, dz, r))
    return np.minimum(side, ray_sphere(wx, wy, wz, dx, dy, dz, r)) if start_cap else side


def cast_part(scene, slot: np.ndarray, part: int, o: np.ndarray, owner: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Ray parameters t [n] (inf for a miss) of rays from ``o`` [3] along ``d`` [n, 3] to one ``part`` of the body
    of the person in ``slot[owner[i]]`` of the scene, each body at its own size. What depends on the person alone
    is worked out once per person, the rest per ray."""
    k = scene.person_scale[slot].astype(F)
    ox, oy, oz = (F(c) for c in o)
    dx, dy, dz = d.T.astype(F)
    if part == TORSO:
        x, y = scene.person_xy[slot].T.astype(F)
        return ray_vertical_cylinder((ox - x)[owner], (oy - y)[owner], oz, dx, dy, dz,
                                     (F(body.TORSO_RADIUS) * k)[owner], (F(body.TORSO_BOTTOM) * k)[owner],
                                     (F(body.TORSO_TOP) * k)[owner])
    if part == HEAD:
        x, y = scene.person_xy[slot].T.astype(F)
        return ray_sphere((ox - x)[owner], (oy - y)[owner], (oz - F(body.HEAD_CENTRE) * k)[owner], dx, dy, dz,
                          (F(body.HEAD_RADIUS) * k)[owner])
    leg = part - LEFT_LEG
    a, b = scene.hips[slot, leg].astype(F), scene.feet[slot, leg].astype(F)
    # where the hip's end of the leg lies inside the torso, a ray meets the torso before it
    return ray_capsule((ox - a[:, 0])[owner], (oy - a[:, 1])[owner], (oz - a[:, 2])[owner], dx, dy, dz,
                       (b - a)[owner], (F(body.LEG_RADIUS) * k)[owner], start_cap=not body.HIP_INSIDE_TORSO)


PART_CORNERS = (slice(0, 8), slice(8, 16), slice(16, 24), slice(24, 32))  # of part_box_corners, by part


def part_box_corners(scene, slot: np.ndarray) -> np.ndarray:
    """Corners [n, 32, 3] of boxes round each person's torso, head, left leg and right leg (``PART_CORNERS``): their
    projection bounds each part's, and the person's, in a camera that has all of them in front."""
    k = scene.person_scale[slot][:, None, None]
    unit = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
    centre = np.zeros((len(slot), 1, 3))
    centre[..., :2] = scene.person_xy[slot][:, None]
    mid, half = (body.TORSO_BOTTOM + body.TORSO_TOP) / 2, (body.TORSO_TOP - body.TORSO_BOTTOM) / 2
    torso = centre + [0.0, 0.0, mid] * k + unit * [body.TORSO_RADIUS, body.TORSO_RADIUS, half] * k
    head = centre + [0.0, 0.0, body.HEAD_CENTRE] * k + unit * body.HEAD_RADIUS * k
    legs = []
    for leg in (0, 1):  # the box round the leg's axis, grown by its radius
        ends = np.stack([scene.hips[slot, leg], scene.feet[slot, leg]], 1)
        lo, hi = ends.min(axis=1) - body.LEG_RADIUS * k[:, 0], ends.max(axis=1) + body.LEG_RADIUS * k[:, 0]
        legs.append((lo + hi)[:, None] / 2 + unit * (hi - lo)[:, None] / 2)
    return np.concatenate([torso, head, *legs], 1)


def normals(scene, slot: np.ndarray, part: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Outward unit normals [n, 3] at surface points [n, 3] of the given parts of the persons in ``slot``: from the
    nearest point of the part's axis (the torso's vertical axis at the point's height, the head's centre, the leg's
    segment), vertical on the torso's flat ends."""
    k = scene.person_scale[slot]
    axis = np.empty_like(points)
    axis[:, :2] = scene.person_xy[slot]
    axis[:, 2] = np.where(part == HEAD, body.HEAD_CENTRE * k, points[:, 2])
    for p, leg in ((LEFT_LEG, 0), (RIGHT_LEG, 1)):
        sel = np.flatnonzero(part == p)
        a = scene.hips[slot[sel], leg]
        e = scene.feet[slot[sel], leg] - a
        s = np.clip(np.einsum("ij,ij->i", points[sel] - a, e) / np.einsum("ij,ij->i", e, e), 0, 1)
        axis[sel] = a + s[:, None] * e
    n = points - axis
    length = np.sqrt(np.einsum("ij,ij->i", n, n))
    cap = (part == TORSO) & (length < 0.98 * body.TORSO_RADIUS * k)
    n[cap] = 0.0
    n[cap, 2] = np.sign(points[cap, 2] - (body.TORSO_BOTTOM + body.TORSO_TOP) / 2 * k[cap])
    length[cap] = 1.0
    return n / np.maximum(length, 1e-12)[:, None]


def colours(person_ids: np.ndarray) -> np.ndarray:
    """RGB [n, 4, 3] in [0, 1] of each person's parts in the parts' order: their top, skin, and trousers twice
    (sensors/body.py)."""
    top, trousers = body.clothing(person_ids)
    return np.stack([top, np.broadcast_to(body.SKIN, top.shape), trousers, trousers], 1)
