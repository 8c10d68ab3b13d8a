"""Groups from relation strengths: a graph over the tracks, cut at a strength threshold.

``single`` is SPENCER's (``tracked_groups.py``: single-linkage clustering of 1 - strength cut at 0.5, i.e. the
connected components of the pairs at or above the threshold; the ROS book chapter Sec. 5.2). It chains: a queue of
strangers, each near the next, becomes one group. ``complete`` and ``average`` cluster each connected component
again by complete or average linkage (``agglomerate``), so a group needs every pair (complete) or its pairs on average
(average) at the threshold; a pair missing from the relations has strength 0 there, as in SPENCER.
"""

from __future__ import annotations

import numpy as np

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
    strength) between rows i and j."""
    link = strength >= threshold
    labels = components(n, i[link], j[link])
    if method == "single":
        return labels
    sizes = np.bincount(labels) if n else np.zeros(0, np.int64)
    big = np.flatnonzero(sizes >= 3)
    if not len(big):
        return labels
    distance = np.ones((n, n))
    distance[i, j] = distance[j, i] = 1.0 - strength
    for component in big:
        rows = np.flatnonzero(labels == component)
        parts = agglomerate(distance[np.ix_(rows, rows)], 1.0 - threshold, method)
        labels[rows[parts > 0]] = n + component * n + parts[parts > 0]  # part 0 keeps the component's label
    return np.unique(labels, return_inverse=True)[1] if n else labels


def agglomerate(distance: np.ndarray, cut: float, method: str) -> np.ndarray:
    """Agglomerative clustering of a small distance matrix by complete or average linkage (UPGMA), stopped where
    the closest two clusters are farther than ``cut``: a part per row, 0..k-1. Both linkages never merge at a
    smaller distance than before (no inversions), so stopping there is scipy's ``fcluster(..., criterion=
    "distance")`` of the whole tree, without its checks, which cost ten times the clustering at this size."""
    d = distance.astype(float).copy()
    np.fill_diagonal(d, np.inf)  # a merged-away cluster's row and column become inf too
    k = len(d)
    part, size = np.arange(k), np.ones(k)
    for _ in range(k - 1):
        a, b = divmod(int(np.argmin(d)), k)
        if d[a, b] > cut:
            break
        merged = np.maximum(d[a], d[b]) if method == "complete" else (size[a] * d[a] + size[b] * d[b]) / (
            size[a] + size[b])
        d[a], d[:, a] = merged, merged
        d[b], d[:, b] = np.inf, np.inf
        d[a, a] = np.inf
        size[a] += size[b]
        part[part == b] = a
    return np.unique(part, return_inverse=True)[1]
