"""The rectangular linear sum assignment, as one compiled kernel: the cheapest one-to-one pairing of the rows of a
cost matrix with its columns, every row (or every column, when there are fewer) assigned.

Why here: the tracker's association, CLEAR-MOT, HOTA and the detection scores solve one small assignment a frame,
and importing ``scipy.optimize`` for it costs about 0.2 s of every command's start; CLEAR-MOT's frame kernel calls
``assignment`` directly, with no Python between. The method is the shortest augmenting path of
D. F. Crouse, "On implementing 2D rectangular assignment algorithms", IEEE Trans. AES 52(4), 2016, pp. 1685-1686,
as SciPy 1.17 carries it out: the same row order, the same choice among tied columns (the first scanned, unless a later
one is free) and the same float operations, so the pairs are SciPy's pair for pair, ties included
(tests/test_lsap.py checks both against hand-worked optima and against SciPy on tied integer and float costs).
"""

from __future__ import annotations

import numpy as np

from .compiled import kernel

__all__ = ["assignment", "linear_sum_assignment"]


def linear_sum_assignment(cost, maximize: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(rows, columns) of the assignment of least total ``cost`` [n, m] (greatest with ``maximize``), min(n, m)
    pairs, rows ascending; ``inf`` marks a pair not allowed. ValueError for a matrix not 2-D, with NaN or -inf, or
    with no full assignment of finite cost."""
    c = np.asarray(cost, np.float64)
    if c.ndim != 2:
        raise ValueError(f"cost must be a 2-D matrix, got {c.ndim} dimensions")
    rows, cols, status = assignment(c, maximize)
    if status:
        raise ValueError("cost matrix contains NaN or -inf entries" if status == INVALID
                         else "cost matrix is infeasible: no full assignment of finite cost")
    return rows, cols


INVALID, INFEASIBLE = 1, 2


@kernel
def assignment(cost, maximize):
    """``linear_sum_assignment``: the rows made the shorter side (the matrix transposed if need be), the signs
    flipped to maximise, the entries checked; status 0, ``INVALID`` or ``INFEASIBLE``."""
    transpose = cost.shape[1] < cost.shape[0]
    work = np.ascontiguousarray(cost.T) if transpose else np.ascontiguousarray(cost)
    if maximize:
        work = -work
    empty = np.zeros(0, np.int64)
    for x in work.ravel():
        if np.isnan(x) or x == -np.inf:
            return empty, empty, INVALID
    col4row, feasible = _col4row(work)
    if not feasible:
        return empty, empty, INFEASIBLE
    if not transpose:
        return np.arange(len(col4row)), col4row, 0
    order = np.argsort(col4row)
    return col4row[order], order, 0


@kernel
def _col4row(cost):
    """Each row's column in the least-cost assignment of ``cost`` [n, m], n <= m, rows taken in order, each by the
    shortest path that augments the assignment so far (Crouse's algorithm 4 with the duals u, v); and False where a
    row cannot be assigned at a finite cost."""
    nr, nc = cost.shape
    u, v = np.zeros(nr), np.zeros(nc)
    shortest = np.empty(nc)
    path, col4row, row4col = np.full(nc, -1), np.full(nr, -1), np.full(nc, -1)
    seen_row, seen_col = np.zeros(nr, np.bool_), np.zeros(nc, np.bool_)
    remaining = np.empty(nc, np.int64)
    for row in range(nr):
        # the shortest augmenting path from this row, over the columns not yet reached
        n_remaining = nc
        for k in range(nc):
            remaining[k] = nc - k - 1  # scanned from the last column: a constant matrix gives the identity
        seen_row[:] = False
        seen_col[:] = False
        shortest[:] = np.inf
        min_val, i, sink = 0.0, row, -1
        while sink == -1:
            index, lowest = -1, np.inf
            seen_row[i] = True
            for k in range(n_remaining):
                j = remaining[k]
                r = min_val + cost[i, j] - u[i] - v[j]
                if r < shortest[j]:
                    path[j], shortest[j] = i, r
                # among columns tied at the lowest, a free one ends the path
                if shortest[j] < lowest or (shortest[j] == lowest and row4col[j] == -1):
                    lowest, index = shortest[j], k
            min_val = lowest
            if min_val == np.inf:
                return col4row, False
            j = remaining[index]
            if row4col[j] == -1:
                sink = j
            else:
                i = row4col[j]
            seen_col[j] = True
            n_remaining -= 1
            remaining[index] = remaining[n_remaining]
        # the duals, then the assignment flipped along the path
        u[row] += min_val
        for i in range(nr):
            if seen_row[i] and i != row:
                u[i] += min_val - shortest[col4row[i]]
        for j in range(nc):
            if seen_col[j]:
                v[j] -= min_val - shortest[j]
        j = sink
        while True:
            i = path[j]
            row4col[j] = i
            col4row[i], j = j, col4row[i]
            if i == row:
                break
    return col4row, True
