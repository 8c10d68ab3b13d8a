"""Multi-hypothesis people tracker: the MHT baseline of seed 000 (Linder et al. ICRA 2016, Sec. IV-C, Table II).

Why: seed 000 measures its nearest-neighbour tracker against a hypothesis-oriented MHT after Reid (1979) in Cox &
Hingorani's (1996) efficient form, with explicit occlusion labels (Arras et al. ICRA 2008, the seed's [26]). This is
that baseline with the NNT's interface (``update(stamp, detections) -> TrackedPersons``, ``reset()``), so both run in
the loop and are scored alike.

Model. A global hypothesis explains every detection so far: a set of tracks, each a CV Kalman filter (the NNT's
``motion.ConstantVelocity`` and ``imm.kalman_update``, seed 000 Eq. 1-2; Sec. IV-C: "EKF parameters ... identical to
the ones used for the NNT"). In a cycle each track of a parent hypothesis is *detected* (by one gated detection),
*occluded* or *deleted*; each detection no track takes is a *new* track or a *false alarm*. A child's probability is
Reid's with the miss term split by the occlusion labels (Arras et al. 2008):

    P(child) = eta P(parent) p_det^N_det p_occ^N_occ p_del^N_del lambda_new^N_new lambda_fal^N_fal
               prod_(detected i <- j) N(z_j; H x_i, S_ij)

so the cost -log(P(child) / P(parent)) is a sum of one term per decision.

One cycle (``MultiHypothesisTracker.update``):

1. predict  -- every track node (a track as one hypothesis holds it; hypotheses share nodes, as Cox & Hingorani's
               track trees do) in one batch; gate every node against every detection (Mahalanobis, ``gate_chi2``).
2. children -- per parent, its tracks and the detections split into clusters that share no gate; a child's cost is
               the sum of its clusters' costs. A cluster's ranked solutions come from Murty's k-best assignment
               (``KBestAssignments`` on ``assignment_matrix``); a lone track, a lone detection, or a track whose only
               gated detection no other track gates get theirs in closed form. A cluster is solved once per cycle for
               every parent that holds it. A parent's children are then the ranked sums of its clusters' solutions.
3. k-best   -- Cox & Hingorani: one priority queue over all parents yields children in decreasing probability until
               ``max_hypotheses`` of them (the stand-in for seed 000's t_max; see ``MHTParams.max_hypotheses``). A
               parent is decomposed only once a lower bound on its children's cost reaches the head of the queue.
4. prune    -- n-scanback (``n_scan``): children whose ancestor ``n_scan`` cycles back is not the best child's are
               dropped. Probabilities are renormalised.
5. output   -- the best hypothesis's confirmed tracks (``n_confirm`` detections), by id.

Choices:

* Output ids come from a counter starting at 1 when a track is first output, and follow the track (its tree's root),
  not the hypothesis: when the best hypothesis changes, a track keeps its id. Ids are never reused (``reset``
  restarts the counter).
* ``is_matched``: detected this cycle; ``is_occluded`` is its negation; ``age`` is the time since the detection that
  started the track.
* Deterministic: no randomness, no clocks; ties go to the earlier parent, cluster, option or queue entry.
* Stamps must not decrease and detections must be in the tracker's frame with finite x/y and positive-definite x/y
  covariance (ValueError), as for the NNT.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from pipeline.lsap import linear_sum_assignment
from pipeline.types import DetectedPersons, TrackedPersons

from ..params import param
from .association import checked_detections, mahalanobis
from .imm import kalman_update
from .motion import ConstantVelocity

__all__ = ["MHTParams", "MultiHypothesisTracker", "KBestAssignments", "assignment_matrix"]

_LOG_2PI = float(np.log(2.0 * np.pi))


def _outcomes_sum_to_one(p: dict):
    total = p["p_det"] + p["p_occ"] + p["p_del"]
    if abs(total - 1.0) > 1e-9:
        return "p_del", f"p_det + p_occ + p_del = {total:g}; expected 1 (seed 000 Sec. IV-C)"


@dataclass
class MHTParams:
    """Parameters of the multi-hypothesis tracker (units: metres, seconds, tracking cycles), the scenario's keys of
    ``tracker: {type: mht}``."""

    process_noise: float = param(0.267, "m^2/s^3, q_L of the CV model: the NNT's (seed 000 Sec. IV-C)", min=0.0,
                                 exclusive_min=True)
    """The MHT's EKF parameters are the NNT's (seed 000 Sec. IV-C)."""

    gate_chi2: float = param(13.82, "Mahalanobis gate (chi2 0.999 for 2 dof)", min=0.0, exclusive_min=True)
    """On the 2D innovation, the NNT's; seed 000 gives no MHT gate. Pairs outside it are never associated; at the
    gate a detection is about as likely (p_det N) as a miss plus a new track (p_occ lambda_new) for the seed's R = 0.1
    I, so the gate cuts only what the model would rarely choose."""

    p_det: float = param(0.7, "probability a track is detected in a cycle (seed 000 Sec. IV-C)", min=0.0,
                         exclusive_min=True, max=1.0)
    """Seed 000 Sec. IV-C takes it from Luber & Arras 2013."""

    p_occ: float = param(0.27, "probability a track is occluded in a cycle (seed 000 Sec. IV-C)", min=0.0,
                         exclusive_min=True, max=1.0)

    p_del: float = param(0.03, "probability a track is deleted in a cycle (seed 000 Sec. IV-C); p_det + p_occ + p_del "
                               "= 1", min=0.0, exclusive_min=True, max=1.0)
    """Deleted: the track left the scene. The three labels are a track's only fates, hence the sum."""

    lambda_new: float = param(0.005, "1/(m^2 cycle), Poisson rate of new tracks (seed 000 Sec. IV-C)", min=0.0,
                              exclusive_min=True)
    """Hand-tuned in seed 000."""

    lambda_fal: float = param(0.005, "1/(m^2 cycle), Poisson rate of false alarms (seed 000 Sec. IV-C)", min=0.0,
                              exclusive_min=True)
    """Hand-tuned in seed 000."""

    n_scan: int = param(30, "cycles of n-scanback pruning (seed 000 Sec. IV-C: 30)", min=1)

    n_delete: int = param(10, "cycles without a detection that delete a track (seed 000 Sec. IV-C: 10)", min=1)
    """In every hypothesis (seed 000 Sec. IV-C: "at most 10 cycles without detection"; without it, occluded tracks
    stayed too long in the PedSim scenario)."""

    max_hypotheses: int = param(50, "hypotheses generated per cycle, in place of seed 000's t_max = 0.03 s so results "
                                    "do not depend on the machine (about 0.03 s with 80 people; "
                                    "pipeline/tracking/mht.py)", min=1)
    """Generated (and kept) per cycle: the k of Cox & Hingorani's k-best. Seed 000 instead stops generating after
    t_max = 0.03 s per cycle, which makes results depend on the machine and its load; a count keeps them
    deterministic. On seed 000's crowded data (PedSim, 79 tracks on average, Table I) t_max is what binds, so the
    count is calibrated there: on a synthetic crowd of 80 at 25 Hz this implementation takes 0.022-0.032 s of CPU per
    cycle with 50 hypotheses (0.037-0.048 s with 100), on an Intel Xeon core with Python 3.11; a crowd of 30 takes
    0.008-0.011 s with 50, so there t_max would allow about 150."""

    n_confirm: int = param(3, "detections before a track is output (the NNT's)", min=1)
    """The creating one included: the NNT's, so both trackers show a person after the same number of detections and
    differ in data association only. Seed 000's MHT has no initiation logic (Sec. V-E); 2 would suffice to tell a
    new track from a false alarm (lambda_new = lambda_fal), but at the seed's rates one false alarm inside a missed
    tentative track's grown gate is likelier the same object (p_det N p_occ^k) than a second false alarm
    (lambda_fal), so 2 confirmed chance pairs of false alarms."""

    initial_velocity_variance: float = param(1.0, "m^2/s^2 of a new track", min=0.0, exclusive_min=True)
    """Per axis: the NNT's (E[vx^2] of a 1.3 m/s walker, rounded up)."""

    CHECKS = (_outcomes_sum_to_one,)


# ----------------------------------------------------------------------------------------------------------------
# Murty's k-best assignment, and one cluster's assignment problem
# ----------------------------------------------------------------------------------------------------------------


def _solve(cost: np.ndarray) -> tuple[float, np.ndarray] | None:
    """Optimal assignment of every row of cost [n, m] (n <= m, inf = forbidden): (total, column of each row)."""
    try:
        rows, cols = linear_sum_assignment(cost)
    except ValueError:  # scipy: "cost matrix is infeasible"
        return None
    total = float(cost[rows, cols].sum())
    return (total, cols) if np.isfinite(total) else None


class KBestAssignments:
    """Murty's (1968) ranked assignments of cost [n, m] (n <= m; inf = forbidden), computed lazily on
    ``pipeline.lsap.linear_sum_assignment``; ``solution(k)`` is the k-th best (0-based) or None.

    Murty splits the solutions other than the best s into disjoint subproblems: for the branch rows r_1..r_K in
    order, subproblem i keeps s's cells of r_1..r_{i-1} and forbids s's cell of r_i. Branching only on
    ``branch_rows`` (all rows by default) ranks the distinct assignments of those rows; the other rows must then be
    determined by them up to equal cost (as in ``assignment_matrix``), or one solution would appear several times.
    """

    def __init__(self, cost: np.ndarray, branch_rows: np.ndarray | None = None):
        self._cost = np.asarray(cost, float)
        n, m = self._cost.shape
        if n > m:
            raise ValueError(f"cost matrix {n} x {m}: needs at least as many columns as rows")
        self._branch = np.arange(n) if branch_rows is None else np.asarray(branch_rows, np.int64)
        self._found: list[tuple[float, np.ndarray]] = []
        self._heap: list = []  # (total, seq, cols, fixed prefix of branch rows, forbidden cells)
        self._seq = 0
        best = _solve(self._cost)
        if best is not None:
            self._heap.append((best[0], 0, best[1], 0, ()))

    def solution(self, k: int) -> tuple[float, np.ndarray] | None:
        """The k-th best (total cost, column of each row), or None when there are at most k assignments."""
        while len(self._found) <= k and self._heap:
            self._pop()
        return self._found[k] if k < len(self._found) else None

    def _pop(self) -> None:
        total, _, cols, fixed, forbidden = heapq.heappop(self._heap)
        self._found.append((total, cols))
        base = self._cost.copy()
        for r, c in forbidden:
            base[r, c] = np.inf
        rows_free = np.ones(base.shape[0], bool)
        cols_free = np.ones(base.shape[1], bool)
        kept = self._branch[:fixed]
        rows_free[kept] = cols_free[cols[kept]] = False
        kept_cost = float(self._cost[kept, cols[kept]].sum())
        for i in range(fixed, self._branch.size):
            r = int(self._branch[i])
            c = int(cols[r])
            sub = base[rows_free][:, cols_free]
            sub[np.count_nonzero(rows_free[:r]), np.count_nonzero(cols_free[:c])] = np.inf
            best = _solve(sub)
            if best is not None:
                child = cols.copy()
                child[rows_free] = np.flatnonzero(cols_free)[best[1]]
                self._seq += 1
                heapq.heappush(self._heap, (best[0] + kept_cost, self._seq, child, i, forbidden + ((r, c),)))
            rows_free[r] = cols_free[c] = False  # the next subproblems keep this cell
            kept_cost += float(self._cost[r, c])


def assignment_matrix(det: np.ndarray, occ: np.ndarray, delete: float, new: float, fal: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """The square assignment problem of a cluster of a tracks and b detections, every hypothesis one assignment.

    det [a, b]: cost of track i taking detection j (inf outside the gate); occ [a]: cost of track i occluded (inf
    where it must go); delete, new, fal: costs of a deletion, a new track, a false alarm. Rows: detections M_j,
    occlusion rows O_i, deletion rows D_i, slack rows Y_j; columns: tracks C_i, slack Z_i, new N_j, false alarm F_j.
    M_j takes C_i (detected), N_j or F_j; O_i takes C_i (occluded) or Z_i; D_i takes C_i (deleted, when neither
    a detection nor O_i did), else Z_i or any N_k; Y_j takes whichever of N_j / F_j is left. Each hypothesis is then
    one assignment of the branch rows (M, O), returned second; the other rows complete it at zero cost.
    """
    a, b = det.shape
    size = 2 * (a + b)
    cost = np.full((size, size), np.inf)
    M, O, D, Y = 0, b, b + a, b + 2 * a  # row blocks
    C, Z, N, F = 0, a, 2 * a, 2 * a + b  # column blocks
    ia, ib = np.arange(a), np.arange(b)
    cost[M:M + b, C:C + a] = det.T
    cost[M + ib, N + ib] = new
    cost[M + ib, F + ib] = fal
    cost[O + ia, C + ia] = occ
    cost[O + ia, Z + ia] = 0.0
    cost[D + ia, C + ia] = delete
    cost[D + ia, Z + ia] = 0.0
    cost[D:D + a, N:N + b] = 0.0
    cost[Y + ib, N + ib] = 0.0
    cost[Y + ib, F + ib] = 0.0
    return cost, np.arange(b + a)


class _Cluster:
    """Tracks (pool nodes) and detections that share gates: their ranked joint decisions, shared by all parents."""

    def __init__(self, nodes: np.ndarray, meas: np.ndarray, det: np.ndarray, occ: np.ndarray, delete: float,
                 new: float, fal: float):
        self.nodes, self.meas = nodes, meas
        cost, branch = assignment_matrix(det, occ, delete, new, fal)
        self._kbest = KBestAssignments(cost, branch)
        self._entries: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def cost(self, k: int) -> float:
        s = self._kbest.solution(k)
        return np.inf if s is None else s[0]

    def entries(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Decisions of the k-th solution: (source node, or -1 for a new track; detection, or -1 for a miss)."""
        if k not in self._entries:
            cols = self._kbest.solution(k)[1]
            a, b = self.nodes.size, self.meas.size
            on = cols[:b]  # M_j's column: C_i (detected), N_j (new track) or F_j
            det, new = on < a, (on >= 2 * a) & (on < 2 * a + b)
            occluded = self.nodes[cols[b:b + a] == np.arange(a)]  # O_i on C_i
            self._entries[k] = (np.concatenate([self.nodes[on[det]], np.full(np.count_nonzero(new), -1), occluded]),
                                np.concatenate([self.meas[det], self.meas[new], np.full(occluded.size, -1)]))
        return self._entries[k]


# ----------------------------------------------------------------------------------------------------------------
# The tracker
# ----------------------------------------------------------------------------------------------------------------

# Closed-form options of a track with at most one gated detection j that no other track of the parent gates.
_DET, _OCC_NEW, _OCC_FAL, _DEL_NEW, _DEL_FAL = range(5)
_KEEPS = np.array([True, True, True, False, False])  # the track goes on
_NEWS = np.array([False, True, False, True, False])  # j starts a new track
_NODE, _MEAS, _CLUSTER = range(3)  # kinds of component
_NO_CONFLICTS = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros(0, np.int64), np.zeros(0, np.int64),
                 np.zeros(0, np.int64))


class _Parent:
    """One parent hypothesis split into independent components, ordered by how much their second-best solution
    costs over their best (the order that lets a child have at most three successors)."""

    __slots__ = ("kind", "ref", "s0", "s1", "root_src", "root_meas", "root_comp")


class MultiHypothesisTracker:
    """Hypothesis-oriented MHT (Reid 1979; Cox & Hingorani 1996) with occlusion labels (Arras et al. 2008)."""

    def __init__(self, frame: str = "odom", **params):
        """``params``: the keywords of ``MHTParams`` (its defaults for those left out)."""
        self.params = MHTParams(**params)
        self.frame = frame
        self._motion = ConstantVelocity(self.params.process_noise)
        self.reset()

    def reset(self) -> None:
        """Forget all hypotheses, tracks and the last stamp; the id counter restarts at 1."""
        self._x = np.zeros((0, 4))  # [T, 4] pool of track nodes: state x, y, vx, vy
        self._P = np.zeros((0, 4, 4))
        self._label = np.zeros(0, np.int64)  # [T] the track (tree root) a node belongs to
        self._oid = np.zeros(0, np.int64)  # [T] output id of its track, 0 before it is first output
        self._hits = np.zeros(0, np.int64)  # [T] detections over the track's life
        self._misses = np.zeros(0, np.int64)  # [T] consecutive cycles without one
        self._created = np.zeros(0)  # [T] stamp of the first detection
        self._det = np.zeros(0, np.int64)  # [T] detection id this cycle, -1 for none
        self._hyp_nodes: list[np.ndarray] = [np.zeros(0, np.int64)]  # per hypothesis: its nodes, ascending
        self._logp = np.zeros(1)  # [H] log-probabilities, normalised
        self._hyp_id = np.zeros(1, np.int64)  # [H] unique hypothesis ids
        self._lineage = np.full((1, self.params.n_scan), -1, np.int64)  # [H, n_scan] ids of ancestors 1..n back
        self._next_label = 0
        self._next_hyp = 1
        self._next_id = 1
        self._stamp: float | None = None

    @property
    def num_hypotheses(self) -> int:
        """Hypotheses held after the last cycle (at most ``max_hypotheses``)."""
        return len(self._hyp_nodes)

    @property
    def probabilities(self) -> np.ndarray:
        """The hypotheses' probabilities, best first (they sum to 1)."""
        return np.exp(self._logp)

    @property
    def num_tracks(self) -> int:
        """Tracks in the best hypothesis, tentative ones included."""
        return int(self._hyp_nodes[0].size)

    # -- one cycle ----------------------------------------------------------------------------------------------

    def update(self, stamp: float, detections: DetectedPersons) -> TrackedPersons:
        """Run one tracking cycle with the detections at ``stamp``; returns the best hypothesis's confirmed tracks."""
        z, R, det_ids = checked_detections(stamp, detections, self.frame, self._stamp)
        stamp = float(stamp)
        dt = 0.0 if self._stamp is None else stamp - self._stamp
        self._stamp = stamp
        if dt > 0.0 and self._x.shape[0]:
            self._x, self._P = self._motion.predict(self._x, self._P, dt)
        self._costs(z, R)
        children = self._generate()
        children = self._scanback(children)
        self._grow(children, stamp, z, R, det_ids)
        return self._output(stamp)

    def _costs(self, z: np.ndarray, R: np.ndarray) -> None:
        """Every decision's cost for every node and detection this cycle, and the closed-form options."""
        p = self.params
        T, m = self._x.shape[0], z.shape[0]
        d2 = mahalanobis(self._x, self._P, z, R)
        s00 = np.add.outer(self._P[:, 0, 0], R[:, 0, 0])
        s11 = np.add.outer(self._P[:, 1, 1], R[:, 1, 1])
        s01 = np.add.outer(self._P[:, 0, 1], 0.5 * (R[:, 0, 1] + R[:, 1, 0]))
        gated = d2 <= p.gate_chi2
        # -log(p_det N(z; Hx, S)) = -log p_det + log 2 pi + log|S| / 2 + d^2 / 2
        self._det_cost = np.where(gated, 0.5 * (d2 + np.log(s00 * s11 - s01 * s01)) + _LOG_2PI - np.log(p.p_det),
                                  np.inf)
        self._gated = gated
        self._occ_cost = np.where(self._misses + 1 >= p.n_delete, np.inf, -np.log(p.p_occ))
        self._del_cost, self._new_cost, self._fal_cost = -np.log(p.p_del), -np.log(p.lambda_new), -np.log(p.lambda_fal)
        self._deg = gated.sum(1)
        self._j1 = np.where(self._deg > 0, np.argmax(gated, 1) if m else 0, -1)
        # closed-form options [T, 5] (see _DET...): a track without a gated detection has only _OCC_FAL / _DEL_FAL,
        # which then mean occluded / deleted
        one = self._deg == 1
        opts = np.full((T, 5), np.inf)
        opts[one, _DET] = self._det_cost[one, self._j1[one]]
        opts[one, _OCC_NEW] = self._occ_cost[one] + self._new_cost
        opts[:, _OCC_FAL] = self._occ_cost + np.where(one, self._fal_cost, 0.0)
        opts[one, _DEL_NEW] = self._del_cost + self._new_cost
        opts[:, _DEL_FAL] = self._del_cost + np.where(one, self._fal_cost, 0.0)
        self._opt_code = np.argsort(opts, axis=1, kind="stable")
        self._opt_cost = np.take_along_axis(opts, self._opt_code, 1)
        self._meas_code = np.argsort([self._new_cost, self._fal_cost], kind="stable")  # 0: new, 1: false alarm
        self._meas_cost = np.array([self._new_cost, self._fal_cost])[self._meas_code]
        # lower bound of a node's share of any child's cost (exclusivity relaxed), for lazy parent decomposition
        u = min(self._new_cost, self._fal_cost)
        best_det = (self._det_cost - u).min(1) if m else np.full(T, np.inf)
        self._bound = np.minimum(np.minimum(self._occ_cost, self._del_cost), best_det)
        self._bound_base = m * u
        code0 = self._opt_code[:, 0]  # each node's best closed-form option, for the best children
        self._keep0, self._new0 = _KEEPS[code0], _NEWS[code0]
        self._meas0 = np.where(code0 == _DET, self._j1, -1)
        self._clusters: dict[bytes, int] = {}
        self._cluster_list: list[_Cluster] = []
        self._conflict_cache: dict[bytes, tuple[np.ndarray, ...]] = {}

    def _conflicts(self, cx: np.ndarray) -> tuple[np.ndarray, ...]:
        """Clusters of the tracks ``cx`` that share detections (connected components of "gates a detection with"):
        their refs, best and second-best costs, and best decisions (source, detection, cluster); cached per cycle,
        since parents that differ only in tracks without conflicts share them."""
        key = cx.tobytes()
        if key not in self._conflict_cache:
            gx = self._gated[cx]
            cmeas = np.flatnonzero(gx.any(0))
            gx = gx[:, cmeas].astype(np.int32)
            reach = gx @ gx.T > 0
            while True:  # transitive closure
                wider = reach.astype(np.int32) @ reach > 0
                if (wider == reach).all():
                    break
                reach = wider
            refs = []
            for first in np.unique(reach.argmax(1)):
                part = np.flatnonzero(reach[first])
                ckey = cx[part].tobytes()
                if ckey not in self._clusters:
                    cn, cm = cx[part], cmeas[gx[part].any(0)]
                    self._clusters[ckey] = len(self._cluster_list)
                    self._cluster_list.append(_Cluster(cn, cm, self._det_cost[np.ix_(cn, cm)], self._occ_cost[cn],
                                                       self._del_cost, self._new_cost, self._fal_cost))
                refs.append(self._clusters[ckey])
            clusters = [self._cluster_list[r] for r in refs]
            best = [cl.entries(0) for cl in clusters]
            self._conflict_cache[key] = (
                np.asarray(refs, np.int64), np.array([cl.cost(0) for cl in clusters]),
                np.array([cl.cost(1) for cl in clusters]), np.concatenate([e[0] for e in best]),
                np.concatenate([e[1] for e in best]), np.repeat(np.arange(len(best)), [e[0].size for e in best]))
        return self._conflict_cache[key]

    def _prepare(self, h: int) -> _Parent:
        """Split parent h into components: closed-form tracks, lone detections, and Murty clusters."""
        nodes = self._hyp_nodes[h]
        cnt = self._gated[nodes].sum(0)
        j1 = self._j1[nodes]
        simple = (j1 < 0) | ((self._deg[nodes] == 1) & (np.append(cnt, 0)[j1] == 1))
        sn, cx, lone = nodes[simple], nodes[~simple], np.flatnonzero(cnt == 0)
        refs, c0, c1, csrc, cmeas, ccomp = self._conflicts(cx) if cx.size else _NO_CONFLICTS
        ns, nl = sn.size, lone.size
        par = _Parent()
        par.kind = np.repeat([_NODE, _MEAS, _CLUSTER], [ns, nl, refs.size])
        par.ref = np.concatenate([sn, lone, refs])
        par.s0 = np.concatenate([self._opt_cost[sn, 0], np.full(nl, self._meas_cost[0]), c0])
        par.s1 = np.concatenate([self._opt_cost[sn, 1], np.full(nl, self._meas_cost[1]), c1])
        order = np.argsort(par.s1 - par.s0, kind="stable")
        par.kind, par.ref, par.s0, par.s1 = par.kind[order], par.ref[order], par.s0[order], par.s1[order]
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        # the best child's decisions, each tagged with its component's position
        keep, new = self._keep0[sn], self._new0[sn]
        lone_new = self._meas_code[0] == 0  # lone detections start new tracks in the best child
        par.root_src = np.concatenate([sn[keep], np.full(np.count_nonzero(new) + nl * lone_new, -1), csrc])
        par.root_meas = np.concatenate([self._meas0[sn[keep]], self._j1[sn[new]], lone[:nl * lone_new], cmeas])
        par.root_comp = np.concatenate([rank[:ns][keep], rank[:ns][new], rank[ns:ns + nl * lone_new],
                                        rank[ns + nl:][ccomp]])
        return par

    def _option(self, par: _Parent, pos: int, k: int) -> float:
        """Cost of the k-th best solution of the component at ``pos``."""
        kind, ref = par.kind[pos], par.ref[pos]
        if kind == _NODE:
            return self._opt_cost[ref, k] if k < 5 else np.inf
        if kind == _MEAS:
            return self._meas_cost[k] if k < 2 else np.inf
        return self._cluster_list[ref].cost(k)

    def _entries(self, par: _Parent, pos: int, k: int) -> tuple[list[int], list[int]]:
        kind, ref = int(par.kind[pos]), int(par.ref[pos])
        if kind == _NODE:
            code, j = int(self._opt_code[ref, k]), int(self._j1[ref])
            src = [ref] if _KEEPS[code] else []
            meas = [j if code == _DET else -1] if _KEEPS[code] else []
            if _NEWS[code]:
                src.append(-1)
                meas.append(j)
            return src, meas
        if kind == _MEAS:
            return ([-1], [ref]) if self._meas_code[k] == 0 else ([], [])
        return self._cluster_list[ref].entries(k)

    def _generate(self) -> list[tuple[int, float, np.ndarray, np.ndarray]]:
        """Cox & Hingorani's k-best children over all parents: (parent, log-probability, sources, detections).

        The queue holds parents not yet decomposed, keyed by a lower bound of their children's cost, and children,
        keyed by their cost. A child is a parent's best solution with some components moved to lower-ranked
        solutions (``moved``: (position, rank) pairs, ascending positions); successors of a child whose last moved
        component is L at rank k: (a) L at rank k + 1, (b) L + 1 at rank 1 as well, (c) if k == 1, L + 1 at rank 1
        instead of L. With components ordered by their second-best surcharge, every child is reached once and no
        successor is cheaper than its child.
        """
        budget = self.params.max_hypotheses
        heap: list = []
        seq = 0
        for h in range(len(self._hyp_nodes)):
            key = -self._logp[h] + self._bound_base + float(self._bound[self._hyp_nodes[h]].sum())
            heap.append((key, seq, h, None))
            seq += 1
        heapq.heapify(heap)
        parents: dict[int, _Parent] = {}
        out = []
        while heap and len(out) < budget:
            _, _, h, child = heapq.heappop(heap)
            if child is None:  # decompose the parent, queue its best child
                par = parents[h] = self._prepare(h)
                cost = float(par.s0.sum())
                if np.isfinite(cost):
                    heapq.heappush(heap, (-self._logp[h] + cost, seq, h, (cost, -1, 0, ())))
                    seq += 1
                continue
            par = parents[h]
            cost, last, k, moved = child
            out.append((h, self._logp[h] - cost, moved))
            n = par.s0.size
            succ = []
            if last >= 0:
                c = self._option(par, last, k + 1)
                if np.isfinite(c):
                    succ.append((cost + c - self._option(par, last, k), last, k + 1, moved[:-1] + ((last, k + 1),)))
            if last + 1 < n and np.isfinite(par.s1[last + 1]):
                extra = par.s1[last + 1] - par.s0[last + 1]
                succ.append((cost + extra, last + 1, 1, moved + ((last + 1, 1),)))
                if last >= 0 and k == 1:
                    back = par.s1[last] - par.s0[last]
                    succ.append((cost + extra - back, last + 1, 1, moved[:-1] + ((last + 1, 1),)))
            for s in succ:
                heapq.heappush(heap, (-self._logp[h] + s[0], seq, h, s))
                seq += 1
        children = []
        for h, logp, moved in out:
            par = parents[h]
            src, meas = par.root_src, par.root_meas
            if moved:
                stay = np.ones(par.s0.size, bool)
                stay[[pos for pos, _ in moved]] = False
                mask = stay[par.root_comp]
                src, meas = [src[mask]], [meas[mask]]
                for pos, k in moved:
                    s, mm = self._entries(par, pos, k)
                    src.append(np.asarray(s, np.int64))
                    meas.append(np.asarray(mm, np.int64))
                src, meas = np.concatenate(src), np.concatenate(meas)
            children.append((h, logp, src, meas))
        return children

    def _scanback(self, children: list) -> list:
        """n-scanback: keep the children that share the best child's ancestor n_scan cycles back (the first child
        is the best); set the new hypotheses' ids and lineage."""
        parent = np.array([c[0] for c in children], np.int64)
        lineage = np.concatenate([self._hyp_id[parent, None], self._lineage[parent, :-1]], axis=1)
        keep = np.flatnonzero(lineage[:, -1] == lineage[0, -1])
        self._lineage = lineage[keep]
        self._hyp_id = np.arange(self._next_hyp, self._next_hyp + keep.size)
        self._next_hyp += keep.size
        logp = np.array([children[i][1] for i in keep])
        top = logp.max()
        self._logp = logp - (top + np.log(np.exp(logp - top).sum()))
        return [children[i] for i in keep]

    def _grow(self, children: list, stamp: float, z: np.ndarray, R: np.ndarray, det_ids: np.ndarray) -> None:
        """The new node pool from the children's decisions, each decision made once for all children that share it."""
        T, m = self._x.shape[0], z.shape[0]
        src = np.concatenate([c[2] for c in children])
        meas = np.concatenate([c[3] for c in children])
        owner = np.repeat(np.arange(len(children)), [c[2].size for c in children])
        code = np.where(src >= 0, src * (m + 1) + meas + 1, T * (m + 1) + meas)
        uniq, inv = np.unique(code, return_inverse=True)
        order = np.lexsort((inv, owner))
        bounds = np.cumsum([c[2].size for c in children])[:-1]
        self._hyp_nodes = np.split(inv[order], bounds)

        cont = uniq < T * (m + 1)
        s = uniq[cont] // (m + 1)
        j = uniq[cont] % (m + 1) - 1
        jn = uniq[~cont] - T * (m + 1)
        k = jn.size
        x, P = self._x[s], self._P[s]
        hit = j >= 0
        if hit.any():
            x[hit], P[hit] = kalman_update(x[hit], P[hit], z[j[hit]], R[j[hit]])[:2]
        xn = np.zeros((k, 4))
        xn[:, :2] = z[jn]
        Pn = np.zeros((k, 4, 4))
        Pn[:, :2, :2] = R[jn]
        Pn[:, 2, 2] = Pn[:, 3, 3] = self.params.initial_velocity_variance
        self._x, self._P = np.concatenate([x, xn]), np.concatenate([P, Pn])
        self._label = np.concatenate([self._label[s], np.arange(self._next_label, self._next_label + k)])
        self._next_label += k
        self._oid = np.concatenate([self._oid[s], np.zeros(k, np.int64)])
        self._hits = np.concatenate([self._hits[s] + hit, np.ones(k, np.int64)])
        self._misses = np.concatenate([np.where(hit, 0, self._misses[s] + 1), np.zeros(k, np.int64)])
        self._created = np.concatenate([self._created[s], np.full(k, stamp)])
        self._det = np.concatenate([np.append(det_ids, -1)[j], det_ids[jn]])  # j = -1: no detection

    def _output(self, stamp: float) -> TrackedPersons:
        nodes = self._hyp_nodes[0]
        nodes = nodes[self._hits[nodes] >= self.params.n_confirm]
        fresh = np.unique(self._label[nodes[self._oid[nodes] == 0]])
        if fresh.size:  # first output: the next ids, in track order, for every node of those tracks
            at = np.minimum(np.searchsorted(fresh, self._label), fresh.size - 1)
            hit = fresh[at] == self._label
            self._oid[hit] = self._next_id + at[hit]
            self._next_id += fresh.size
        nodes = nodes[np.argsort(self._oid[nodes], kind="stable")]
        P = self._P[nodes]
        matched = self._misses[nodes] == 0
        return TrackedPersons(
            stamp=stamp,
            frame=self.frame,
            track_id=self._oid[nodes],
            is_matched=matched,
            is_occluded=~matched,
            detection_id=self._det[nodes],
            position=self._x[nodes, :2],
            velocity=self._x[nodes, 2:],
            position_covariance=P[:, :2, :2],
            velocity_covariance=P[:, 2:, 2:],
            age=stamp - self._created[nodes],
        )
