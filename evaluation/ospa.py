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
   and 0 where neither is; the assignment minimises the total over the assigned pairs, every id of the smaller set
   being assigned (``assignment.ospa_t_labels`` solves it exactly on the pairs ever present together, without the
   dense matrix). The paper has its own cut-off Delta for this step; we take Delta = c. (With p = 1, the default,
   the exponent does nothing.)
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
on those pairs only, frame by frame (hota.close_pairs, hota.matching_by_frame).

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

from dataclasses import dataclass

import numpy as np

from evaluation.assignment import ospa_t_labels
from evaluation.hota import check_ids, close_pairs, matching_by_frame, same_frame_pairs
from evaluation.metric import Result
from evaluation.sequence import Sequence, frames_of
from evaluation.tables import Counts, ExactSum, Slots, grown, pair_key, split_pair_key

__all__ = ["Ospa", "OspaResult", "ospa"]

_GRID_CELLS = 1 << 18  # a chunk's pairs are counted on its (gt ids x track ids) grid up to this size (2 MB)


@dataclass(frozen=True)
class OspaResult(Result):
    """The means over frames (None without frames), the frames averaged and the track ids given a gt label."""

    ospa: float | None
    localisation: float | None
    cardinality: float | None
    ospa_t: float | None
    frames: int
    labelled_tracks: int


def _per_frame(n: np.ndarray, m: np.ndarray, gain_sum: np.ndarray, cp: float, p: float):
    """(OSPA, localisation part) per frame from the sizes n >= m and the summed gains c^p - base^p of the matched
    pairs: sum_pi base_c^p = c^p m - gain (unmatched pairs of the assignment sit at the cut-off)."""
    loc = np.maximum(cp * m - gain_sum, 0.0) / n
    total = loc + cp * (n - m) / n
    return total ** (1.0 / p), loc ** (1.0 / p)


class Ospa:
    """OSPA and OSPA-T over a sequence given as chunks of whole frames in frame order, in two passes over the same
    chunks (evaluation/metric.py): ``add`` every chunk (plain OSPA, and what OSPA-T's labels need), ``next_pass``
    (the labels), ``add`` every chunk again (OSPA-T), ``result``. The state is per gt id, per track id and per
    (gt id, track id) pair ever present in the same frame; the means over frames are exactly rounded sums, whatever
    the chunks."""

    passes = 2

    def __init__(self, c: float = 1.0, p: float = 1.0, label_penalty: float = 1.0):
        self.c, self.p, self.alpha = float(c), float(p), float(label_penalty)
        if not np.isfinite(self.c) or self.c <= 0.0:
            raise ValueError("c must be finite and > 0")
        if not np.isfinite(self.p) or self.p < 1.0:
            raise ValueError("p must be finite and >= 1")
        if not np.isfinite(self.alpha) or self.alpha < 0.0:
            raise ValueError("label_penalty must be finite and >= 0")
        self.cp = self.c ** self.p
        self.sums = {name: ExactSum() for name in ("ospa", "localisation", "cardinality", "ospa_t")}
        self.gt_ids, self.track_ids, self.close = Slots(), Slots(), Slots()
        self.n_g = self.n_t = np.zeros(0, np.int64)  # frames each gt (track) id is present in
        self.together = Counts()  # frames each pair of a gt id and a track id is present together
        self.saving = np.zeros(0)  # per pair ever within c: the sum over frames of c^p - d^p where d < c
        self.labels = self.assigned = None  # per track slot: the gt id it is labelled with, and whether it is

    def _frames(self, gt: Sequence, tracks: Sequence):
        """The chunk's frames, their set sizes n >= m, and its pairs closer than c with their frame index and d^p."""
        check_ids(gt, "gt")
        check_ids(tracks, "tracks")
        frames = frames_of(gt, tracks)
        ng, nt = np.diff(gt.bounds(frames)), np.diff(tracks.bounds(frames))
        gi, ti, d = close_pairs(gt, tracks, self.c)
        fr = np.searchsorted(frames, gt.frame[gi])
        return frames, np.maximum(ng, nt), np.minimum(ng, nt), gi, ti, fr, d ** self.p

    def add(self, gt: Sequence, tracks: Sequence):
        """A chunk of the first pass (``_count``: its plain OSPA per frame returned) or, after ``next_pass``, of the
        second (``_score``: its OSPA-T per frame returned)."""
        return (self._count if self.labels is None else self._score)(gt, tracks)

    def _count(self, gt: Sequence, tracks: Sequence) -> dict:
        """Pass 1: plain OSPA per frame of the chunk (returned, and added to the means), and OSPA-T's step 1
        statistics."""
        frames, n, m, gi, ti, fr, dp = self._frames(gt, tracks)
        cp, nf = self.cp, len(frames)
        sel = matching_by_frame(gi, ti, cp - dp, fr)  # maximise the sum of c^p - d^p over pairs within c
        o, loc = _per_frame(n, m, np.bincount(fr[sel], cp - dp[sel], minlength=nf), cp, self.p)
        card = (cp * (n - m) / n) ** (1.0 / self.p)
        for name, values in (("ospa", o), ("localisation", loc), ("cardinality", card)):
            self.sums[name].add(values)
        g, t = self.gt_ids(gt.id), self.track_ids(tracks.id)
        self.n_g, self.n_t = grown(self.n_g, len(self.gt_ids)), grown(self.n_t, len(self.track_ids))
        np.add.at(self.n_g, g, 1)
        np.add.at(self.n_t, t, 1)
        self._count_together(g, t, gt, tracks)
        close = self.close(pair_key(g[gi], t[ti]))
        self.saving = grown(self.saving, len(self.close))
        np.add.at(self.saving, close, cp - dp)  # in frame order
        return {"frame": frames, "ospa": o, "localisation": loc, "cardinality": card}

    def _count_together(self, g: np.ndarray, t: np.ndarray, gt: Sequence, tracks: Sequence) -> None:
        """Frames together of each pair of a gt slot ``g`` and a track slot ``t`` (per row) present in one frame:
        counted on the chunk's (gt ids x track ids) grid where that is small, which needs no sort."""
        gu, gl = np.unique(g, return_inverse=True)
        tu, tl = np.unique(t, return_inverse=True)
        if gu.size * tu.size > _GRID_CELLS:
            for pg, pt in same_frame_pairs(gt, tracks):
                self.together.add(pair_key(g[pg], t[pt]))
            return
        grid = np.zeros(gu.size * tu.size, np.int64)
        for pg, pt in same_frame_pairs(gt, tracks):
            grid += np.bincount(gl[pg] * tu.size + tl[pt], minlength=grid.size)
        cell = np.flatnonzero(grid)  # row-major over ascending slots: the keys come ascending
        self.together.add_counts(pair_key(gu[cell // tu.size], tu[cell % tu.size]), grid[cell])

    def next_pass(self) -> None:
        """Between the passes: OSPA-T step 1 (module docstring), one global assignment of track ids to gt ids,
        solved on the pairs (evaluation/assignment.py); what only it needed is let go."""
        close = self.close.keys
        order = np.argsort(close)
        close, saving = close[order], self.saving[:len(close)][order]

        def pairs():  # each pair's weight: cp both + saving (OSPA-T's step 1), a segment at a time
            for keys, counts in zip(self.together.keys, self.together.counts):
                if not len(keys):
                    continue
                w = counts * self.cp
                lo, hi = np.searchsorted(close, keys[0]), np.searchsorted(close, keys[-1], side="right")
                w[np.searchsorted(keys, close[lo:hi])] += saving[lo:hi]  # close pairs: together too
                yield *split_pair_key(keys), w

        gt_slot, track_slot = ospa_t_labels(self.n_g[:len(self.gt_ids)], self.n_t[:len(self.track_ids)], pairs,
                                            self.cp)
        self.together = self.close = self.saving = None
        self.labels = np.zeros(len(self.track_ids), np.int64)
        self.assigned = np.zeros(len(self.track_ids), bool)
        self.labels[track_slot] = self.gt_ids.keys[gt_slot]
        self.assigned[track_slot] = True

    def track_labels(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """After ``next_pass``: the track ids in ascending order, the gt id each is labelled with, whether it is."""
        order = np.argsort(self.track_ids.keys)
        return self.track_ids.keys[order], self.labels[order], self.assigned[order]

    def _score(self, gt: Sequence, tracks: Sequence) -> np.ndarray:
        """Pass 2: OSPA-T per frame of the chunk with the labelled base distance (returned, and added to the
        mean)."""
        frames, n, m, gi, ti, fr, dp = self._frames(gt, tracks)
        cp = self.cp
        k = self.track_ids(tracks.id[ti], add=False)
        same = self.assigned[k] & (self.labels[k] == gt.id[gi])
        bp = dp + self.alpha ** self.p * ~same
        keep = np.flatnonzero(bp < cp)
        sel = keep[matching_by_frame(gi[keep], ti[keep], cp - bp[keep], fr[keep])]
        ot, _ = _per_frame(n, m, np.bincount(fr[sel], cp - bp[sel], minlength=len(frames)), cp, self.p)
        self.sums["ospa_t"].add(ot)
        return ot

    def result(self) -> OspaResult:
        """The means over frames, ``frames`` and ``labelled_tracks``."""
        means = {name: total.mean() for name, total in self.sums.items()}
        return OspaResult(**means, frames=self.sums["ospa"].count,
                          labelled_tracks=0 if self.assigned is None else int(self.assigned.sum()))


def ospa(gt: Sequence, tracks: Sequence, c: float = 1.0, p: float = 1.0, label_penalty: float = 1.0) -> dict:
    """Mean per-frame OSPA of ``tracks`` against ``gt`` with its ``localisation`` and ``cardinality`` parts, the
    labelled ``ospa_t``, the number of ``frames`` averaged, ``labelled_tracks`` (track ids given a gt label) and
    ``per_frame`` (lists ``frame``, ``ospa``, ``localisation``, ``cardinality``, ``ospa_t``); see the module docstring.
    ``c``: cut-off (m); ``p``: order; ``label_penalty``: OSPA-T's alpha (m)."""
    o = Ospa(c, p, label_penalty)
    per = o.add(gt, tracks)
    o.next_pass()
    per["ospa_t"] = o.add(gt, tracks)
    return {**o.result().as_dict(), "per_frame": {name: values.tolist() for name, values in per.items()}}
