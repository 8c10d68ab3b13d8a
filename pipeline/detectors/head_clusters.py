"""Seed 003's people candidates from a point cloud above the ground plane (Munaro & Menegatti Sec. 3, 3.1.1, after
Munaro, Basso & Menegatti 2012): Euclidean clusters, those too high dropped, those close on the ground merged, and a
cluster holding several people split at their heads.

The paper names the steps and one number, 0.3 m between heads (Table 7); the rest are the values of the authors' own
released code (PCL's ground-based people detection): clusters 2 voxels apart (``cluster_tolerance`` may say more:
pipeline/detectors/rgbd.py), 36 to 5,111 points at 6 cm voxels,
cluster centres merged within 0.4 m, people 1.3-2.3 m tall, a height map of 6 cm bins across the image, sub-clusters of
more than 30 points, a head the top eighth of a person.

Points are in the camera's optical frame (x right, y down, z forward); ``plane`` is the ground with its normal up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .point_cloud import euclidean_clusters, plane_distance


@dataclass
class ClusterLimits:
    """The candidate rules' numbers (module docstring), for a voxel grid of ``voxel`` m."""

    voxel: float = 0.06
    cluster_tolerance: float | None = None  # m between neighbours of a cluster; None: two voxels (PCL)
    merge_distance: float = 0.4  # m, between cluster centres on the ground
    min_height: float = 1.3  # m, a person's least height above the ground
    max_height: float = 2.3
    min_width: float = 0.1  # m, with the heights: a cluster's least and most points at this voxel size
    max_width: float = 8.0
    head_distance: float = 0.3  # m, least distance between two people's heads (seed 003 Table 7)
    bin_size: float = 0.06  # m, the height map's bins across the image
    min_subcluster: int = 30  # points

    @property
    def tolerance(self) -> float:
        return 2 * self.voxel if self.cluster_tolerance is None else self.cluster_tolerance

    @property
    def point_range(self) -> tuple[int, int]:
        area = self.voxel * self.voxel
        return int(self.min_height * self.min_width / area), int(self.max_height * self.max_width / area)


def candidates(points: np.ndarray, plane: np.ndarray, limits: ClusterLimits = ClusterLimits(),
               split: bool = True) -> list[np.ndarray]:
    """The point indices of each person candidate among ``points`` (the ground already removed): clusters, merged
    when their centres are within ``merge_distance`` on the ground, of a person's height, and (with ``split``) each
    split at its heads."""
    least, most = limits.point_range
    clusters = euclidean_clusters(points, limits.tolerance, least, most)
    clusters = merge_close(points, plane, clusters, limits.merge_distance)
    heights = plane_distance(points, plane)
    out = []
    for cluster in clusters:
        top = heights[cluster].max()
        if not limits.min_height <= top <= limits.max_height:
            continue
        if split and len(cluster) > 1.5 * limits.min_subcluster:
            out += subclusters(points[cluster], heights[cluster], plane, limits, cluster)
        else:
            out.append(cluster)
    return out


def on_ground(points: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """The points dropped onto the plane along its normal."""
    return points - plane_distance(points, plane)[:, None] * plane[:3]


def merge_close(points: np.ndarray, plane: np.ndarray, clusters: list[np.ndarray], distance: float) -> list:
    """Clusters whose centroids lie within ``distance`` of each other on the ground joined (transitively)."""
    if len(clusters) < 2:
        return clusters
    centres = on_ground(np.array([points[c].mean(axis=0) for c in clusters]), plane)
    near = np.linalg.norm(centres[:, None] - centres[None], axis=2) < distance
    group = np.arange(len(clusters))
    for _ in range(len(clusters)):  # label propagation to the least index of each connected set
        group = np.where(near, group[None], len(clusters)).min(axis=1)
    return [np.concatenate([clusters[k] for k in np.flatnonzero(group == g)]) for g in np.unique(group)]


def heads(points: np.ndarray, heights: np.ndarray, plane: np.ndarray, limits: ClusterLimits) -> np.ndarray:
    """Indices of the points at the heads of a cluster: the local maxima of its height map (the highest point of
    each ``bin_size`` bin across the image), highest first, each at least ``head_distance`` on the ground from every
    higher one kept."""
    bins = np.floor(points[:, 0] / limits.bin_size).astype(np.int64)
    bins -= bins.min()
    top = np.full(bins.max() + 1, -np.inf)
    np.maximum.at(top, bins, heights)
    padded = np.concatenate([[-np.inf], top, [-np.inf]])
    peaks = np.flatnonzero((top > padded[:-2]) & (top >= padded[2:]) & np.isfinite(top))
    owner = np.lexsort((-heights, bins))  # per bin, its highest point first
    first = np.searchsorted(bins[owner], peaks)
    candidates_ = owner[first][np.argsort(-top[peaks], kind="stable")]
    ground = on_ground(points, plane)
    kept: list[int] = []
    for k in candidates_.tolist():
        if all(np.linalg.norm(ground[k] - ground[j]) >= limits.head_distance for j in kept):
            kept.append(k)
    return np.array(kept, np.int64)


def subclusters(points: np.ndarray, heights: np.ndarray, plane: np.ndarray, limits: ClusterLimits,
                index: np.ndarray) -> list[np.ndarray]:
    """A cluster split at its heads (``heads``): each point goes to the nearest head on the ground if it is within
    ``head_distance`` (PCL gives it to the highest such head, which takes a shorter neighbour's near side); points
    near no head are left out, and so are sub-clusters of ``min_subcluster`` points or fewer. ``index`` maps the
    cluster's points to the cloud's."""
    top = heads(points, heights, plane, limits)
    if len(top) <= 1:
        return [index]
    ground = on_ground(points, plane)
    distance = np.linalg.norm(ground[:, None] - ground[top][None], axis=2)
    nearest = distance.argmin(axis=1)
    owner = np.where(distance[np.arange(len(points)), nearest] < limits.head_distance, nearest, -1)
    return [index[owner == k] for k in range(len(top)) if (owner == k).sum() > limits.min_subcluster]
