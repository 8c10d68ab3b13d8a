"""Groups from relation strengths: a graph over the tracks, cut at a strength threshold.

``single`` is SPENCER's (``tracked_groups.py``: single-linkage clustering of 1 - strength cut at 0.5, i.e. the
connected components of the pairs at or above the threshold; the ROS book chapter Sec. 5.2). It chains: a queue of
strangers, each near the next, becomes one group. ``complete`` and ``average`` cluster each connected component
again by complete or average linkage (scipy's), so a group needs every pair (complete) or its pairs on average
(average) at the threshold; a pair missing from the relations has strength 0 there, as in SPENCER.
"""

from __future__ import annotations

import numpy as np
from scipy.cluster.hierarchy import fcluster, linkage

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
    if method == "single" or n < 3:
        return labels
    sizes = np.bincount(labels)
    out, next_label = labels.copy(), labels.max() + 1 if n else 0
    for component in np.flatnonzero(sizes >= 3):
        rows = np.flatnonzero(labels == component)
        distance = np.ones((len(rows), len(rows)))
        inside = np.isin(i, rows) & np.isin(j, rows)
        a, b = np.searchsorted(rows, i[inside]), np.searchsorted(rows, j[inside])
        distance[a, b] = distance[b, a] = 1.0 - strength[inside]
        condensed = distance[np.triu_indices(len(rows), 1)]
        parts = fcluster(linkage(condensed, method=method), 1.0 - threshold, criterion="distance")
        out[rows] = np.where(parts == 1, component, next_label + parts - 2)
        next_label += parts.max() - 1
    return np.unique(out, return_inverse=True)[1]
