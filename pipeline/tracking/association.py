"""Gating and data association of the people tracker (seed 000 Sec. II-B "Data association", Sec. V-A, Table II).

The cost of pairing track i with detection j is the squared Mahalanobis distance of the detection from the track's
predicted position; pairs costing more than the gate are not allowed. Three ways to choose pairs, as in Table II:

* ``greedy`` (Greedy NN): take the cheapest allowed pair, drop its row and column, repeat.
* ``global`` (Global NN): the assignment of least total cost, solved by Jonker-Volgenant (scipy's
  ``linear_sum_assignment``). Leaving a track without a detection costs the gate, the standard non-assignment
  cost of global nearest neighbour, so no pair beyond the gate is ever taken and no far pair is forced on a track
  to make room for another.
* ``multi`` (NN with multiple associations per detection): every track takes its nearest allowed detection, even one
  another track took. Seed 000 Sec. V-A: more MOTA, more ID switches, since a track that lost its person converges
  onto a neighbour and duplicates its track.

Each returns (rows, cols), the pairs taken, deterministically (greedy and multi break ties by the smaller row,
then column). Each takes ``later`` [n] bool too: rows that choose only after all the others, by greedy NN from the
columns left (the tracker's initiation candidates, which seed 000 Alg. 1 gives the detections no track took, Z^u).

The tracker is given its association as a part (``GreedyNN``, ``GlobalNN``, ``MultiNN``, or anything with a
``gate_chi2`` and ``assign(cost, later)``), which holds the gate.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..compiled import kernel
from ..lsap import linear_sum_assignment
from ..params import param

__all__ = ["ASSOCIATIONS", "GreedyNN", "GlobalNN", "MultiNN", "checked_detections", "mahalanobis",
           "gated_mahalanobis", "greedy_assign", "global_assign", "multi_assign"]


def checked_detections(stamp: float, det, frame: str, previous: float | None):
    """A tracker's input checked once for every tracker: detections in the tracker's ``frame``, a finite stamp no
    earlier than the ``previous`` cycle's, finite x/y and positive-definite x/y covariances. Returns the positions
    z [m, 2], covariances R [m, 2, 2] and detection ids; ValueError naming what is wrong."""
    if det.frame != frame:
        raise ValueError(f"detections are in frame '{det.frame}' but the tracker tracks in frame '{frame}'")
    if not math.isfinite(stamp):
        raise ValueError(f"stamp must be finite, got {stamp}")
    if previous is not None and stamp < previous:
        raise ValueError(f"stamp {stamp} is earlier than the previous cycle's {previous}")
    n = len(det)
    pos, cov = np.asarray(det.position, float), np.asarray(det.covariance, float)
    if pos.shape != (n, 3) or cov.shape != (n, 3, 3):
        raise ValueError(f"detections: position {pos.shape} / covariance {cov.shape} do not match {n} ids")
    z, R = pos[:, :2], cov[:, :2, :2]
    if not (np.isfinite(z).all() and np.isfinite(R).all()):
        raise ValueError("detections: x/y position and covariance must be finite")
    if not ((R[:, 0, 0] > 0.0) & (R[:, 0, 0] * R[:, 1, 1] - R[:, 0, 1] * R[:, 1, 0] > 0.0)).all():
        raise ValueError("detections: x/y covariance must be positive definite")
    return z, R, np.asarray(det.detection_id, np.int64)


def mahalanobis(x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Squared Mahalanobis distance d^2[i, j] = nu^T S^-1 nu of every track i against every detection j.

    x [n, >=2], P [n, >=2, >=2] (predicted tracks; position first), z [m, 2] positions, R [m, 2, 2] their
    covariances; returns [n, m]. nu = z_j - H x_i, S = H P_i H^T + R_j; the 2x2 inverse is written out in closed form.
    """
    return gated_mahalanobis(x, P, z, R, math.inf)


def gated_mahalanobis(x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray, gate: float) -> np.ndarray:
    """``mahalanobis(x, P, z, R)`` where a pair can lie within ``gate``, inf where it cannot: the same numbers
    wherever it matters to an association, bit for bit.

    Why: in a crowd a track's gate holds a few of the detections. For any positive-definite S,
    nu^T S^-1 nu >= nu_x^2 / S_xx, so a pair within the gate has |x_i - z_j| <= sqrt(gate (P_i,xx + R_xx)) along x,
    R_xx the largest of the detections': the detections are sorted by x once and each track computes only the window
    of them that its bound allows (``_d2``). The window is widened (its square by half again) so that rounding in the
    computed d^2 (relative errors of 1e-16 times S's condition number) cannot bring a pair outside it within the gate.
    """
    x, P, z, R = (np.asarray(a, np.float64) for a in (x, P, z, R))
    n, m = x.shape[0], z.shape[0]
    if x.ndim != 2 or x.shape[1] < 2 or P.shape[0] != n or P.shape[1] < 2 or P.shape[2] < 2 or z.shape != (m, 2) \
            or R.shape != (m, 2, 2):
        raise ValueError(f"mahalanobis: expected x [n, >=2], P [n, >=2, >=2], z [m, 2], R [m, 2, 2], got "
                         f"{x.shape}, {P.shape}, {z.shape}, {R.shape}")
    out = np.empty((n, m))
    _d2(x, P, z, R, float(gate), out)
    return out


@kernel
def _d2(x, P, z, R, gate, out):
    """nu^T S^-1 nu of the pairs in each track's window (every pair when ``gate`` is inf) into ``out``, inf
    elsewhere, in one operation order for every pair: s11 nu0^2 - 2 s01 nu0 nu1 + s00 nu1^2 over
    s00 s11 - s01^2, S's off-diagonal the mean of R's two."""
    n, m = out.shape
    windowed = math.isfinite(gate)
    order = np.argsort(z[:, 0], kind="mergesort")
    zx = np.empty(m)
    widest = 0.0
    for j in range(m):
        zx[j] = z[order[j], 0]
        widest = R[j, 0, 0] if j == 0 else max(widest, R[j, 0, 0])
    for i in range(n):
        lo, hi = 0, m
        if windowed:
            out[i, :] = np.inf
            half = math.sqrt((P[i, 0, 0] + widest) * (1.5 * gate))
            lo = np.searchsorted(zx, x[i, 0] - half, side="left")
            hi = np.searchsorted(zx, x[i, 0] + half, side="right")
        for k in range(lo, hi):
            j = order[k]
            nu0, nu1 = x[i, 0] - z[j, 0], x[i, 1] - z[j, 1]  # the sign of nu is moot
            s00, s11 = P[i, 0, 0] + R[j, 0, 0], P[i, 1, 1] + R[j, 1, 1]
            s01 = P[i, 0, 1] + 0.5 * (R[j, 0, 1] + R[j, 1, 0])
            d2 = s11 * nu0 * nu0
            d2 -= 2.0 * s01 * nu0 * nu1
            d2 += s00 * nu1 * nu1
            det = s00 * s11
            det -= s01 * s01
            out[i, j] = d2 / det


def _none() -> tuple[np.ndarray, np.ndarray]:
    return np.zeros(0, np.int64), np.zeros(0, np.int64)


def greedy_assign(cost: np.ndarray, gate: float, later: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Greedy NN on cost [n, m]: pairs with cost <= gate taken in increasing cost (the ``later`` rows' pairs after all
    others), each row and column at most once; returned in the order taken. One stable sort of the allowed pairs
    (ties by row, then column) and a single walk, compiled (``_greedy``)."""
    n, m = cost.shape
    if n == 0 or m == 0:
        return _none()
    late = np.zeros(n, np.int64) if later is None else np.asarray(later, np.int64)
    rows, cols = np.empty(min(n, m), np.int64), np.empty(min(n, m), np.int64)
    k = _greedy(np.ascontiguousarray(cost, np.float64), float(gate), late, rows, cols)
    return rows[:k], cols[:k]


@kernel
def _greedy(cost, gate, late, out_r, out_c):
    """``greedy_assign``'s pairs into out_r, out_c; their number."""
    n, m = cost.shape
    pairs = 0
    for i in range(n):
        for j in range(m):
            if cost[i, j] <= gate:
                pairs += 1
    rows, cols, value = np.empty(pairs, np.int64), np.empty(pairs, np.int64), np.empty(pairs)
    p = 0
    for i in range(n):  # row-major, so the stable sorts break ties by (row, col)
        for j in range(m):
            if cost[i, j] <= gate:
                rows[p], cols[p], value[p] = i, j, cost[i, j]
                p += 1
    order = np.argsort(value, kind="mergesort")
    order = order[np.argsort(late[rows[order]], kind="mergesort")]  # the later rows' pairs behind, still by cost
    row_free, col_free = np.ones(n, np.bool_), np.ones(m, np.bool_)
    taken = 0
    for q in order:
        r, c = rows[q], cols[q]
        if row_free[r] and col_free[c]:
            row_free[r] = col_free[c] = False
            out_r[taken], out_c[taken] = r, c
            taken += 1
            if taken == len(out_r):
                break
    return taken


def _then_greedy(assign):
    """The association ``assign`` for the rows not ``later``, then greedy NN for those on the columns left."""

    @functools.wraps(assign)
    def with_later(cost: np.ndarray, gate: float, later: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        if later is None or not later.any():
            return assign(cost, gate)
        first, cand = np.flatnonzero(~later), np.flatnonzero(later)
        rows, cols = assign(cost[first], gate)
        rest = cost[cand]
        rest[:, cols] = np.inf
        r, c = greedy_assign(rest, gate)
        return np.concatenate([first[rows], cand[r]]), np.concatenate([cols, c])

    return with_later


@_then_greedy
def global_assign(cost: np.ndarray, gate: float) -> tuple[np.ndarray, np.ndarray]:
    """Global NN on cost [n, m]: the pairs (cost <= gate) of least sum(cost) + gate * (rows left without a pair).

    Written as one rectangular assignment on cost - gate for allowed pairs and 0 otherwise: a pair costing 0 is the
    same as no pair, so the solver's complete assignment is the best partial one; its 0-cost pairs are dropped.
    Returned by row (the ``later`` rows' pairs after the others).
    """
    n, m = cost.shape
    if n == 0 or m == 0:
        return _none()
    allowed = cost <= gate
    rows, cols = linear_sum_assignment(np.where(allowed, cost - gate, 0.0))
    keep = allowed[rows, cols]
    return rows[keep].astype(np.int64), cols[keep].astype(np.int64)


@_then_greedy
def multi_assign(cost: np.ndarray, gate: float) -> tuple[np.ndarray, np.ndarray]:
    """NN with multiple associations per detection on cost [n, m]: each row its cheapest column with cost <= gate,
    whether or not other rows took it. Returned by row (the ``later`` rows' pairs after the others)."""
    n, m = cost.shape
    if n == 0 or m == 0:
        return _none()
    cols = np.argmin(cost, axis=1)  # the first of equal minima: the smaller column
    rows = np.flatnonzero(cost[np.arange(n), cols] <= gate)
    return rows.astype(np.int64), cols[rows].astype(np.int64)


@dataclass(frozen=True)
class _Gated:
    """An association with its gate: pairs costing more are never taken."""

    gate_chi2: float = param(
        13.82, "Mahalanobis gate on the 2D innovation: the chi-square 0.999 quantile for 2 degrees of freedom. The "
               "0.99 quantile (9.21) rejects 1 % of a track's own detections, about one every 4 s per person at 25 Hz; "
               "early in a track's life, with a velocity still uncertain, such a rejection often loses the track. On "
               "a synthetic crowd (30 and 80 walkers at ~1.3 m/s in 30 x 30 m, 25 Hz, sigma 0.05 m, 5 % misses, 1 "
               "false alarm per frame, 60 s; q_L = 0.267) 13.82 cut the ID switches from 25 to 9 (30 walkers) and 65 "
               "to 21 (80 walkers); the gate only bounds which pairs may match, greedy NN still takes the nearest "
               "first", min=0.0, exclusive_min=True)

    RULE: ClassVar  # the association function: (cost, gate, later) -> (rows, cols)

    def assign(self, cost: np.ndarray, later: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The pairs (rows, cols) of cost [n, m] taken within the gate; the ``later`` rows choose after the others."""
        return self.RULE(cost, self.gate_chi2, later)


@dataclass(frozen=True)
class GreedyNN(_Gated):
    """``greedy``: Greedy NN, the base NNT of seed 000 Table II, and within 0.1 % MOTA of the optimal global NN there
    (Sec. V-A)."""

    RULE = staticmethod(greedy_assign)


@dataclass(frozen=True)
class GlobalNN(_Gated):
    """``global``: Global NN (Jonker-Volgenant), seed 000 Sec. V-A."""

    RULE = staticmethod(global_assign)


@dataclass(frozen=True)
class MultiNN(_Gated):
    """``multi``: NN with multiple associations per detection, seed 000 Sec. V-A."""

    RULE = staticmethod(multi_assign)


ASSOCIATIONS = {"greedy": GreedyNN, "global": GlobalNN, "multi": MultiNN}
