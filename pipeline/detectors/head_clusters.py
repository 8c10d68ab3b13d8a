"""Seed 003's people candidates from a point cloud above the ground plane (Munaro & Menegatti Sec. 3, 3.1.1, after
Munaro, Basso & Menegatti 2012): Euclidean clusters, those too high dropped, those close on the ground merged, and a
cluster holding several people split at their heads.

The paper names the steps and one number, 0.3 m between heads (Table 7); the rest are the values of the authors' own
released code (PCL's ground-based people detection): clusters 2 voxels apart (``cluster_tolerance`` may say more:
pipeline/detectors/rgbd.py), 36 to 5,111 points at 6 cm voxels,
cluster centres merged within 0.4 m, people 1.3-2.3 m tall, a height map of 6 cm bins across the image, sub-clusters of
more than 30 points, a head the top eighth of a person.

Points are in the camera's optical frame (x right, y down, z forward); ``plane`` is the ground with its normal up.

The merging of close clusters, the height map's heads and the points' assignment to them are kernels: a frame has a
few clusters of a few hundred points, where numpy's sorts and reductions cost their call overhead (a replay's profile:
0.2 ms a cluster split). Distances are summed x, y, z, as numpy's norm sums them; the ground points and heights stay
numpy's own (``on_ground``, ``plane_distance``: their matrix products round as the BLAS does), the kernels take them as
they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.compiled import by_label, kernel

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
    sizes = np.array([len(c) for c in clusters])
    centres = on_ground(_centroids(points, np.concatenate(clusters), sizes), plane)
    group = _close_sets(centres, distance)
    return [np.concatenate([clusters[k] for k in np.flatnonzero(group == g)]) for g in np.unique(group)]


@kernel
def _centroids(points, members, sizes):
    """The mean point of each of the clusters ``members`` holds one after another, ``sizes`` points each (summed in
    order, as numpy's mean along the first axis)."""
    centres, at = np.zeros((len(sizes), 3)), 0
    for c in range(len(sizes)):
        for i in members[at:at + sizes[c]]:
            for k in range(3):
                centres[c, k] += points[i, k]
        for k in range(3):
            centres[c, k] /= sizes[c]
        at += sizes[c]
    return centres


@kernel
def _close_sets(centres, distance):
    """The least index of each centre's connected set, centres joined when nearer than ``distance``: labels
    propagated all at once, as many rounds as there are centres."""
    n = len(centres)
    near = np.empty((n, n), np.bool_)
    for i in range(n):
        for j in range(n):
            dx, dy, dz = centres[i, 0] - centres[j, 0], centres[i, 1] - centres[j, 1], centres[i, 2] - centres[j, 2]
            near[i, j] = np.sqrt(dx * dx + dy * dy + dz * dz) < distance
    group = np.arange(n)
    for _ in range(n):
        least = np.full(n, n)
        for i in range(n):
            for j in range(n):
                if near[i, j]:
                    least[i] = min(least[i], group[j])
        group = least
    return group


def heads(points: np.ndarray, heights: np.ndarray, plane: np.ndarray, limits: ClusterLimits,
          ground: np.ndarray | None = None) -> np.ndarray:
    """Indices of the points at the heads of a cluster: the local maxima of its height map (the highest point of
    each ``bin_size`` bin across the image, the first of equals), highest first (equals in the order of their bins),
    each at least ``head_distance`` on the ground from every higher one kept. ``ground``: the points' ``on_ground``,
    when the caller has them."""
    ground = on_ground(points, plane) if ground is None else ground
    return _heads(np.ascontiguousarray(points[:, 0]), heights, ground, limits.bin_size, limits.head_distance)


@kernel
def _heads(across, heights, ground, bin_size, head_distance):
    """``heads`` of the points at ``across`` (x in the image) with ``heights`` and ``ground`` points."""
    bins = np.floor(across / bin_size).astype(np.int64)
    bins -= bins.min()
    top, highest = np.full(bins.max() + 1, -np.inf), np.full(bins.max() + 1, -1)
    for i in range(len(bins)):
        if heights[i] > top[bins[i]]:
            top[bins[i]], highest[bins[i]] = heights[i], i
    peaks, count = np.empty(len(top), np.int64), 0  # highest first, equals in bin order (an insertion sort)
    for b in range(len(top)):
        if np.isfinite(top[b]) and (b == 0 or top[b] > top[b - 1]) and (b == len(top) - 1 or top[b] >= top[b + 1]):
            at = count
            while at and top[peaks[at - 1]] < top[b]:
                peaks[at] = peaks[at - 1]
                at -= 1
            peaks[at], count = b, count + 1
    kept, count_kept = np.empty(count, np.int64), 0
    for b in peaks[:count]:
        k = highest[b]
        for j in kept[:count_kept]:
            dx, dy, dz = ground[k, 0] - ground[j, 0], ground[k, 1] - ground[j, 1], ground[k, 2] - ground[j, 2]
            if not np.sqrt(dx * dx + dy * dy + dz * dz) >= head_distance:
                break
        else:
            kept[count_kept], count_kept = k, count_kept + 1
    return kept[:count_kept]


def subclusters(points: np.ndarray, heights: np.ndarray, plane: np.ndarray, limits: ClusterLimits,
                index: np.ndarray) -> list[np.ndarray]:
    """A cluster split at its heads (``heads``): each point goes to the nearest head on the ground (the first of
    equals) if it is within ``head_distance`` (PCL gives it to the highest such head, which takes a shorter
    neighbour's near side); points near no head are left out, and so are sub-clusters of ``min_subcluster`` points or
    fewer. ``index`` maps the cluster's points to the cloud's."""
    ground = on_ground(points, plane)
    top = heads(points, heights, plane, limits, ground)
    if len(top) <= 1:
        return [index]
    start, members = _nearest_head(ground, top, limits.head_distance)
    return [index[members[start[k]:start[k + 1]]] for k in range(len(top))
            if start[k + 1] - start[k] > limits.min_subcluster]


@kernel
def _nearest_head(ground, top, head_distance):
    """The points of each head's sub-cluster (``subclusters``) as ``by_label`` gives them."""
    owner = np.full(len(ground), -1)
    for i in range(len(ground)):
        nearest, least = 0, np.inf
        for k in range(len(top)):
            head = ground[top[k]]
            dx, dy, dz = ground[i, 0] - head[0], ground[i, 1] - head[1], ground[i, 2] - head[2]
            distance = np.sqrt(dx * dx + dy * dy + dz * dz)
            if distance < least:
                nearest, least = k, distance
        if least < head_distance:
            owner[i] = nearest
    return by_label(owner, len(top))
