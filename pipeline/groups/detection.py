"""Groups from relation strengths: a graph over the tracks, cut at a strength threshold.

``single`` is SPENCER's (``tracked_groups.py``: single-linkage clustering of 1 - strength cut at 0.5, i.e. the
connected components of the pairs at or above the threshold; the ROS book chapter Sec. 5.2). It chains: a queue of
strangers, each near the next, becomes one group. ``complete`` and ``average`` cut the tree of complete or average
linkage (scipy's ``linkage``, whose nearest-neighbour chain ``nn_chain`` repeats, tie for tie) at the same height,
so a group needs every pair (complete) or its pairs on average (average) at the threshold; a pair missing from the
relations has strength 0 there, as in SPENCER.
"""

from __future__ import annotations

import math

import numpy as np

from pipeline.compiled import kernel

LINKAGES = ("single", "complete", "average")


@kernel
def components(n, a, b):
    """Connected components of the graph of ``n`` nodes and edges (a, b), labelled 0..k-1 in the order of their
    smallest node: a union-find whose root is always its set's smallest node (with path halving), so a root is met
    before the rest of its set (scipy's csgraph costs more in checking its input at a crowd's size)."""
    parent = np.arange(n)
    for e in range(len(a)):
        x, y = _root(parent, a[e]), _root(parent, b[e])
        if x < y:
            parent[y] = x
        elif y < x:
            parent[x] = y
    labels = np.empty(n, np.int64)
    k = 0
    for v in range(n):
        r = _root(parent, v)
        if r == v:
            labels[v] = k
            k += 1
        else:
            labels[v] = labels[r]
    return labels


@kernel
def _root(parent, v):
    """The root of node ``v``, each node on the way pointed at its grandparent."""
    while parent[v] != v:
        parent[v] = parent[parent[v]]
        v = parent[v]
    return v


def detect_groups(n: int, i: np.ndarray, j: np.ndarray, strength: np.ndarray, threshold: float = 0.5,
                  method: str = "single") -> np.ndarray:
    """A cluster label per track (rows 0..n-1; labels 0..k-1, singletons included) from the relations (i, j,
    strength) between rows i < j."""
    if method not in LINKAGES:
        raise ValueError(f"method: expected one of {', '.join(LINKAGES)}, got {method!r}")
    if method == "single":
        link = strength >= threshold
        return components(n, i[link], j[link])
    return _linkage_groups(n, np.ascontiguousarray(i, np.int64), np.ascontiguousarray(j, np.int64),
                           np.ascontiguousarray(strength, np.float64), float(threshold), method == "average")


@kernel
def _linkage_groups(n, i, j, strength, threshold, average):
    """``detect_groups`` for complete (else ``average``) linkage. The rows with any pair at the threshold are
    clustered together: that is the tree of each connected component cut at the same height, as two clusters of
    two components are farther apart than the cut whatever the linkage. Their clusters are numbered as the cut of
    scipy's tree numbers them (``cut``), the rows left alone after them, in row order."""
    related = np.zeros((n, n))  # filled above the diagonal, 0 where a pair is missing
    linked = np.zeros(n, np.bool_)
    for e in range(len(i)):
        related[i[e], j[e]] = strength[e]
        if strength[e] >= threshold:
            linked[i[e]] = linked[j[e]] = True
    rows = np.empty(n, np.int64)
    count = 0
    for v in range(n):
        if linked[v]:
            rows[count] = v
            count += 1
    rows = rows[:count]
    m = len(rows)  # (not ``count``: numba types it as the literal 0 first and would compile the calls twice)
    labels = np.empty(n, np.int64)
    parts = 0
    if m:
        distance = np.empty(m * (m - 1) // 2)  # scipy's condensed matrix, pairs p < q in row-major order
        k = 0
        for p in range(m):
            for q in range(p + 1, m):
                distance[k] = 1.0 - related[rows[p], rows[q]]
                if not math.isfinite(distance[k]):
                    raise ValueError("relation strengths: expected finite values (complete and average linkage)")
                k += 1
        first, second, height = nn_chain(distance, m, average)
        part = cut(first, second, height, m, 1.0 - threshold)
        for p in range(m):
            labels[rows[p]] = part[p]
            parts = max(parts, part[p] + 1)
    for v in range(n):
        if not linked[v]:
            labels[v] = parts
            parts += 1
    return labels


@kernel
def _condensed(n, a, b):
    """The place of the pair (a, b), a != b, of ``n`` in a condensed distance matrix."""
    if a > b:
        a, b = b, a
    return n * a - a * (a + 1) // 2 + (b - a - 1)


@kernel
def nn_chain(distance, n, average):
    """The merges of complete (else ``average``) linkage on the condensed ``distance`` matrix of ``n`` points, as
    scipy's ``linkage`` finds them (its ``_hierarchy.nn_chain``: the same scan order and strict comparisons, so ties
    break alike, and the same Lance-Williams updates): x < y, the points standing for the two clusters merged, and
    the height, in ascending height (a stable sort of the chain's order, as scipy's)."""
    d = distance.copy()
    size = np.ones(n, np.int64)
    chain = np.empty(n, np.int64)
    length = 0
    first, second, height = np.empty(n - 1, np.int64), np.empty(n - 1, np.int64), np.empty(n - 1)
    x = y = 0
    for k in range(n - 1):
        if length == 0:
            length = 1
            for v in range(n):
                if size[v] > 0:
                    chain[0] = v
                    break
        while True:  # along the chain of nearest neighbours until two are each other's
            x = chain[length - 1]
            if length > 1:  # the previous one first, so that the chain does not cycle among equals
                y = chain[length - 2]
                nearest = d[_condensed(n, x, y)]
            else:
                nearest = np.inf
            for v in range(n):
                if size[v] > 0 and v != x and d[_condensed(n, x, v)] < nearest:
                    nearest, y = d[_condensed(n, x, v)], v
            if length > 1 and y == chain[length - 2]:
                break
            chain[length] = y
            length += 1
        length -= 2
        if x > y:
            x, y = y, x
        nx, ny = size[x], size[y]
        first[k], second[k], height[k] = x, y, nearest
        size[x], size[y] = 0, nx + ny  # y stands for the merged cluster
        for v in range(n):
            if size[v] > 0 and v != y:
                dx, dy = d[_condensed(n, v, x)], d[_condensed(n, v, y)]
                d[_condensed(n, v, y)] = (nx * dx + ny * dy) / (nx + ny) if average else max(dx, dy)
    for k in range(1, n - 1):  # an insertion sort: stable, and the chain's heights come nearly in order
        a, b, h = first[k], second[k], height[k]
        p = k
        while p > 0 and height[p - 1] > h:
            first[p], second[p], height[p] = first[p - 1], second[p - 1], height[p - 1]
            p -= 1
        first[p], second[p], height[p] = a, b, h
    return first, second, height


@kernel
def cut(first, second, height, n, at):
    """The flat clusters (a part per point) of the merges (``nn_chain``'s, ascending) at most ``at`` high, numbered
    as scipy's tree cut there lists them: the points left alone in order, then the clusters in the order of the
    merge that made each."""
    parent = np.arange(n)
    made = np.full(n, -1, np.int64)  # per root: the merge that made its cluster
    merges = 0
    while merges < n - 1 and height[merges] <= at:
        a, b = _root(parent, first[merges]), _root(parent, second[merges])
        parent[b] = a
        made[a] = merges
        merges += 1
    part, number = np.empty(n, np.int64), np.full(n, -1, np.int64)  # number: per merge, its cluster's part
    k = 0
    for v in range(n):
        if made[v] < 0 and _root(parent, v) == v:
            part[v] = k
            k += 1
    for q in range(merges):
        if made[_root(parent, first[q])] == q:
            number[q] = k
            k += 1
    for v in range(n):
        r = _root(parent, v)
        if made[r] >= 0:
            part[v] = number[made[r]]
    return part
