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

from pipeline.compiled import kernel, union_root

LINKAGES = ("single", "complete", "average")


@kernel
def components(n, a, b):
    """Connected components of the graph of ``n`` nodes and edges (a, b), labelled 0..k-1 in the order of their
    smallest node: a union-find whose root is always its set's smallest node (with path halving), so a root is met
    before the rest of its set (scipy's csgraph costs more in checking its input at a crowd's size)."""
    parent = np.arange(n)
    for e in range(len(a)):
        if not (0 <= a[e] < n and 0 <= b[e] < n):
            raise ValueError("edges: expected nodes 0 <= a, b < n")
        x, y = union_root(parent, a[e]), union_root(parent, b[e])
        if x < y:
            parent[y] = x
        elif y < x:
            parent[x] = y
    labels = np.empty(n, np.int64)
    k = 0
    for v in range(n):
        r = union_root(parent, v)
        if r == v:
            labels[v] = k
            k += 1
        else:
            labels[v] = labels[r]
    return labels


def detect_groups(n: int, i: np.ndarray, j: np.ndarray, strength: np.ndarray, threshold: float = 0.5,
                  method: str = "single") -> np.ndarray:
    """A cluster label per track (rows 0..n-1; labels 0..k-1, singletons included) from the relations (i, j,
    strength) between rows i < j."""
    if method not in LINKAGES:
        raise ValueError(f"method: expected one of {', '.join(LINKAGES)}, got {method!r}")
    if not len(i) == len(j) == len(strength):
        raise ValueError(f"i, j and strength: expected one entry each per relation, got {len(i)}, {len(j)} and "
                         f"{len(strength)}")
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
        if not 0 <= i[e] < j[e] < n:
            raise ValueError("i, j: expected rows 0 <= i < j < n")
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
    """The merges of complete (else ``average``) linkage on the condensed ``distance`` matrix of ``n`` points, by the
    nearest-neighbour chain (Murtagh 1983; Muellner 2011, arXiv:1109.2378, Fig. 4), with the tie rules of scipy's
    ``linkage`` so that ties merge alike: the chain starts at the first active cluster; the nearest neighbour is the
    first found at the least distance in index order, the cluster below the chain's top winning every tie. Returns
    each merge's two clusters, each named by a point of it (x < y; y names the merged one), and its height, in
    ascending height (a stable sort: equal heights in the order merged)."""
    d = distance.copy()
    size = np.ones(n, np.int64)  # 0: merged into another
    chain = np.empty(n, np.int64)
    top = -1  # the chain's top, chain[:top + 1]
    first, second, height = np.empty(n - 1, np.int64), np.empty(n - 1, np.int64), np.empty(n - 1)
    for k in range(n - 1):
        if top < 0:  # a new chain, from the first active cluster
            top, chain[0] = 0, 0
            while size[chain[0]] == 0:
                chain[0] += 1
        while True:
            x = chain[top]
            below = chain[top - 1] if top > 0 else -1
            y, gap = _nearest(d, n, size, x, below)
            if y == below:  # x and y are each other's nearest: merge them
                break
            top += 1
            chain[top] = y
        top -= 2
        x, y = min(x, y), max(x, y)
        first[k], second[k], height[k] = x, y, gap
        _merge(d, n, size, x, y, average)
    for k in range(1, n - 1):  # a stable insertion sort: the chain's heights come nearly in order
        p = k
        while p > 0 and height[p - 1] > height[p]:
            first[p - 1], first[p] = first[p], first[p - 1]
            second[p - 1], second[p] = second[p], second[p - 1]
            height[p - 1], height[p] = height[p], height[p - 1]
            p -= 1
    return first, second, height


@kernel
def _nearest(d, n, size, x, below):
    """The active cluster nearest to ``x`` and its distance: ``below`` (-1: none) unless another is strictly nearer,
    else the first at the least distance in index order."""
    y, gap = below, d[_condensed(n, x, below)] if below >= 0 else np.inf
    for v in range(n):
        if size[v] > 0 and v != x and d[_condensed(n, x, v)] < gap:
            y, gap = v, d[_condensed(n, x, v)]
    return y, gap


@kernel
def _merge(d, n, size, x, y, average):
    """Cluster x merged into y: the distances from y to the rest by the linkage's Lance-Williams rule (complete: the
    larger; average: weighted by the clusters' sizes)."""
    nx, ny = size[x], size[y]
    size[x], size[y] = 0, nx + ny
    for v in range(n):
        if size[v] > 0 and v != y:
            dx, dy = d[_condensed(n, v, x)], d[_condensed(n, v, y)]
            d[_condensed(n, v, y)] = (nx * dx + ny * dy) / (nx + ny) if average else max(dx, dy)


@kernel
def cut(first, second, height, n, at):
    """The flat clusters (a part per point) of the merges (``nn_chain``'s, ascending) at most ``at`` high, numbered
    as scipy's tree cut there lists them: the points left alone in order, then the clusters in the order of the
    merge that made each."""
    parent = np.arange(n)
    made = np.full(n, -1, np.int64)  # per root: the merge that made its cluster
    merges = 0
    while merges < n - 1 and height[merges] <= at:
        a, b = union_root(parent, first[merges]), union_root(parent, second[merges])
        parent[b] = a
        made[a] = merges
        merges += 1
    part, number = np.empty(n, np.int64), np.full(n, -1, np.int64)  # number: per merge, its cluster's part
    k = 0
    for v in range(n):
        if made[v] < 0 and union_root(parent, v) == v:
            part[v] = k
            k += 1
    for q in range(merges):
        if made[union_root(parent, first[q])] == q:
            number[q] = k
            k += 1
    for v in range(n):
        r = union_root(parent, v)
        if made[r] >= 0:
            part[v] = number[made[r]]
    return part
