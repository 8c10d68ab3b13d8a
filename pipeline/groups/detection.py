"""Groups from relation strengths: a graph over the tracks, cut at a strength threshold.

``single`` is SPENCER's (``tracked_groups.py``: single-linkage clustering of 1 - strength cut at 0.5, i.e. the
connected components of the pairs at or above the threshold; the ROS book chapter Sec. 5.2). It chains: a queue of
strangers, each near the next, becomes one group. ``complete`` and ``average`` cut the tree of complete or average
linkage (scipy's ``linkage``, cut by ``cut_tree``) at the same height, so a group needs every pair (complete) or its
pairs on average (average) at the threshold; a pair missing from the relations has strength 0 there, as in SPENCER.
"""

from __future__ import annotations

import numpy as np
from scipy.cluster.hierarchy import linkage

from .relations import pairs

LINKAGES = ("single", "complete", "average")


def components(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Connected components of the graph of ``n`` nodes and edges (a, b), labelled 0..k-1 in the order of their
    smallest node: each node takes the least label among its neighbours', with pointer jumping, until none changes
    (a few passes for the small chains of a crowd; scipy's csgraph costs more in checking its input at this size)."""
    labels = np.arange(n)
    while len(a):
        least = np.minimum(labels[a], labels[b])
        new = labels.copy()
        np.minimum.at(new, a, least)
        np.minimum.at(new, b, least)
        new = new[new]
        if np.array_equal(new, labels):
            break
        labels = new
    return np.unique(labels, return_inverse=True)[1]


def detect_groups(n: int, i: np.ndarray, j: np.ndarray, strength: np.ndarray, threshold: float = 0.5,
                  method: str = "single") -> np.ndarray:
    """A cluster label per track (rows 0..n-1; labels 0..k-1, singletons included) from the relations (i, j,
    strength) between rows i < j."""
    link = strength >= threshold
    if method == "single":
        return components(n, i[link], j[link])
    # the rows with any pair at the threshold, clustered together: that is the tree of each connected component
    # cut at the same height, as two clusters of two components are farther apart than the cut whatever the linkage
    linked = np.zeros(n, bool)
    linked[i[link]] = linked[j[link]] = True
    rows = np.flatnonzero(linked)
    labels = np.empty(n, np.int64)
    parts = 0
    if len(rows):
        related = np.zeros(n * n)  # row-major [n, n], filled above the diagonal; flat indices cost a third of pairs
        related[i * n + j] = strength
        p, q = pairs(len(rows))
        labels[rows] = cut_tree(linkage(1.0 - related[rows[p] * n + rows[q]], method), 1.0 - threshold)
        parts = labels[rows].max() + 1
    labels[~linked] = parts + np.arange(n - len(rows))  # the rest alone
    return labels


def cut_tree(merges: np.ndarray, cut: float) -> list[int]:
    """The flat clusters (a part per leaf) of a linkage tree (scipy's ``linkage`` rows: a, b, distance, size) whose
    merges are at most ``cut`` apart: scipy's ``fcluster(..., criterion="distance")`` for the linkages whose merge
    distances never decrease (complete, average), without its checks, which cost three times the linkage itself at
    a crowd's size."""
    k = len(merges) + 1
    clusters = {leaf: [leaf] for leaf in range(k)}
    for node, (a, b) in enumerate(merges[merges[:, 2] <= cut, :2].astype(np.int64).tolist(), start=k):
        clusters[node] = clusters.pop(a) + clusters.pop(b)
    part = [0] * k
    for label, leaves in enumerate(clusters.values()):
        for leaf in leaves:
            part[leaf] = label
    return part
