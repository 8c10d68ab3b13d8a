"""CLEAR-MOT metrics (MOTA, MOTP) for 2D point targets on the ground plane.

Why: the testbed has to score a people tracker against the simulator's ground truth with the metrics the tracking
literature reports, so that numbers are comparable with published results. We use the CLEAR-MOT metrics of

    K. Bernardin and R. Stiefelhagen, "Evaluating multiple object tracking performance: the CLEAR MOT metrics",
    EURASIP Journal on Image and Video Processing, 2008, article 246309.

with the Euclidean distance between ground-plane positions as the distance measure and a 1 m matching threshold,
as the SPENCER people-tracking evaluation does (seed 000, Sec. IV-B).

Per frame t (paper Sec. 2.1):

1. Every correspondence (gt o, hyp h) matched in frame t-1 is kept if both o and h are present in frame t and
   their distance is ``<= threshold`` (kept even when another hypothesis is now nearer).
2. The remaining ground-truth objects and hypotheses are matched with the Hungarian method
   (``scipy.optimize.linear_sum_assignment``) on Euclidean distance: the largest number of pairs within the
   threshold, and among those the smallest total distance. Pairs over the threshold are never matches.
3. A newly made match (o, h) is an ID switch (mismatch) when o's last known correspondence -- the hypothesis it
   was last matched to in any earlier frame, which persists over frames in which o was unmatched -- is not h.
4. Unmatched hypotheses are false positives, unmatched ground-truth objects are misses. The distances of all
   matches are summed for MOTP.

    MOTA = 1 - (FN + FP + IDSW) / GT,   MOTP = sum(match distances) / matches   (metres; lower is better).

Choices: the threshold is inclusive (a distance equal to it is a match) in both steps. Non-finite positions never
match. Ids must be unique within a frame. With no ground truth at all, MOTA, fp_rate and miss_rate are ``None``
(undefined, and NaN is not JSON); with no matches MOTP is ``None``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

__all__ = ["ClearMot", "FrameResult"]

_EMPTY_I = np.zeros(0, np.int64)
_EMPTY_F = np.zeros(0, np.float64)


@dataclass
class FrameResult:
    """Counts of one frame and its matched pairs (ordered as the ground truth was given)."""

    gt: int
    matches: int
    fp: int
    fn: int
    id_switches: int
    matched_gt_ids: np.ndarray  # [k] int64
    matched_hyp_ids: np.ndarray  # [k] int64
    distances: np.ndarray  # [k] metres


def _ids(a, name: str) -> np.ndarray:
    ids = np.asarray(a, dtype=np.int64).reshape(-1)
    if ids.size > 1 and np.unique(ids).size != ids.size:
        raise ValueError(f"{name} must be unique within a frame")
    return ids


def _pos(a, n: int, name: str) -> np.ndarray:
    pos = np.asarray(a, dtype=np.float64)
    if pos.size == 0 and n == 0:
        return np.zeros((0, 2))
    if pos.shape != (n, 2):
        raise ValueError(f"{name} must have shape ({n}, 2), got {pos.shape}")
    return pos


def _lookup(keys_sorted: np.ndarray, values: np.ndarray, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Look ``query`` up in a map of sorted keys and aligned values: (found mask, values; junk where not found)."""
    if keys_sorted.size == 0 or query.size == 0:
        return np.zeros(query.size, bool), np.zeros(query.size, np.int64)
    p = np.searchsorted(keys_sorted, query)
    np.minimum(p, keys_sorted.size - 1, out=p)
    return keys_sorted[p] == query, values[p]


class ClearMot:
    """Accumulates CLEAR-MOT over frames."""

    def __init__(self, threshold: float = 1.0):
        """``threshold``: largest ground-plane distance (m, inclusive) of a match; 1 m as in seed 000 Sec. IV-B."""
        threshold = float(threshold)
        if not np.isfinite(threshold) or threshold < 0.0:
            raise ValueError("threshold must be finite and >= 0")
        self.threshold = threshold
        # Matches of the previous frame (step 1), sorted by gt id.
        self._prev_gt = _EMPTY_I
        self._prev_hyp = _EMPTY_I
        # Last known correspondence of every gt id ever matched (step 3), sorted by gt id.
        self._last_gt = _EMPTY_I
        self._last_hyp = _EMPTY_I
        self._frames = self._gt = self._matches = self._fp = self._fn = self._ids = 0
        self._dist_sum = 0.0

    def update(self, gt_ids: np.ndarray, gt_pos: np.ndarray, hyp_ids: np.ndarray, hyp_pos: np.ndarray) -> FrameResult:
        """Score one frame: gt ids [n], positions [n, 2]; hypothesis ids [m], positions [m, 2] (metres)."""
        gt_ids = _ids(gt_ids, "gt_ids")
        hyp_ids = _ids(hyp_ids, "hyp_ids")
        n, m = gt_ids.size, hyp_ids.size
        gt_pos = _pos(gt_pos, n, "gt_pos")
        hyp_pos = _pos(hyp_pos, m, "hyp_pos")
        thr = self.threshold

        # Step 1: keep last frame's correspondences that are still present and within the threshold.
        gt_free = np.ones(n, bool)
        hyp_free = np.ones(m, bool)
        keep_g, keep_h, keep_d = _EMPTY_I, _EMPTY_I, _EMPTY_F
        had, prev_h = _lookup(self._prev_gt, self._prev_hyp, gt_ids)
        if had.any() and m:
            order = np.argsort(hyp_ids)
            present, hj_all = _lookup(hyp_ids[order], order, prev_h)
            cand = np.flatnonzero(had & present)
            hj = hj_all[cand]
            d = np.sqrt(((gt_pos[cand] - hyp_pos[hj]) ** 2).sum(axis=1))
            ok = d <= thr
            keep_g, keep_h, keep_d = cand[ok], hj[ok], d[ok]
            gt_free[keep_g] = False
            hyp_free[keep_h] = False

        # Step 2: Hungarian matching of the rest; the large finite cost of a forbidden pair exceeds any sum of
        # allowed distances, so the solve maximises the number of allowed pairs first, then minimises distance.
        new_g, new_h, new_d = _EMPTY_I, _EMPTY_I, _EMPTY_F
        gi = np.flatnonzero(gt_free)
        hi = np.flatnonzero(hyp_free)
        if gi.size and hi.size:
            dist = cdist(gt_pos[gi], hyp_pos[hi])
            allowed = dist <= thr  # False for NaN
            if allowed.any():
                big = thr * min(gi.size, hi.size) + 1.0
                r, c = linear_sum_assignment(np.where(allowed, dist, big))
                ok = allowed[r, c]
                new_g, new_h, new_d = gi[r[ok]], hi[c[ok]], dist[r[ok], c[ok]]

        # Step 3: a new match contradicting the gt's last known correspondence is an ID switch.
        new_gid, new_hid = gt_ids[new_g], hyp_ids[new_h]
        known, last_h = _lookup(self._last_gt, self._last_hyp, new_gid)
        switches = int(np.count_nonzero(known & (last_h != new_hid)))
        if new_gid.size:
            self._remember(new_gid, new_hid, known)

        # Step 4: counts; matched pairs in ground-truth input order.
        mg = np.concatenate([keep_g, new_g])
        order = np.argsort(mg, kind="stable")
        mg = mg[order]
        mh = np.concatenate([keep_h, new_h])[order]
        md = np.concatenate([keep_d, new_d])[order]
        m_gid, m_hid = gt_ids[mg], hyp_ids[mh]
        k = mg.size
        o = np.argsort(m_gid)
        self._prev_gt, self._prev_hyp = m_gid[o], m_hid[o]

        res = FrameResult(n, k, m - k, n - k, switches, m_gid, m_hid, md)
        self._frames += 1
        self._gt += n
        self._matches += k
        self._fp += m - k
        self._fn += n - k
        self._ids += switches
        self._dist_sum += float(md.sum())
        return res

    def _remember(self, gid: np.ndarray, hid: np.ndarray, known: np.ndarray) -> None:
        """Set the last known correspondence of ``gid`` to ``hid`` (``known``: gid already in the map)."""
        if known.any():
            p = np.searchsorted(self._last_gt, gid[known])
            self._last_hyp[p] = hid[known]
        if not known.all():
            g = np.concatenate([self._last_gt, gid[~known]])
            h = np.concatenate([self._last_hyp, hid[~known]])
            o = np.argsort(g)
            self._last_gt, self._last_hyp = g[o], h[o]

    def summary(self) -> dict:
        """Totals over all frames so far as plain, JSON-serialisable Python values (see module docstring)."""
        gt = self._gt
        return {
            "mota": None if gt == 0 else 1.0 - (self._fp + self._fn + self._ids) / gt,
            "motp_m": None if self._matches == 0 else self._dist_sum / self._matches,
            "fp": self._fp,
            "fn": self._fn,
            "id_switches": self._ids,
            "gt": gt,
            "matches": self._matches,
            "fp_rate": None if gt == 0 else self._fp / gt,
            "miss_rate": None if gt == 0 else self._fn / gt,
            "frames": self._frames,
        }
