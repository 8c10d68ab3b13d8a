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
    # the rows of every component of three or more, clustered together: a pair of two components is below the
    # threshold, so no linkage joins them
    rows = np.flatnonzero(np.isin(labels, big))
    at = np.full(n, -1)
    at[rows] = np.arange(len(rows))
    keep = (at[i] >= 0) & (at[j] >= 0)
    distance = np.ones((len(rows), len(rows)))
    distance[at[i[keep]], at[j[keep]]] = distance[at[j[keep]], at[i[keep]]] = 1.0 - strength[keep]
    labels[rows] = n + agglomerate(distance, 1.0 - threshold, method)
    return np.unique(labels, return_inverse=True)[1]


def agglomerate(distance: np.ndarray, cut: float, method: str) -> np.ndarray:
    """Agglomerative clustering of a small distance matrix by complete or average linkage (UPGMA), stopped where
    the closest two clusters are farther than ``cut``: a part per row, 0..k-1. Each step merges every pair of
    clusters that are each other's nearest within ``cut`` at once: both linkages are reducible (a merge never brings
    a third cluster nearer), so the tree is the one merging a pair at a time builds (the nearest-neighbour chain's
    argument, Murtagh 1983), in a few steps instead of one per merge; and both never merge at a smaller distance
    than before, so stopping at ``cut`` is scipy's ``fcluster(..., criterion="distance")`` of the whole tree."""
    d = distance.astype(float).copy()
    np.fill_diagonal(d, np.inf)  # a merged-away cluster's row and column become inf too
    k = len(d)
    part, size, rows = np.arange(k), np.ones(k), np.arange(k)
    while True:
        nearest = np.argmin(d, axis=1)
        a = np.flatnonzero((nearest[nearest] == rows) & (rows < nearest) & (d[rows, nearest] <= cut))
        if not len(a):
            break
        b = nearest[a]
        # rows, then columns: for disjoint pairs this is the linkage over the four blocks
        if method == "complete":
            d[a] = np.maximum(d[a], d[b])
            d[:, a] = np.maximum(d[:, a], d[:, b])
        else:
            w = (size[a] / (size[a] + size[b]))[:, None]
            d[a] = w * d[a] + (1 - w) * d[b]
            d[:, a] = w.T * d[:, a] + (1 - w.T) * d[:, b]
        d[b], d[:, b], d[a, a] = np.inf, np.inf, np.inf
        size[a] += size[b]
        relabel = np.arange(k)
        relabel[b] = a
        part = relabel[part]
    return np.unique(part, return_inverse=True)[1]
