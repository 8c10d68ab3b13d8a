"""The point-cloud steps of seed 003's RGB-D people detector (Munaro & Menegatti, Sec. 3): a voxel grid, the ground
plane by RANSAC, and Euclidean clusters (the PCL classes the paper uses, VoxelGrid, SACSegmentation and
EuclideanClusterExtraction). The voxel grid and the clusters are kernels: at a few thousand points a frame, numpy's
unique and scipy's k-d tree and sparse graph cost their call overhead many times over (a replay's profile: 63% of the
detector's time).

Points are [n, 3] in any metric frame; a plane is (a, b, c, d) with a x + b y + c z + d = 0 and (a, b, c) a unit
normal.
"""

from __future__ import annotations

import numpy as np

from pipeline.compiled import by_label, kernel, union_root


@kernel
def _cell_keys(points, side):
    """One integer a cube of side ``side`` holding each point, in the order of the cubes' integer coordinates (x,
    then y, then z); and the key steps of one cube along x and y."""
    n = len(points)
    cells = np.empty((n, 3), np.int64)
    for i in range(n):
        for k in range(3):
            cells[i, k] = np.int64(np.floor(points[i, k] / side))
    low, high = cells[0].copy(), cells[0].copy()
    for i in range(1, n):
        for k in range(3):
            low[k], high[k] = min(low[k], cells[i, k]), max(high[k], cells[i, k])
    span_y, span_z = high[1] - low[1] + 1, high[2] - low[2] + 1
    if (high[0] - low[0] + 1.0) * span_y * span_z > 2.0 ** 62:
        raise ValueError("the points spread over too many cubes for one 64-bit key a cube")
    keys = np.empty(n, np.int64)
    for i in range(n):
        keys[i] = ((cells[i, 0] - low[0]) * span_y + cells[i, 1] - low[1]) * span_z + cells[i, 2] - low[2]
    return keys, span_y * span_z, span_z


@kernel
def _sorted_order(keys):
    """The order that sorts the non-negative ``keys`` stably: a least-significant-digit radix sort, a counting sort
    of 11 bits a pass (on a frame's 19,000 voxel keys: 0.1 ms, numpy's stable argsort 0.4, numba's 0.9)."""
    order, spare = np.arange(len(keys)), np.empty(len(keys), np.int64)
    top, shift = keys.max(), 0
    while shift == 0 or (shift < 63 and top >> shift > 0):
        counts = np.zeros(2049, np.int64)
        for i in order:
            counts[((keys[i] >> shift) & 2047) + 1] += 1
        for d in range(2048):
            counts[d + 1] += counts[d]
        for i in order:
            digit = (keys[i] >> shift) & 2047
            spare[counts[digit]] = i
            counts[digit] += 1
        order, spare = spare, order
        shift += 11
    return order


@kernel
def _voxel_centroids(points, leaf):
    """The centroids of ``voxel_grid``: the cubes in key order, each one's sums in the order of its points (as
    numpy's unique and bincount give them)."""
    keys = _cell_keys(points, leaf)[0]
    order = _sorted_order(keys)
    cubes = 1
    for i in range(1, len(order)):
        cubes += keys[order[i]] != keys[order[i - 1]]
    sums, counts = np.zeros((cubes, 3)), np.zeros(cubes, np.int64)
    cube = 0
    for i in range(len(order)):
        if i and keys[order[i]] != keys[order[i - 1]]:
            cube += 1
        for k in range(3):
            sums[cube, k] += points[order[i], k]
        counts[cube] += 1
    for c in range(cubes):
        for k in range(3):
            sums[c, k] /= counts[c]
    return sums


def voxel_grid(points: np.ndarray, leaf: float) -> np.ndarray:
    """The centroid of the points in each occupied cube of side ``leaf`` (PCL's VoxelGrid), in the order of the
    cubes' integer coordinates."""
    points = np.ascontiguousarray(points, float).reshape(-1, 3)
    if not len(points):
        return points
    return _voxel_centroids(points, float(leaf))


def plane_distance(points: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """Signed distances [n] of the points from the plane (positive on its normal's side)."""
    return np.asarray(points, float) @ plane[:3] + plane[3]


def fit_plane(points: np.ndarray) -> np.ndarray:
    """The least-squares plane through the points (the normal is the direction of least spread)."""
    centre = points.mean(axis=0)
    normal = np.linalg.svd(points - centre, full_matrices=False)[2][-1]
    return np.append(normal, -normal @ centre)


def ransac_plane(points: np.ndarray, threshold: float, rng: np.random.Generator, iterations: int = 100,
                 up: np.ndarray | None = None, max_tilt: float = np.pi) -> tuple[np.ndarray | None, np.ndarray]:
    """RANSAC (Fischler & Bolles 1981): of ``iterations`` planes through 3 random points, the one with the most
    points within ``threshold``, refitted to them by least squares. With ``up``, the normal is turned to point along
    it and planes tilted more than ``max_tilt`` from it are not considered (a floor, not a wall). Returns the plane
    (None when no candidate is acceptable) and its inlier mask."""
    points = np.asarray(points, float).reshape(-1, 3)
    n = len(points)
    if n < 3:
        return None, np.zeros(n, bool)
    triples = points[rng.integers(0, n, (iterations, 3))]
    normals = np.cross(triples[:, 1] - triples[:, 0], triples[:, 2] - triples[:, 0])
    length = np.linalg.norm(normals, axis=1)
    ok = length > 1e-12
    normals = normals[ok] / length[ok, None]
    offsets = -np.einsum("ij,ij->i", normals, triples[ok, 0])
    if up is not None:
        flip = normals @ up < 0
        normals[flip], offsets[flip] = -normals[flip], -offsets[flip]
        keep = normals @ up >= np.cos(max_tilt)
        normals, offsets = normals[keep], offsets[keep]
    if not len(normals):
        return None, np.zeros(n, bool)
    support = (np.abs(points @ normals.T + offsets) <= threshold).sum(axis=0)
    best = int(support.argmax())
    inliers = np.abs(points @ normals[best] + offsets[best]) <= threshold
    plane = fit_plane(points[inliers])
    if up is not None and plane[:3] @ up < 0:
        plane = -plane
    return plane, np.abs(plane_distance(points, plane)) <= threshold


@kernel
def _clusters(points, tolerance, min_size, max_size):
    """``euclidean_clusters``' clusters as (start, order, kept): cluster c is ``order[start[c]:start[c + 1]]``, and
    ``kept`` the clusters to return, in their order.

    The points go into cubes a little smaller than ``tolerance`` / sqrt(3), so that the points of a cube are all
    joined and a pair of joined points is at most two cubes apart along each axis; two cubes are joined (union-find)
    by the first pair of their points found within the tolerance, tested as scipy's cKDTree.query_pairs tests it
    (the squared distance, summed x, y, z, at most the squared tolerance), and not tested once they are joined. The
    millionth left as margin is far above the rounding in a point's cube."""
    n = len(points)
    keys, step_x, step_y = _cell_keys(points, tolerance * (1 - 1e-6) / np.sqrt(3.0))
    order = _sorted_order(keys)
    by_cube = points[order]
    first, cube_of, cubes = np.empty(n + 1, np.int64), np.empty(n, np.int64), 0  # in ``order``: each cube's start
    for s in range(n):
        if s == 0 or keys[order[s]] != keys[order[s - 1]]:
            first[cubes], cubes = s, cubes + 1
        cube_of[order[s]] = cubes - 1
    first[cubes] = n
    cube_keys = keys[order[first[:cubes]]]
    # the key offsets of the columns of cubes within two along x and y; each column runs from -2 to +2 along z. Those
    # that can only hold cubes of lower key are left out: each pair of cubes is looked at from its lower key
    columns, count = np.empty(25, np.int64), 0
    for dx in range(-2, 3):
        for dy in range(-2, 3):
            column = dx * step_x + dy * step_y
            if column + 2 > 0 and not (columns[:count] == column).any():  # (columns coincide when a span is short)
                columns[count], count = column, count + 1
    columns = columns[:count]
    parent, limit = np.arange(cubes), tolerance * tolerance
    lowest = np.zeros(len(columns), np.int64)  # per column, the first cube at or past its start: rises with a
    for a in range(cubes):
        root_a = union_root(parent, a)  # only a's set grows while a's neighbours are looked at: its root is kept here
        for k in range(len(columns)):
            while lowest[k] < cubes and cube_keys[lowest[k]] < cube_keys[a] + max(columns[k] - 2, 1):
                lowest[k] += 1
            b = lowest[k]
            while b < cubes and cube_keys[b] <= cube_keys[a] + columns[k] + 2:
                root_b = union_root(parent, b)
                if root_b != root_a and _touch(by_cube, first[a], first[a + 1], first[b], first[b + 1], limit):
                    parent[max(root_a, root_b)] = min(root_a, root_b)
                    root_a = min(root_a, root_b)
                b += 1
    labels, label_of, count = np.empty(n, np.int64), np.full(cubes, -1), 0
    for i in range(n):  # numbered by their lowest point, as scipy's connected_components numbers them
        root = union_root(parent, cube_of[i])
        if label_of[root] < 0:
            label_of[root], count = count, count + 1
        labels[i] = label_of[root]
    start, members = by_label(labels, count)
    kept = np.array([c for c in range(count) if min_size <= start[c + 1] - start[c] <= max_size], np.int64)
    if len(kept):  # largest first, equals in label order (a stable sort)
        kept = kept[_sorted_order(n - (start[kept + 1] - start[kept]))]
    return start, members, kept


@kernel
def _touch(points, a0, a1, b0, b1, limit):
    """Whether a point of ``points[a0:a1]`` and one of ``points[b0:b1]`` are at most sqrt(``limit``) apart."""
    for s in range(a0, a1):
        for t in range(b0, b1):
            dx, dy, dz = points[s, 0] - points[t, 0], points[s, 1] - points[t, 1], points[s, 2] - points[t, 2]
            if dx * dx + dy * dy + dz * dz <= limit:
                return True
    return False


def euclidean_clusters(points: np.ndarray, tolerance: float, min_size: int = 1,
                       max_size: int | None = None) -> list[np.ndarray]:
    """The point indices of each cluster (PCL's EuclideanClusterExtraction), each in increasing order: the connected
    components of the graph joining points at most ``tolerance`` apart, those of ``min_size`` to ``max_size``
    points, largest first (equal sizes in the order of their lowest index). The points must be finite, and span
    fewer than 2^62 cubes of side ``tolerance`` / sqrt(3) (at 0.15 m: 140 km along each axis of a cube-shaped cloud)."""
    points = np.ascontiguousarray(points, float).reshape(-1, 3)
    if not np.isfinite(points).all():
        raise ValueError("data must be finite, check for nan or inf values")
    if not len(points):
        return []
    start, order, kept = _clusters(points, float(tolerance), min_size, len(points) if max_size is None else max_size)
    return [order[start[c]:start[c + 1]] for c in kept.tolist()]
