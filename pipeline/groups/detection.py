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
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

LINKAGES = ("single", "complete", "average")


def detect_groups(n: int, i: np.ndarray, j: np.ndarray, strength: np.ndarray, threshold: float = 0.5,
                  method: str = "single") -> np.ndarray:
    """A cluster label per track (rows 0..n-1; labels 0..k-1, singletons included) from the relations (i, j,
    strength) between rows i and j."""
    link = strength >= threshold
    graph = coo_matrix((np.ones(int(link.sum())), (i[link], j[link])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
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
