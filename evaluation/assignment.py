"""Exact one-to-one assignments of ground-truth ids to track ids from per-pair statistics, without the dense
(gt ids x track ids) matrix.

Why: IDF1 (clearmot.py) and OSPA-T's step 1 (ospa.py) end in a global assignment over the whole run. Dense, an hour
at 25 Hz (~6,000 gt ids, ~19,000 track ids) needs a 900 MB matrix; here memory is O(ids + pairs) and a solve takes
seconds. Both functions reach the optimum total of ``scipy.optimize.linear_sum_assignment`` on the dense matrix;
where optima tie they may pick another one.

``max_weight_matching`` (IDF1): a maximum-weight matching is a minimum-cost matching in which every row is matched,
along a pair (cost -weight) or to a private dummy column (cost 0); such a full matching always exists and LAPJVsp
(``scipy.sparse.csgraph.min_weight_full_bipartite_matching``) solves it on the pairs.

``ospa_t_labels`` (OSPA-T step 1). Rows: the ids of the smaller side (n, each must be assigned); columns: the others
(m >= n), b_j = cp n_j their frames; w_ij = cp both_ij + saving_ij > 0 on the listed pairs, 0 elsewhere. Row i taking
column j costs cp n_i + b_j - w_ij, so the task is to minimise sum_i (b_s(i) - w_i,s(i)) over one-to-one s. A row
may take a column it has no pair with, at b_j, which makes the matrix dense: a min-cost flow through one hub node
(row -> hub at 0, hub -> column j at b_j), dense again when made bipartite. Relax the hub's balance with a price lam:
a row may go to the hub at lam (its private dummy column), the hub feeds any column j at b_j - lam, unlimited, and
does so exactly for the columns with b_j < lam that no row takes:

    L(lam) = sum_j min(0, b_j - lam) + min over M of [sum over M's pairs of (max(b_j, lam) - w_ij) + lam g(M)],

M a matching of the pairs, g(M) the rows it leaves to the hub; a sparse LAPJVsp solve as above.

1. L(lam) <= cost(s) for every lam and s: put s's pairs in M and its other rows on the hub; what is left over is
   max(0, b_j - lam) for each of those rows' columns and -min(0, b_j - lam) for each unused column, all >= 0.
2. An M optimal at lam gives s_M: its pairs, and its g hub rows take the g cheapest columns it leaves unused.
   cost(s_M) = L(lam) when M is balanced, p_< <= g <= p_<=, p_< (p_<=) counting the unused columns with b_j < lam
   (<= lam): then s_M is optimal by 1. This is checked at run time: RuntimeError if cost(s_M) - L(lam) exceeds
   1e-9 cp (sum n_g + sum n_t) (float rounding).
3. Such lam and M exist: max L is the optimum (LP duality; the flow's matrix is totally unimodular) and the flow's
   optimum is a balanced M at the maximiser. The search: M's cost as a function of the price, U_M(x) = sum over
   M's pairs of (b_j - w_ij) + g x + sum over its unused columns of min(0, b_j - x), is concave, >= L, = L at lam,
   with right and left slopes g - p_<= and g - p_< there; a right slope > 0 puts every maximiser of L at or right
   of lam, a left slope < 0 at or left of it. Keeping such a lo and hi, L is evaluated where min(U_lo, U_hi) peaks
   (Kelley's cutting planes, with U in place of lines). There are finitely many matchings, so this ends, at a
   balanced M or where L reaches the peak: that lam maximises L, and the matchings whose U touch L there are optimal
   at lam, one with left slope >= 0 and one with right slope <= 0; their symmetric difference is a set of
   alternating paths and cycles, each of cost change 0, and swapping them over one at a time moves the right slope
   by at most 1 (a path has two ends), so it reaches a balanced M (``_balance``).

4. Most pairs cannot matter: at a price lam a row prefers the hub to a pair whose max(b_j, lam) - w_ij > lam, so
   the pairs with b_j - w_ij > reach are of no use at any lam <= reach (a track that spends many frames away from
   the person). The search runs on the others, reach starting at the lowest level of b; when the maximiser it finds
   lies at or below reach, L there is the same with every pair (those left out are above the hub's price), and 2
   certifies the assignment; otherwise reach is raised to that maximiser's level and the search run again. On an
   hour-long airport run 335,000 of 1.5 million pairs are searched, once.

Ties: b and w are integers for pairs never within c, so L often peaks at a level of b, where the slopes jump; a peak
computed within rounding of a level is moved onto it.

Speed, on synthetic hour-long runs (~1.5 M pairs; a shared 2-core machine): IDF1 with 0.95 M close pairs 0.3 s;
OSPA-T with 6,000 gt ids and 19,000 track ids 0.3 s (one LAPJVsp solve: many one-frame tracks make L peak at the
lowest level), 19,000 and 6,000 5 s (13 solves); under 100 MB beyond the inputs.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np
from scipy.sparse import csr_array
from scipy.sparse.csgraph import connected_components, min_weight_full_bipartite_matching

__all__ = ["max_weight_matching", "ospa_t_labels"]

_EMPTY_I = np.zeros(0, np.int64)
_SNAP = 1e-12  # of the cost scale: rounding of L and of prices (a bound this close is reached, a level this close hit)
_CERT_TOL = 1e-9  # of the cost scale: largest accepted gap between the assignment's cost and the lower bound L
_MAX_STEPS = 200  # cutting-plane steps; finitely many are needed, this guards against a numerical loop


def _row_matching(n_rows: int, n_cols: int, rows: np.ndarray, cols: np.ndarray, cost: np.ndarray,
                  dummy_cost: float) -> np.ndarray:
    """Minimum-cost matching in which every row is matched, along an edge or to a private dummy column costing
    ``dummy_cost``: per row, the index of its edge, -1 for the dummy. Edges sorted by row, unique.

    Every row is matched exactly once, so adding one constant to all costs keeps the optimum; it makes them positive,
    as LAPJVsp drops explicit zeros. Integer costs stay exact."""
    n_edges = rows.size
    counts = np.bincount(rows, minlength=n_rows) + 1  # each row's edges, then its dummy
    indptr = np.zeros(n_rows + 1, np.int64)
    np.cumsum(counts, out=indptr[1:])
    shift = 1.0 - min(float(cost.min()) if n_edges else 0.0, dummy_cost)
    data = np.empty(n_edges + n_rows)
    indices = np.empty(n_edges + n_rows, np.int32)
    edge_pos = np.arange(n_edges, dtype=rows.dtype)
    edge_pos += rows  # the rows before an edge's row each hold one dummy
    data[edge_pos] = cost
    data[edge_pos] += shift
    indices[edge_pos] = cols
    del edge_pos
    data[indptr[1:] - 1] = dummy_cost + shift
    indices[indptr[1:] - 1] = n_cols + np.arange(n_rows)
    graph = csr_array((data, indices, indptr.astype(np.int32)), shape=(n_rows, n_cols + n_rows))
    match = min_weight_full_bipartite_matching(graph)[1]
    picked = np.full(n_rows, -1, np.int64)
    hit = np.flatnonzero(cols == match[rows])
    picked[rows[hit]] = hit
    return picked


def max_weight_matching(rows: np.ndarray, cols: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Indices of the pairs of a maximum-total-weight one-to-one matching of rows to columns (sorted).

    ``rows``, ``cols``: non-negative indices of each pair's two ids, pairs unique; ``weight`` > 0 (IDF1: the frames
    a gt id and a track id are within the threshold). The total equals that of ``linear_sum_assignment(dense,
    maximize=True)`` on the zero-filled dense matrix (the zeros it picks are no pairs), exactly for integer weights.
    Memory O(pairs)."""
    rows, cols = np.asarray(rows, np.int64), np.asarray(cols, np.int64)
    weight = np.asarray(weight, np.float64)
    if rows.size == 0:
        return _EMPTY_I
    n_rows, n_cols = int(rows.max()) + 1, int(cols.max()) + 1
    if n_rows > n_cols:  # LAPJVsp augments once per row: fewer rows, faster (5x on an IDF1 instance)
        rows, cols, n_rows, n_cols = cols, rows, n_cols, n_rows
    order = np.argsort(rows, kind="stable")
    picked = _row_matching(n_rows, n_cols, rows[order], cols[order], -weight[order], 0.0)
    return np.sort(order[picked[picked >= 0]])


class _Matching:
    """An optimal matching of the Lagrangian at one hub price, and the bound on L it gives at every price x:

        U(x) = sum over its edges of (b_j - w_ij) + hub x + sum over its unused columns of min(0, b_j - x),

    its cost at x (max(b_j, x) + min(0, b_j - x) = b_j), which is >= L(x), = L at its own price, concave."""

    def __init__(self, n: int, rows: np.ndarray, cols: np.ndarray, w: np.ndarray, b: np.ndarray, lam: float):
        cost = b[cols]
        np.maximum(cost, lam, out=cost)
        cost -= w
        self.picked = _row_matching(n, b.size, rows, cols, cost, lam)
        del cost
        edges = self.picked[self.picked >= 0]
        used = np.zeros(b.size, bool)
        used[cols[edges]] = True
        self.hub = n - edges.size
        self.fixed = float(b[cols[edges]].sum() - w[edges].sum())
        self.free = np.sort(b[~used])
        self.free_sum = np.r_[0.0, np.cumsum(self.free)]
        self.lam, self.value = lam, float(self.upper(lam))

    def upper(self, x):
        """U(x), for a number or an array."""
        k = np.searchsorted(self.free, x)  # unused columns with b < x
        return self.fixed + self.hub * x + self.free_sum[k] - k * x

    def slopes(self, x: float) -> tuple[int, int]:
        """(right, left) slope of U at x: hub rows minus unused columns with b <= x, b < x. The matching is balanced,
        an optimal assignment, at an x where it is optimal and right <= 0 <= left."""
        return (self.hub - int(np.searchsorted(self.free, x, "right")),
                self.hub - int(np.searchsorted(self.free, x, "left")))

    def balanced(self, x: float) -> bool:
        right, left = self.slopes(x)
        return right <= 0 <= left


def _peak(lo: _Matching, hi: _Matching | None, top: float, levels: np.ndarray, snap: float) -> tuple[float, float]:
    """Where min(U_lo, U_hi) (U_lo alone without hi) peaks in [lo.lam, top], and its value there. Both are linear
    between the levels of b, so it peaks at a level or where they cross between two; a crossing within ``snap`` of
    a level is left to the level (the slopes change exactly there)."""
    x = np.r_[lo.lam, levels[(levels > lo.lam) & (levels < top)], top]
    if hi is not None:
        d = lo.upper(x) - hi.upper(x)
        k = np.flatnonzero((d[:-1] < 0) & (d[1:] > 0))
        cross = x[k] - d[k] * (x[k + 1] - x[k]) / (d[k + 1] - d[k])
        x = np.r_[x, cross[np.minimum(cross - x[k], x[k + 1] - cross) > snap]]
    value = lo.upper(x) if hi is None else np.minimum(lo.upper(x), hi.upper(x))
    best = int(np.argmax(value))
    return float(x[best]), float(value[best])


def _mates(picked: np.ndarray, cols: np.ndarray, dummy: np.ndarray) -> np.ndarray:
    """Column matched to each row, ``dummy`` where the row is on the hub."""
    on = picked >= 0
    dummy[on] = cols[picked[on]]
    return dummy


def _balance(a: _Matching, z: _Matching, n: int, cols: np.ndarray, b: np.ndarray, lam: float) -> np.ndarray:
    """A balanced optimum at ``lam`` from two optimal matchings there, ``a`` with left slope >= 0 and ``z`` with
    right slope <= 0: their symmetric difference splits into alternating paths and cycles, each of cost change 0 at
    ``lam``; swapping them from ``a`` to ``z`` one at a time moves the right slope by at most 1 per swap (a path has
    two ends), so it reaches 0 on the way, where the left slope is >= 0 (the first one at which right <= 0)."""
    m = b.size
    mate_a, mate_z = _mates(a.picked, cols, m + np.arange(n)), _mates(z.picked, cols, m + np.arange(n))
    diff = np.flatnonzero(mate_a != mate_z)  # m + row: the row's dummy
    graph = csr_array((np.ones(2 * diff.size), (np.r_[diff, diff], n + np.r_[mate_a[diff], mate_z[diff]])),
                      shape=(2 * n + m, 2 * n + m))
    label = connected_components(graph, directed=False)[1][diff]
    counts = np.r_[b <= lam, np.ones(n, bool)]  # ends that count in the right slope: cheap columns, dummies
    comp, inverse = np.unique(label, return_inverse=True)
    step = np.bincount(inverse, counts[mate_z[diff]].astype(float) - counts[mate_a[diff]], minlength=comp.size)
    right = a.slopes(lam)[0] + np.r_[0, np.cumsum(step)]
    swapped = int(np.argmax(right <= 0))
    out = a.picked.copy()
    flip = diff[inverse < swapped]
    out[flip] = z.picked[flip]
    return out


def _search(n: int, rows: np.ndarray, cols: np.ndarray, w: np.ndarray, b: np.ndarray,
            snap: float) -> tuple[float, float, np.ndarray]:
    """A maximiser of L, L there, and a balanced optimal matching there (module docstring, 3)."""
    levels = np.unique(b)
    lo = _Matching(n, rows, cols, w, b, float(levels[0]))  # left slope >= 0: no column is cheaper
    if lo.balanced(lo.lam):
        return lo.lam, lo.value, lo.picked
    hi = None  # at the top level every unused column is as cheap: right slope <= 0, the maximisers lie below
    for _ in range(_MAX_STEPS):
        # lo (right slope > 0) and hi (left slope < 0) bracket the maximisers. Until a hi is found, U_lo's peak is
        # tried rather than the top level, where LAPJVsp solves a maximum-weight matching: 12 s against 0.5 s on
        # a 12,000 x 12,000 instance.
        lam, bound = _peak(lo, hi, float(levels[-1]) if hi is None else hi.lam, levels, snap)
        new = _Matching(n, rows, cols, w, b, lam)
        if new.balanced(lam):
            return lam, new.value, new.picked
        if new.value >= bound - snap:  # L reaches the peak of its bounds: lam maximises L
            optimal = [m for m in (new, lo, hi) if m is not None and m.upper(lam) <= new.value + snap]
            a = max(optimal, key=lambda m: m.slopes(lam)[1])
            z = min(optimal, key=lambda m: m.slopes(lam)[0])
            return lam, new.value, _balance(a, z, n, cols, b, lam)
        lo, hi = (new, hi) if new.slopes(lam)[0] > 0 else (lo, new)
    raise RuntimeError("ospa_t_labels: the cutting-plane search did not converge")


def _complete(picked: np.ndarray, cols: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Column per row: the matching's edges, and for the hub rows the cheapest columns it leaves unused."""
    mate = _mates(picked, cols, np.full(picked.size, -1))
    used = np.zeros(b.size, bool)
    used[mate[mate >= 0]] = True
    free = np.flatnonzero(~used)
    hub = np.flatnonzero(mate < 0)
    mate[hub] = free[np.argsort(b[free], kind="stable")[:hub.size]]
    return mate


def _edges_within(pairs, flip: bool, b: np.ndarray, reach: float):
    """The edges (rows, cols, w) of the pairs with w > 0 (a pair never present together and never close is none)
    and b[col] - w <= reach, sorted by row (stably), and whether that is every edge."""
    rows, cols, weights, left_out = [], [], [], 0
    for l, r, w in pairs():
        row, col = (r, l) if flip else (l, r)
        w = np.asarray(w, np.float64)
        edge = w > 0
        keep = edge & (b[col] - w <= reach)
        left_out += int(np.count_nonzero(edge)) - int(np.count_nonzero(keep))
        rows.append(np.asarray(row, np.int32)[keep])
        cols.append(np.asarray(col, np.int32)[keep])
        weights.append(w[keep])
    rows, cols, w = (np.concatenate(parts) if parts else np.zeros(0, dtype)
                     for parts, dtype in ((rows, np.int32), (cols, np.int32), (weights, np.float64)))
    if rows.size and (rows[1:] < rows[:-1]).any():  # by row (pairs in key order are by gt already)
        order = np.argsort(rows, kind="stable")
        rows, cols, w = rows[order], cols[order], w[order]
    return rows, cols, w, left_out == 0


def ospa_t_labels(n_g: np.ndarray, n_t: np.ndarray, pairs: Callable[[], Iterable[tuple]],
                  cp: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """OSPA-T step 1 (ospa.py) from per-id and per-pair frame statistics: the assignment minimising the sum of

        cost[l, r] = cp (n_g[l] + n_t[r]) - w[l, r],  w = cp both + saving   (w = 0 off the listed pairs)

    over the assigned pairs, every id of the smaller side assigned, returned as ``linear_sum_assignment(cost)`` does:
    (gt indices, track indices), sorted by gt index. ``n_g``, ``n_t``: frames each gt id, track id is present;
    ``pairs()``: the pairs ever present in one frame, each once, as blocks (l, r, w) of gt index, track index and
    weight (``both``: frames both are present; ``saving``: sum over those frames of cp - min(c, d)^p); it is called
    once per price bound tried (module docstring, 4), so that all the pairs are never in memory at once, and the
    gt indices ascending where the gt ids are the fewer sort nothing; ``cp``: c^p. Method and proof: module
    docstring. Raises RuntimeError if the optimality certificate fails (float rounding beyond 1e-9 of the total's
    scale)."""
    n_g, n_t = np.asarray(n_g, np.float64), np.asarray(n_t, np.float64)
    flip = n_g.size > n_t.size  # rows: the smaller side, each of them assigned
    n, b = (n_t.size, cp * n_g) if flip else (n_g.size, cp * n_t)
    if n == 0:
        return _EMPTY_I, _EMPTY_I
    scale = cp * float(n_g.sum() + n_t.sum())  # bounds the total cost
    levels = np.unique(b)
    reach = levels[0]
    while True:  # solved on the edges a row could prefer to the hub at a price up to reach (module docstring, 4)
        rows, cols, w, every = _edges_within(pairs, flip, b, reach)
        lam, bound, picked = _search(n, rows, cols, w, b, _SNAP * scale)
        if lam <= reach or every:
            break
        reach = levels[np.searchsorted(levels, lam)]
    mate = _complete(picked, cols, b)
    cost = float(b[mate].sum() - w[picked[picked >= 0]].sum())
    if cost - bound > _CERT_TOL * scale:
        raise RuntimeError(f"ospa_t_labels: assignment cost {cost} exceeds the lower bound {bound}")
    if not flip:
        return np.arange(n), mate
    o = np.argsort(mate)
    return mate[o], o
