"""Exact ray casts against the people's bodies (torso cylinder, head sphere, two leg capsules), compiled.

The cameras use these for what OpenGL cannot give cheaply: each person's silhouette as it would show with nothing in
front (the visible fraction's denominator), and the people of a wall camera's image. Under Mesa every drawn geom
costs about 20 microseconds whatever its size on screen, so 75 people of four parts cost 6-7 ms a pass; the rays of
the pixels they cover cost a fraction of that, and the surfaces are the exact primitives the lasers see.

``nearest_parts`` casts the rays of the pixels of each person's box against their four parts and keeps the nearest
part per pixel, in one kernel (numpy made some thirty passes over temporaries as long as the rays: 3.7 ms for the
93 people of a wall camera's view, 1.1 ms now). Each primitive is a scalar kernel that takes a ray origin relative to the primitive and a direction d of any
length, and returns the ray parameter t of the first surface point o + t d with t >= 0 (inf where the ray misses).
Single precision, as every value is float32: relative to each person, a millimetre is far below a pixel here. A
pixel's ray is summed in float64 in the order written and then rounded to float32; the matrix product it replaced
(BLAS, with fused multiply-adds) differs in the last float64 bit for about one value in eight, and gave the same
float32 in all of 2 million. The normals' three-term sums, in the order written, differ from numpy's ``einsum``
(which adds the first and third terms first) by up to 3e-14: no 8-bit colour moved in 400 wall-camera frames.
"""

from __future__ import annotations

import numpy as np

from pipeline.compiled import kernel

from . import body

TORSO, HEAD, LEFT_LEG, RIGHT_LEG = range(4)  # the parts, in the order of ``part_box_corners``
F = np.float32
_ZERO, _TINY, _INF = F(0.0), F(1e-12), F(np.inf)


@kernel
def ray_vertical_cylinder(px, py, oz, dx, dy, dz, r, z0, z1):
    """A closed cylinder of radius r about the vertical axis through the origin, between heights z0 and z1
    (ray origin (px, py, oz) relative to the axis)."""
    a = dx * dx + dy * dy
    b = dx * px + dy * py  # half the linear coefficient
    c = px * px + py * py - r * r
    disc = b * b - a * c
    if not disc >= _ZERO:  # misses the infinite cylinder
        return _INF
    if a < _TINY:  # a vertical ray: inside the circle or not at all
        t0, t1 = (-_INF, _INF) if c <= _ZERO else (_INF, -_INF)
    else:
        sq = np.sqrt(disc)
        t0, t1 = (-b - sq) / a, (-b + sq) / a
    if abs(dz) < _TINY:  # a level ray: between the ends or not at all
        tz0, tz1 = (-_INF, _INF) if z0 <= oz <= z1 else (_INF, -_INF)
    else:
        za, zb = (z0 - oz) / dz, (z1 - oz) / dz
        tz0, tz1 = min(za, zb), max(za, zb)
    enter = max(max(t0, tz0), _ZERO)
    return enter if enter <= min(t1, tz1) else _INF


@kernel
def ray_sphere(wx, wy, wz, dx, dy, dz, r):
    """A sphere of radius r about the origin (ray origin w relative to the centre)."""
    a = dx * dx + dy * dy + dz * dz
    b = dx * wx + dy * wy + dz * wz  # half the linear coefficient
    disc = b * b - a * (wx * wx + wy * wy + wz * wz - r * r)
    if not disc >= _ZERO:
        return _INF
    sq = np.sqrt(disc)
    return max((-b - sq) / a, _ZERO) if -b + sq >= _ZERO else _INF


@kernel
def ray_capsule(wx, wy, wz, dx, dy, dz, ex, ey, ez, r, start_cap):
    """A capsule of radius r round the segment from the origin to e (ray origin w relative to its start).

    The capsule is the union of its side (the infinite cylinder round the segment's line, where the entry point
    projects onto the segment) and the spheres at the two ends, so its first hit is the nearest of theirs.
    ``start_cap=False`` leaves out the sphere at the start, for a capsule whose start lies inside another body."""
    A = dx * dx + dy * dy + dz * dz
    B = dx * ex + dy * ey + dz * ez
    C = ex * ex + ey * ey + ez * ez
    D = dx * wx + dy * wy + dz * wz
    E = ex * wx + ey * wy + ez * wz
    W = wx * wx + wy * wy + wz * wz
    # |w + t d|^2 - (E + t B)^2 / C = r^2, times C
    qa, qb, qc = A * C - B * B, C * D - E * B, C * W - E * E - r * r * C
    disc = qb * qb - qa * qc
    side = _INF
    if disc >= _ZERO and qa > _TINY:
        t = (-qb - np.sqrt(disc)) / qa
        s = (E + t * B) / C
        if t >= _ZERO and s >= _ZERO and s <= F(1.0):
            side = t
    side = min(side, ray_sphere(wx - ex, wy - ey, wz - ez, dx, dy, dz, r))
    return min(side, ray_sphere(wx, wy, wz, dx, dy, dz, r)) if start_cap else side


@kernel
def _part_values(o, part, sizes, xy, hips, feet):
    """One part of one person as its primitive takes it: the ray origin relative to it, then its measures (a torso's
    radius, bottom and top; a head's radius; a leg's axis and radius)."""
    ox, oy, oz = o
    values = np.zeros(7, np.float32)
    if part == TORSO:
        values[0], values[1], values[2], values[3], values[4], values[5] = (ox - xy[0], oy - xy[1], oz, sizes[0],
                                                                            sizes[1], sizes[2])
    elif part == HEAD:
        values[0], values[1], values[2], values[3] = ox - xy[0], oy - xy[1], oz - sizes[3], sizes[4]
    else:
        a, b = hips[part - LEFT_LEG], feet[part - LEFT_LEG]
        values[0], values[1], values[2] = ox - a[0], oy - a[1], oz - a[2]
        values[3], values[4], values[5], values[6] = b[0] - a[0], b[1] - a[1], b[2] - a[2], sizes[5]
    return values


@kernel
def nearest_parts(origin, rot, f, cx, cy, width, height, part_lo, part_hi, cast, sizes, xy, hips, feet, start_cap):
    """Each person's silhouette: the nearest part at every pixel of their box that a ray of the camera meets.

    Person i's box is the union of the boxes [part_lo, part_hi) [n, 4, 2] of its parts, cast where ``cast``. A
    part's box pixels inside the image are all cast; where it reaches beyond the image, the pixels out there only
    on even rows and columns. On a tie the earlier part (torso, head, left leg, right leg) keeps the pixel. The camera
    is at ``origin`` with the optical frame's axes ``rot``, focal length f and centre (cx, cy) in pixels; every
    person's values are float32. Returns the hits by person, then row by row: person, u, v, z-depth (the ray's
    parameter, as its optical z is 1), part, and the pixels each stands for (1 inside the image, 4 outside)."""
    n = len(cast)
    o = (np.float32(origin[0]), np.float32(origin[1]), np.float32(origin[2]))
    lo = np.empty((n, 2), np.int64)
    box = np.zeros((n, 2), np.int64)
    start = np.zeros(n + 1, np.int64)
    for i in range(n):
        lo[i, 0], lo[i, 1] = part_lo[i, :, 0].min(), part_lo[i, :, 1].min()
        if cast[i]:
            box[i, 0], box[i, 1] = part_hi[i, :, 0].max() - lo[i, 0], part_hi[i, :, 1].max() - lo[i, 1]
        start[i + 1] = start[i] + box[i, 0] * box[i, 1]
    depth = np.full(start[n], np.inf, np.float32)
    nearest_part = np.zeros(start[n], np.int64)
    for i in range(n):
        if not cast[i]:
            continue
        for part in range(4):
            p = _part_values(o, part, sizes[i], xy[i], hips[i], feet[i])
            u0, v0, u1, v1 = part_lo[i, part, 0], part_lo[i, part, 1], part_hi[i, part, 0], part_hi[i, part, 1]
            crosses = u0 < 0 or v0 < 0 or u1 > width or v1 > height
            for v in range(v0, v1):
                y = (v + 0.5 - cy) / f
                row = start[i] + (v - lo[i, 1]) * box[i, 0] - lo[i, 0]
                for u in range(u0, u1):
                    if crosses and not (0 <= u < width and 0 <= v < height) and (u % 2 != 0 or v % 2 != 0):
                        continue
                    x = (u + 0.5 - cx) / f
                    dx = np.float32(x * rot[0, 0] + y * rot[0, 1] + rot[0, 2])
                    dy = np.float32(x * rot[1, 0] + y * rot[1, 1] + rot[1, 2])
                    dz = np.float32(x * rot[2, 0] + y * rot[2, 1] + rot[2, 2])
                    if part == TORSO:
                        t = ray_vertical_cylinder(p[0], p[1], p[2], dx, dy, dz, p[3], p[4], p[5])
                    elif part == HEAD:
                        t = ray_sphere(p[0], p[1], p[2], dx, dy, dz, p[3])
                    else:
                        t = ray_capsule(p[0], p[1], p[2], dx, dy, dz, p[3], p[4], p[5], p[6], start_cap)
                    if t < depth[row + u]:
                        depth[row + u] = t
                        nearest_part[row + u] = part
    hits = 0
    for at in range(start[n]):
        hits += depth[at] < np.inf
    owner, us, vs = np.empty(hits, np.int64), np.empty(hits, np.int64), np.empty(hits, np.int64)
    z, parts, weight = np.empty(hits, np.float32), np.empty(hits, np.int64), np.empty(hits)
    k = 0
    for i in range(n):
        for local in range(start[i + 1] - start[i]):
            at = start[i] + local
            if depth[at] < np.inf:
                u, v = lo[i, 0] + local % box[i, 0], lo[i, 1] + local // box[i, 0]
                owner[k], us[k], vs[k], z[k], parts[k] = i, u, v, depth[at], nearest_part[at]
                weight[k] = 1.0 if 0 <= u < width and 0 <= v < height else 4.0
                k += 1
    return owner, us, vs, z, parts, weight


def bodies(scene, slot: np.ndarray) -> tuple[np.ndarray, ...]:
    """What ``nearest_parts`` takes of the persons in ``slot``, in float32: their sizes (torso radius, bottom and
    top, head centre and radius, leg radius, each at the person's own scale), positions, hips and leg ends."""
    k = scene.person_scale[slot].astype(F)
    sizes = np.stack([F(c) * k for c in (body.TORSO_RADIUS, body.TORSO_BOTTOM, body.TORSO_TOP, body.HEAD_CENTRE,
                                         body.HEAD_RADIUS, body.LEG_RADIUS)], 1)
    return sizes, scene.person_xy[slot].astype(F), scene.hips[slot].astype(F), scene.feet[slot].astype(F)


UNIT_BOX = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)  # [-1, 1]^3


def part_box_corners(scene, slot: np.ndarray) -> np.ndarray:
    """Corners [n, 32, 3] of boxes round each person's torso, head, left leg and right leg (8 each, in turn): their
    projection bounds each part's, and the person's, in a camera that has all of them in front."""
    slot = np.asarray(slot, np.int64)
    if len(slot) and (slot.min() < 0 or slot.max() >= len(scene.person_scale)):
        raise ValueError(f"slot must lie in [0, {len(scene.person_scale)})")
    return _part_box_corners(slot, scene.person_scale, scene.person_xy, scene.hips, scene.feet, UNIT_BOX,
                             np.array([body.TORSO_BOTTOM, body.TORSO_TOP, body.TORSO_RADIUS, body.HEAD_CENTRE,
                                       body.HEAD_RADIUS, body.LEG_RADIUS]))


@kernel
def _part_box_corners(slot, scale, xy, hips, feet, unit, measures):
    """``part_box_corners`` from every slot's scale, position, hips and leg ends, read at ``slot``, and the adult
    body's ``measures`` (torso bottom, top and radius, head centre and radius, leg radius); each corner is the sum
    of a centre and a half size times a corner of the unit box, in the order numpy broadcasts them."""
    bottom, top, torso_radius, head_centre, head_radius, leg_radius = measures
    mid, half = (bottom + top) / 2, (top - bottom) / 2
    out = np.empty((len(slot), 32, 3))
    for n in range(len(slot)):
        i = slot[n]
        k = scale[i]
        centre = (xy[i, 0], xy[i, 1], 0.0)
        torso_mid = (0.0 * k, 0.0 * k, mid * k)
        torso_half = (torso_radius, torso_radius, half)
        head_mid = (0.0 * k, 0.0 * k, head_centre * k)
        for c in range(8):
            for a in range(3):
                out[n, c, a] = (centre[a] + torso_mid[a]) + unit[c, a] * torso_half[a] * k
                out[n, 8 + c, a] = (centre[a] + head_mid[a]) + unit[c, a] * head_radius * k
        for leg in range(2):
            for a in range(3):
                lo = min(hips[i, leg, a], feet[i, leg, a]) - leg_radius * k
                hi = max(hips[i, leg, a], feet[i, leg, a]) + leg_radius * k
                for c in range(8):
                    out[n, 16 + 8 * leg + c, a] = (lo + hi) / 2 + unit[c, a] * (hi - lo) / 2
    return out


def normals(scene, slot: np.ndarray, part: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Outward unit normals [n, 3] at surface points [n, 3] of the given parts of the persons in ``slot``: from the
    nearest point of the part's axis (the torso's vertical axis at the point's height, the head's centre, the leg's
    segment), vertical on the torso's flat ends."""
    slot, part = np.asarray(slot, np.int64), np.asarray(part, np.int64)
    if len(slot) and (slot.min() < 0 or slot.max() >= len(scene.person_scale)):
        raise ValueError(f"slot must lie in [0, {len(scene.person_scale)})")
    if len(part) and (part.min() < TORSO or part.max() > RIGHT_LEG):
        raise ValueError("part must be one of TORSO, HEAD, LEFT_LEG, RIGHT_LEG")
    return _normals(slot, part, np.ascontiguousarray(points, np.float64), scene.person_scale, scene.person_xy,
                    scene.hips, scene.feet,
                    (body.HEAD_CENTRE, 0.98 * body.TORSO_RADIUS, (body.TORSO_BOTTOM + body.TORSO_TOP) / 2))


@kernel
def _normals(slot, part, points, scale, xy, hips, feet, measures):
    """``normals`` on every slot's values (scale, position, hips and leg ends [n, 2, 3]), read at each point's slot
    (a point's own copies of them cost more to gather than the normals to compute), and the adult body's
    ``measures``: the head's centre, the torso's flat ends' radius and middle height."""
    head_centre, flat_radius, middle = measures
    out = np.empty_like(points)
    for p in range(len(part)):
        x, y, z = points[p, 0], points[p, 1], points[p, 2]  # (unpacking the row itself iterates over it: 6x slower)
        i = slot[p]
        if part[p] == LEFT_LEG or part[p] == RIGHT_LEG:
            a, b = hips[i, part[p] - LEFT_LEG], feet[i, part[p] - LEFT_LEG]
            ex, ey, ez = b[0] - a[0], b[1] - a[1], b[2] - a[2]
            s = ((x - a[0]) * ex + (y - a[1]) * ey + (z - a[2]) * ez) / (ex * ex + ey * ey + ez * ez)
            s = min(max(s, 0.0), 1.0)
            ax, ay, az = a[0] + s * ex, a[1] + s * ey, a[2] + s * ez
        else:
            ax, ay, az = xy[i, 0], xy[i, 1], head_centre * scale[i] if part[p] == HEAD else z
        nx, ny, nz = x - ax, y - ay, z - az
        length = np.sqrt(nx * nx + ny * ny + nz * nz)
        if part[p] == TORSO and length < flat_radius * scale[i]:  # a flat end: straight up or down
            nx, ny, nz = 0.0, 0.0, np.sign(z - middle * scale[i])
            length = 1.0
        length = max(length, 1e-12)
        out[p, 0], out[p, 1], out[p, 2] = nx / length, ny / length, nz / length
    return out


def colours(person_ids: np.ndarray) -> np.ndarray:
    """RGB [n, 4, 3] in [0, 1] of each person's parts in the parts' order: their top, skin, and trousers twice
    (sensors/body.py)."""
    top, trousers = body.clothing(person_ids)
    return np.stack([top, np.broadcast_to(body.SKIN, top.shape), trousers, trousers], 1)
