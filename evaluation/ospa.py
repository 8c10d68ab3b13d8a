"""OSPA and its labelled form OSPA-T for 2D point targets on the ground plane, per frame and averaged over frames.

Why: OSPA is the set distance the random-finite-set tracking literature reports; it folds localisation and
cardinality error into one number in metres, frame by frame, with no matching threshold to tune. We use

    D. Schuhmacher, B.-T. Vo and B.-N. Vo, "A consistent metric for performance evaluation of multi-object filters",
    IEEE Transactions on Signal Processing 56(8):3447-3457, 2008,

and, for identities, the labelling term of OSPA-T:

    B. Ristic, B.-N. Vo, D. Clark and B.-T. Vo, "A metric for performance evaluation of multi-target tracking
    algorithms", IEEE Transactions on Signal Processing 59(7):3452-3457, 2011.

Per frame, with ground truth X (m points) and tracks Y (n points), say m <= n (the formula is symmetric), cut-off c,
order p and d_c(x, y) = min(c, d(x, y)):

    OSPA = ( (1/n) (min over assignments pi of sum_i d_c(x_i, y_pi(i))^p + c^p (n - m)) )^(1/p)
    localisation = ( (1/n) min_pi sum_i d_c(x_i, y_pi(i))^p )^(1/p),   cardinality = ( c^p (n - m) / n )^(1/p)

(the paper's decomposition; with p = 1 OSPA = localisation + cardinality). OSPA(empty, empty) = 0, and c when only
one set is empty. c = 1 m (the CLEAR-MOT gate of clearmot.py: farther than that an estimate is no better than none),
p = 1 (errors add in metres; the paper's p >= 1 sets how much outliers weigh).

OSPA-T (Ristic et al.) gives every point a label and uses the base distance
min(c, (d^p + alpha^p [labels differ])^(1/p)) in place of d_c; its cardinality term is the same. The labels:

1. Step 1 of the paper: a global one-to-one assignment of track ids to gt ids over the whole sequence. The distance
   of gt id l and track id r sums over frames min(Delta, d)^p where both are present, Delta^p where exactly one is,
   and 0 where neither is; ``linear_sum_assignment`` minimises the total over the assigned pairs, every id of the
   smaller set being assigned. The paper has its own cut-off Delta for this step; we take Delta = c. (With p = 1,
   the default, the exponent does nothing.)
2. A track id assigned to gt id l carries label l; every other track id carries a label no gt id has.

``label_penalty`` (alpha) defaults to c, the top of the paper's range alpha in [0, c] (a larger alpha acts as c):
a point following the right position under another person's label then costs what a missed person costs, as MOTA
weighs an ID switch like a miss. Unlike MOTA the penalty recurs in every frame the label is wrong.

Frames: the mean is over frames in which the ground truth or the tracks have at least one row. A frame with neither
has OSPA 0 by definition, but a ``Sequence`` has no row for it, so it cannot be told apart from a frame that was never
evaluated; it is not averaged in (zeros for idle time would flatter a tracker). With no frames at all every mean is
``None``. The caller removes ignored ground-truth rows first: every row counts. Ids must be unique within a frame.

Computation: a pair at the cut-off costs what leaving both points unassigned does, so the minimum over assignments
is c^p m minus a maximum-weight matching of the pairs closer than c, weighted c^p - base^p; the matching is done
on those pairs only, frame by frame (hota.close_pairs, hota.max_weight_matching).

SPENCER (spencer_people_tracking, spencer_tracking_metrics/ospa, adapted from the cuda-PHDSLAM ospa.py) computes
differently; its online_analysis uses c = 1 m (the matching threshold), p = 1 and a label weight a = 10:

- It first keeps last frame's gt-track correspondences still within c (CLEAR-MOT style) and assigns only the rest
  (Munkres or lapjv on min(d, c), padded square with c), so its value can exceed the OSPA optimum.
- Its localisation sum runs over the padded square assignment and so already holds c^p per unassigned point; its
  OSPA adds c^p (n - m) once more, counting the cardinality error twice (one gt 0.3 m from a track plus one unmatched
  gt: SPENCER 1.15, OSPA 0.65) and its "localisation error" includes the cardinality part.
- Labels are online, not a global assignment: a new correspondence whose gt was last matched to another track, the
  track itself having been matched to some gt before, adds a to the frame's sum (a / n to its OSPA with p = 1; a = 10
  is outside the metric's range alpha <= c and not capped by c), once, in the frame of the switch; OSPA-T charges
  every frame in which the label is wrong.
- It averages over every synchronised frame, frames with neither gt nor tracks counting 0.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import csr_matrix

from evaluation.hota import check_ids, close_pairs, max_weight_matching
from evaluation.sequence import Sequence, frames_of

__all__ = ["ospa", "track_labels"]


def track_labels(gt: Sequence, tracks: Sequence, cutoff: float = 1.0, p: float = 1.0,
                 pairs: tuple | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """OSPA-T step 1 (module docstring) over the whole sequence: (sorted track ids, the gt id each is assigned to,
    whether it is assigned). ``pairs``: ``close_pairs(gt, tracks, cutoff)`` if already at hand. Dense in
    (gt ids x track ids)."""
    t_ids, t_idx = np.unique(tracks.id, return_inverse=True)
    labels = np.zeros(t_ids.size, np.int64)
    assigned = np.zeros(t_ids.size, bool)
    if not len(gt) or not len(tracks):
        return t_ids, labels, assigned
    g_ids, g_idx = np.unique(gt.id, return_inverse=True)
    g_idx, t_idx = g_idx.reshape(-1), t_idx.reshape(-1)
    frames = frames_of(gt, tracks)
    cp = cutoff ** p
    # Frames in which both ids are present: presence (id x frame) products.
    pg = csr_matrix((np.ones(len(gt)), (g_idx, np.searchsorted(frames, gt.frame))), shape=(g_ids.size, frames.size))
    pt = csr_matrix((np.ones(len(tracks)), (t_idx, np.searchsorted(frames, tracks.frame))),
                    shape=(t_ids.size, frames.size))
    both = (pg @ pt.T).toarray()
    # sum over frames = cp * (frames of l only + frames of r only + frames of both) - savings of the close pairs.
    gi, ti, d = close_pairs(gt, tracks, cutoff) if pairs is None else pairs
    saving = np.bincount(g_idx[gi] * t_ids.size + t_idx[ti], cp - d ** p,
                         minlength=g_ids.size * t_ids.size).reshape(g_ids.size, t_ids.size)
    n_g = np.bincount(g_idx, minlength=g_ids.size)
    n_t = np.bincount(t_idx, minlength=t_ids.size)
    cost = cp * (n_g[:, None] + n_t[None, :] - both) - saving
    r, c = linear_sum_assignment(cost)
    labels[c] = g_ids[r]
    assigned[c] = True
    return t_ids, labels, assigned


def _per_frame(n: np.ndarray, m: np.ndarray, gain_sum: np.ndarray, cp: float, p: float):
    """(OSPA, localisation part) per frame from the sizes n >= m and the summed gains c^p - base^p of the matched
    pairs: sum_pi base_c^p = c^p m - gain (unmatched pairs of the assignment sit at the cut-off)."""
    loc = np.maximum(cp * m - gain_sum, 0.0) / n
    total = loc + cp * (n - m) / n
    return total ** (1.0 / p), loc ** (1.0 / p)


def ospa(gt: Sequence, tracks: Sequence, c: float = 1.0, p: float = 1.0, label_penalty: float = 1.0) -> dict:
    """Mean per-frame OSPA of ``tracks`` against ``gt`` with its ``localisation`` and ``cardinality`` parts, the
    labelled ``ospa_t``, the number of ``frames`` averaged, ``labelled_tracks`` (track ids given a gt label) and
    ``per_frame`` (lists ``frame``, ``ospa``, ``localisation``, ``cardinality``, ``ospa_t``); see the module docstring.
    ``c``: cut-off (m); ``p``: order; ``label_penalty``: OSPA-T's alpha (m)."""
    c, p, alpha = float(c), float(p), float(label_penalty)
    if not np.isfinite(c) or c <= 0.0:
        raise ValueError("c must be finite and > 0")
    if not np.isfinite(p) or p < 1.0:
        raise ValueError("p must be finite and >= 1")
    if not np.isfinite(alpha) or alpha < 0.0:
        raise ValueError("label_penalty must be finite and >= 0")
    check_ids(gt, "gt")
    check_ids(tracks, "tracks")
    frames = frames_of(gt, tracks)
    nf = frames.size
    if nf == 0:
        empty = {"frame": [], "ospa": [], "localisation": [], "cardinality": [], "ospa_t": []}
        return {"ospa": None, "localisation": None, "cardinality": None, "ospa_t": None, "frames": 0,
                "labelled_tracks": 0, "per_frame": empty}

    ng = np.diff(gt.bounds(frames))
    nt = np.diff(tracks.bounds(frames))
    n, m = np.maximum(ng, nt), np.minimum(ng, nt)
    cp = c ** p

    gi, ti, d = close_pairs(gt, tracks, c)
    fr = np.searchsorted(frames, gt.frame[gi])
    dp = d ** p

    # Plain OSPA: maximise the sum of c^p - d^p over pairs within c.
    sel = max_weight_matching(gi, ti, cp - dp, fr)
    gain = np.bincount(fr[sel], cp - dp[sel], minlength=nf)
    o, loc = _per_frame(n, m, gain, cp, p)
    card = (cp * (n - m) / n) ** (1.0 / p)

    # OSPA-T: labelled base distance, labels from the global assignment.
    t_ids, labels, assigned = track_labels(gt, tracks, c, p, (gi, ti, d))
    k = np.searchsorted(t_ids, tracks.id[ti])
    same = assigned[k] & (labels[k] == gt.id[gi])
    bp = dp + alpha ** p * ~same
    keep = np.flatnonzero(bp < cp)
    sel_t = keep[max_weight_matching(gi[keep], ti[keep], cp - bp[keep], fr[keep])]
    gain_t = np.bincount(fr[sel_t], cp - bp[sel_t], minlength=nf)
    ot, _ = _per_frame(n, m, gain_t, cp, p)

    per = {"frame": frames.tolist(), "ospa": o.tolist(), "localisation": loc.tolist(), "cardinality": card.tolist(),
           "ospa_t": ot.tolist()}
    return {"ospa": float(o.mean()), "localisation": float(loc.mean()), "cardinality": float(card.mean()),
            "ospa_t": float(ot.mean()), "frames": int(nf), "labelled_tracks": int(assigned.sum()),
            "per_frame": per}
