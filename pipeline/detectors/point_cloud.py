"""The point-cloud steps of seed 003's RGB-D people detector (Munaro & Menegatti, Sec. 3): a voxel grid, the ground
plane by RANSAC, and Euclidean clusters, each in numpy and scipy over whole arrays (the PCL classes the paper uses,
VoxelGrid, SACSegmentation and EuclideanClusterExtraction, do the same point by point in C++).

Points are [n, 3] in any metric frame; a plane is (a, b, c, d) with a x + b y + c z + d = 0 and (a, b, c) a unit
normal.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree


def voxel_grid(points: np.ndarray, leaf: float) -> np.ndarray:
    """The centroid of the points in each occupied cube of side ``leaf`` (PCL's VoxelGrid), in the order of the
    cubes' integer coordinates."""
    points = np.asarray(points, float).reshape(-1, 3)
    if not len(points):
        return points
    cells = np.floor(points / leaf).astype(np.int64)
    cells -= cells.min(axis=0)
    span = cells.max(axis=0) + 1
    keys = (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]  # one integer a cube, in the same order
    _, index, counts = np.unique(keys, return_inverse=True, return_counts=True)
    sums = np.stack([np.bincount(index, points[:, k], minlength=len(counts)) for k in range(3)], axis=1)
    return sums / counts[:, None]


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


def euclidean_clusters(points: np.ndarray, tolerance: float, min_size: int = 1,
                       max_size: int | None = None) -> list[np.ndarray]:
    """The point indices of each cluster (PCL's EuclideanClusterExtraction): the connected components of the graph
    joining points nearer than ``tolerance``, those of ``min_size`` to ``max_size`` points, largest first."""
    points = np.asarray(points, float).reshape(-1, 3)
    n = len(points)
    if not n:
        return []
    pairs = cKDTree(points).query_pairs(tolerance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    count, labels = connected_components(graph, directed=False)
    order = np.argsort(labels, kind="stable")
    sizes = np.bincount(labels, minlength=count)
    groups = np.split(order, np.cumsum(sizes)[:-1])
    keep = [g for g in groups if len(g) >= min_size and (max_size is None or len(g) <= max_size)]
    return sorted(keep, key=len, reverse=True)
