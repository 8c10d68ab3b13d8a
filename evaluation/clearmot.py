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
   (``pipeline.lsap``, SciPy's algorithm) on Euclidean distance: the largest number of pairs within the threshold,
   and among those the smallest total distance. Pairs over the threshold are never matches.
3. A newly made match (o, h) is an ID switch (mismatch) when o's last known correspondence -- the hypothesis it
   was last matched to in any earlier frame, which persists over frames in which o was unmatched -- is not h.
4. Unmatched hypotheses are false positives, unmatched ground-truth objects are misses. The distances of all
   matches are summed for MOTP.

    MOTA = 1 - (FN + FP + IDSW) / GT,   MOTP = sum(match distances) / matches   (metres; lower is better).

Occlusion-aware ground truth (seed 000, Sec. IV-B: "we ignore all correspondences where the groundtruth track is
physically occluded"): ground-truth objects flagged ``ignore`` take part in the matching like any other, but a
hypothesis matched to one is not a false positive, the pair is not a match (no MOTP, no ID switch, and it does not
become the object's last known correspondence), and an ignored object left unmatched is not a miss. The pair is
still carried into the next frame's step 1, so a track that follows a person through an occlusion keeps them.

Beyond MOTA and MOTP (``ClearMotResult``):

- rIDS = IDS * GT / TP, the ID switches relative to the recall (seed 000, Sec. IV-B, after Leal-Taixe et al.).
- MT and ML: ground-truth persons matched in more than 80% / fewer than 20% of the frames they count in
  (seed 000 after Li et al. 2009); PT the rest. Fragmentations: the times a person's matched run is interrupted
  and resumed, over the frames they count in.
- ID switches split as seed 001 (Sec. 4) needs: an *id swap* when the new hypothesis was last matched to another
  person (it takes that person's identity), a *re-initialisation* otherwise (a new or unused track); seed 001's
  TSR = TP / GT, MR = FN / GT, GR = FP / GT, and its mismatch is our ID switch count.
- IDF1, IDP, IDR (Ristani et al. 2016): the one-to-one assignment of ground-truth ids to hypothesis ids over the
  whole sequence that maximises the frames a pair is within the threshold (IDTP), with IDF1 = 2 IDTP / (GT + H),
  H the hypotheses that count (those not matched to an ignored person).

Choices: the threshold is inclusive (a distance equal to it is a match) in both steps. Non-finite positions never
match. Ids must be unique within a frame. With no ground truth at all, MOTA, fp_rate and miss_rate are ``None``
(undefined, and NaN is not JSON); with no matches MOTP is ``None``.

Memory: the state grows with the persons and hypotheses seen (per person: frames counted, frames matched, matched
runs; per pair of a person and a hypothesis ever within the threshold: frames together), never with the frames, so
a run of any length is scored as it streams.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.compiled import kernel, pairwise
from pipeline.lsap import assignment

from .assignment import max_weight_matching
from .metric import Result, accumulate
from .sequence import Sequence, frames_of
from .tables import Slots, grown, pair_key, split_pair_key

__all__ = ["ClearMot", "ClearMotResult", "FrameResult", "evaluate"]

_EMPTY_I = np.zeros(0, np.int64)
_EMPTY_B = np.zeros(0, bool)
GATHER_ROWS = 1 << 14  # counted persons and close pairs gathered over frames before they are counted per person


@dataclass
class FrameResult:
    """Counts of one frame and its matched pairs (ordered as the ground truth was given); ignored persons and the
    hypotheses matched to them count nowhere."""

    gt: int
    matches: int
    fp: int
    fn: int
    id_switches: int
    matched_gt_ids: np.ndarray  # [k] int64
    matched_hyp_ids: np.ndarray  # [k] int64
    distances: np.ndarray  # [k] metres
    switched_gt_ids: np.ndarray  # the persons whose match this frame is an ID switch
    excused_hyp_ids: np.ndarray  # hypotheses matched to ignored persons: no false positives


@dataclass(frozen=True)
class ClearMotResult(Result):
    """Totals over every frame scored (module docstring); None where undefined."""

    mota: float | None
    motp_m: float | None
    fp: int
    fn: int
    id_switches: int
    id_swaps: int
    reinitialisations: int
    rids: float | None
    gt: int
    matches: int
    fp_rate: float | None
    miss_rate: float | None
    tsr: float | None
    mt: int
    pt: int
    ml: int
    fragmentations: int
    persons: int
    idf1: float | None
    idp: float | None
    idr: float | None
    idtp: int
    frames: int
    threshold_m: float


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


class ClearMot:
    """Accumulates CLEAR-MOT and the trajectory and identity measures over frames: a chunk of whole frames at a time
    (``add``, or ``scored_frames`` for each frame's result; evaluation/metric.py), or one frame given as arrays
    (``update``, ``update_dissimilarity``: a loop scoring as it goes); then ``result``."""

    passes = 1

    def __init__(self, threshold: float = 1.0):
        """``threshold``: largest ground-plane distance (m, inclusive) of a match; 1 m as in seed 000 Sec. IV-B,
        0.3 m as in seeds 001 and 003."""
        threshold = float(threshold)
        if not np.isfinite(threshold) or threshold < 0.0:
            raise ValueError("threshold must be finite and >= 0")
        self.threshold = threshold
        # Pairs of the previous frame (step 1), ignored ones included, sorted by gt id.
        self._prev_gt = self._prev_hyp = _EMPTY_I
        # Last known correspondence of every gt id ever matched (step 3), and of every hypothesis id the gt id it
        # was last matched to (to tell id swaps from re-initialisations), each sorted by key.
        self._last_gt = self._last_hyp = _EMPTY_I
        self._hyp_key = self._hyp_gt = _EMPTY_I
        self._frames = self._gt = self._matches = self._fp = self._fn = self._ids = self._swaps = 0
        self._dist_sum = 0.0
        self._hyps = 0
        self._last_frame: int | None = None  # the frame number last scored by ``scored_frames``
        # Per counted person (a slot): frames counted, frames matched, matched runs, matched in their last counted
        # frame; per pair of a counted person and a counted hypothesis: frames within the threshold (IDF1). Frames
        # are gathered (``_gathered``: counted ids, their matched flags, pair ids) and absorbed a batch at a time.
        self._persons, self._hyp_slots, self._pairs = Slots(), Slots(), Slots()
        self._counted = self._matched = self._runs = np.zeros(0, np.int64)
        self._was_matched = np.zeros(0, bool)
        self._together = np.zeros(0, np.int64)
        self._gathered: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        self._gathered_rows = 0

    def update(self, gt_ids: np.ndarray, gt_pos: np.ndarray, hyp_ids: np.ndarray, hyp_pos: np.ndarray,
               gt_ignore: np.ndarray | None = None) -> FrameResult:
        """Score one frame: gt ids [n], positions [n, 2], optional ``gt_ignore`` [n] (occluded or out of range);
        hypothesis ids [m], positions [m, 2] (metres)."""
        gt_ids, hyp_ids, ignore = self._checked(gt_ids, hyp_ids, gt_ignore)
        n, m = gt_ids.size, hyp_ids.size
        gt_pos, hyp_pos = _pos(gt_pos, n, "gt_pos"), _pos(hyp_pos, m, "hyp_pos")
        return self._update(gt_ids, ignore, hyp_ids, _distances(gt_pos, hyp_pos))

    def update_dissimilarity(self, gt_ids: np.ndarray, hyp_ids: np.ndarray, dissimilarity: np.ndarray,
                             gt_ignore: np.ndarray | None = None) -> FrameResult:
        """Score one frame from a dissimilarity [n, m] of each person and hypothesis in place of their distance on
        the ground: 1 - IoU of image boxes, say, with the threshold 0.5 for seed 003's 2D matching at IoU 0.5 (MOTP
        is then the mean of 1 - IoU over the matches)."""
        gt_ids, hyp_ids, ignore = self._checked(gt_ids, hyp_ids, gt_ignore)
        d = np.ascontiguousarray(dissimilarity, float)
        if d.shape != (gt_ids.size, hyp_ids.size):
            raise ValueError(f"dissimilarity must be [{gt_ids.size}, {hyp_ids.size}], got {list(d.shape)}")
        return self._update(gt_ids, ignore, hyp_ids, d)

    @staticmethod
    def _checked(gt_ids, hyp_ids, gt_ignore):
        gt_ids, hyp_ids = _ids(gt_ids, "gt_ids"), _ids(hyp_ids, "hyp_ids")
        n = gt_ids.size
        ignore = np.zeros(n, bool) if gt_ignore is None else np.asarray(gt_ignore, bool).reshape(-1)
        if ignore.size != n:
            raise ValueError(f"gt_ignore must have {n} entries, got {ignore.size}")
        return gt_ids, hyp_ids, ignore

    def _update(self, gt_ids, ignore, hyp_ids, dist) -> FrameResult:
        """One frame's steps 1-4 (module docstring) in ``_frame``; the totals and the IDF1 gathering here."""
        (self._prev_gt, self._prev_hyp, self._last_gt, self._last_hyp, self._hyp_key, self._hyp_gt, counts, dist_sum,
         matched_gt, matched_hyp, distances, switched, excused, counted, matched, close_gt, close_hyp) = _frame(
            gt_ids, ignore, hyp_ids, dist, self.threshold, self._prev_gt, self._prev_hyp, self._last_gt,
            self._last_hyp, self._hyp_key, self._hyp_gt)
        n_counted, k, m_counted, switches, swaps = counts.tolist()
        self._frames += 1
        self._gt += n_counted
        self._matches += k
        self._fp += m_counted - k
        self._fn += n_counted - k
        self._ids += switches
        self._swaps += swaps
        self._dist_sum += dist_sum
        self._hyps += m_counted
        self._gathered.append((counted, matched, close_gt, close_hyp))
        self._gathered_rows += n_counted + close_gt.size
        if self._gathered_rows >= GATHER_ROWS:
            self._absorb()
        return FrameResult(n_counted, k, m_counted - k, n_counted - k, switches, matched_gt, matched_hyp, distances,
                           switched, excused)

    def _absorb(self) -> None:
        """The gathered frames into the per-person and per-pair counts. Per person, in frame order: a matched run
        starts where they are matched after an unmatched counted frame (or in their first)."""
        if not self._gathered:
            return
        ids, matched, pair_g, pair_h = (np.concatenate(parts) for parts in zip(*self._gathered))
        frame = np.repeat(np.arange(len(self._gathered)), [len(g[0]) for g in self._gathered])
        self._gathered, self._gathered_rows = [], 0
        slot = self._persons(ids)
        n = len(self._persons)
        self._counted, self._matched, self._runs = (grown(a, n) for a in (self._counted, self._matched, self._runs))
        self._was_matched = grown(self._was_matched, n)
        order = np.lexsort((frame, slot))
        slot, matched = slot[order], matched[order]
        first = np.r_[True, slot[1:] != slot[:-1]]  # each person's first counted frame of the batch
        before = np.where(first, self._was_matched[slot], np.r_[False, matched[:-1]])
        np.add.at(self._counted, slot, 1)
        np.add.at(self._matched, slot, matched)
        np.add.at(self._runs, slot, matched & ~before)
        self._was_matched[slot] = matched  # the last write per person is their latest frame's
        keys, together = np.unique(pair_key(self._persons(pair_g), self._hyp_slots(pair_h)), return_counts=True)
        pairs = self._pairs(keys)
        self._together = grown(self._together, len(self._pairs))
        self._together[pairs] += together

    def _trajectories(self) -> dict:
        """MT, PT, ML and fragmentations of the ground-truth persons over the frames they count in."""
        self._absorb()
        n = len(self._persons)
        ratio = self._matched[:n] / self._counted[:n]
        return {"mt": int((ratio > 0.8).sum()), "pt": int(((ratio >= 0.2) & (ratio <= 0.8)).sum()),
                "ml": int((ratio < 0.2).sum()), "fragmentations": int(np.maximum(self._runs[:n] - 1, 0).sum()),
                "persons": n}

    def _identity(self) -> dict:
        """IDF1, IDP, IDR: the best one-to-one assignment of gt ids to hypothesis ids over the sequence (a sparse
        maximum-weight matching of the pairs ever within the threshold)."""
        self._absorb()
        together = self._together[:len(self._pairs)]
        idtp = int(together[max_weight_matching(*split_pair_key(self._pairs.keys), together)].sum())
        gt, hyps = self._gt, self._hyps
        return {"idf1": None if gt + hyps == 0 else 2 * idtp / (gt + hyps),
                "idp": None if hyps == 0 else idtp / hyps, "idr": None if gt == 0 else idtp / gt, "idtp": idtp}

    def result(self) -> ClearMotResult:
        """Totals over all frames so far (see module docstring)."""
        gt, tp = self._gt, self._matches
        return ClearMotResult(
            mota=None if gt == 0 else 1.0 - (self._fp + self._fn + self._ids) / gt,
            motp_m=None if tp == 0 else self._dist_sum / tp,
            fp=self._fp,
            fn=self._fn,
            id_switches=self._ids,
            id_swaps=self._swaps,
            reinitialisations=self._ids - self._swaps,
            rids=None if tp == 0 else self._ids * gt / tp,
            gt=gt,
            matches=tp,
            fp_rate=None if gt == 0 else self._fp / gt,
            miss_rate=None if gt == 0 else self._fn / gt,
            tsr=None if gt == 0 else tp / gt,
            **self._trajectories(),
            **self._identity(),
            frames=self._frames,
            threshold_m=self.threshold,
        )

    def add(self, gt: Sequence, tracks: Sequence) -> None:
        """Score a chunk of whole frames (``scored_frames`` without the per-frame results)."""
        for _ in self.scored_frames(gt, tracks):
            pass

    def scored_frames(self, gt: Sequence, tracks: Sequence):
        """Score a chunk of whole frames frame by frame (a chunk of a longer sequence too: the ClearMot remembers the
        last frame it scored), yielding each frame number with its FrameResult. A frame number missing between two
        is an empty frame: correspondences are not kept across it."""
        for name, seq in (("ground truth", gt), ("tracks", tracks)):
            dup = (np.diff(seq.frame) == 0) & (np.diff(seq.id) == 0) if len(seq) > 1 else _EMPTY_B
            if dup.any():
                k = int(np.flatnonzero(dup)[0])
                raise ValueError(f"{name}: id {seq.id[k]} appears twice in frame {seq.frame[k]}")
        frames = frames_of(gt, tracks)
        gb, tb = gt.bounds(frames), tracks.bounds(frames)
        for k, frame in enumerate(frames.tolist()):
            if self._last_frame is not None and frame != self._last_frame + 1:
                self._prev_gt = self._prev_hyp = _EMPTY_I  # a frame without rows between: nothing was matched in it
            self._last_frame = frame
            g, t = slice(gb[k], gb[k + 1]), slice(tb[k], tb[k + 1])
            dist = _distances(gt.position[g], tracks.position[t])
            yield frame, self._update(gt.id[g], gt.ignore[g], tracks.id[t], dist)


@kernel
def _distances(a, b):
    """The Euclidean distances [n, m] of points a [n, 2] and b [m, 2], as SciPy's ``cdist`` gives them."""
    out = np.empty((len(a), len(b)))
    for i in range(len(a)):
        for j in range(len(b)):
            dx, dy = a[i, 0] - b[j, 0], a[i, 1] - b[j, 1]
            out[i, j] = math.sqrt(dx * dx + dy * dy)
    return out


@kernel
def _find(keys, key):
    """The place of ``key`` in the sorted ``keys``, or -1."""
    p = np.searchsorted(keys, key)
    return p if p < len(keys) and keys[p] == key else -1


@kernel
def _put(keys, values, new_keys, new_values):
    """The sorted map (keys, values) with each of ``new_keys`` (unique) set to its value."""
    values = values.copy()
    fresh = np.zeros(len(new_keys), np.bool_)
    for i in range(len(new_keys)):
        p = _find(keys, new_keys[i])
        if p >= 0:
            values[p] = new_values[i]
        else:
            fresh[i] = True
    if not fresh.any():
        return keys, values
    k, v = np.concatenate((keys, new_keys[fresh])), np.concatenate((values, new_values[fresh]))
    order = np.argsort(k)
    return k[order], v[order]


@kernel
def _frame(gt_ids, ignore, hyp_ids, dist, thr, prev_gt, prev_hyp, last_gt, last_hyp, hyp_key, hyp_gt):
    """Steps 1-4 of one frame (module docstring) on the distances ``dist`` [n, m]. The state: last frame's pairs
    (prev_gt -> prev_hyp, ignored ones included), each person's last hypothesis (last_gt -> last_hyp), each
    hypothesis's last person (hyp_key -> hyp_gt), maps on sorted keys, returned updated. Then the counts (counted
    persons, matches, counted hypotheses, ID switches, id swaps), the sum of the match distances (numpy's pairwise
    order), the matches' ids and distances in ground-truth order, the switched persons, the excused hypotheses, the
    counted persons with their matched flags, and the pairs of counted ids within the threshold."""
    n, m = len(gt_ids), len(hyp_ids)
    gt_free, hyp_free = np.ones(n, np.bool_), np.ones(m, np.bool_)
    pair_g, pair_h = np.empty(min(n, m), np.int64), np.empty(min(n, m), np.int64)
    # 1: last frame's pairs still present and within the threshold
    kept = 0
    if m and len(prev_gt):
        order = np.argsort(hyp_ids)
        by_id = hyp_ids[order]
        for g in range(n):
            p = _find(prev_gt, gt_ids[g])
            if p >= 0:
                q = _find(by_id, prev_hyp[p])
                if q >= 0 and dist[g, order[q]] <= thr:
                    pair_g[kept], pair_h[kept] = g, order[q]
                    gt_free[g], hyp_free[order[q]] = False, False
                    kept += 1
    # 2: the rest matched by the Hungarian method, on the rows and columns with an allowed pair; a forbidden pair's
    # cost exceeds any sum of allowed ones, so the most allowed pairs are made first, then the least distance
    made = kept
    gi, hi = np.flatnonzero(gt_free), np.flatnonzero(hyp_free)
    row_allowed, column_allowed = np.zeros(len(gi), np.bool_), np.zeros(len(hi), np.bool_)
    for a in range(len(gi)):
        for b in range(len(hi)):
            if dist[gi[a], hi[b]] <= thr:  # False for NaN
                row_allowed[a], column_allowed[b] = True, True
    gi, hi = gi[row_allowed], hi[column_allowed]
    if len(gi):
        big = thr * min(len(gi), len(hi)) + 1.0
        cost = np.empty((len(gi), len(hi)))
        for a in range(len(gi)):
            for b in range(len(hi)):
                d = dist[gi[a], hi[b]]
                cost[a, b] = d if d <= thr else big
        rows, columns, _ = assignment(cost, False)
        for t in range(len(rows)):
            g, h = gi[rows[t]], hi[columns[t]]
            if dist[g, h] <= thr:
                pair_g[made], pair_h[made] = g, h
                made += 1
    pair_g, pair_h = pair_g[:made], pair_h[:made]
    # every pair carried into the next frame, ignored ones too, by gt id
    by_gt = np.argsort(gt_ids[pair_g])
    next_gt, next_hyp = gt_ids[pair_g][by_gt], hyp_ids[pair_h][by_gt]
    # 3: a new counted match other than the person's last known correspondence is an ID switch; an id swap when its
    # hypothesis was last another person's
    new = pair_g[kept:][~ignore[pair_g[kept:]]]
    new_gid, new_hid = gt_ids[new], hyp_ids[pair_h[kept:][~ignore[pair_g[kept:]]]]
    switched = np.zeros(len(new), np.bool_)
    for t in range(len(new)):
        p = _find(last_gt, new_gid[t])
        switched[t] = p >= 0 and last_hyp[p] != new_hid[t]
    swaps = 0
    for t in np.flatnonzero(switched):
        p = _find(hyp_key, new_hid[t])
        swaps += p >= 0 and hyp_gt[p] != new_gid[t]
    if len(new):
        last_gt, last_hyp = _put(last_gt, last_hyp, new_gid, new_hid)
        hyp_key, hyp_gt = _put(hyp_key, hyp_gt, new_hid, new_gid)
    # 4: the counts; the matches in ground-truth order
    match_h = np.full(n, -1)
    for t in range(made):
        if not ignore[pair_g[t]]:
            match_h[pair_g[t]] = pair_h[t]
    mg = np.flatnonzero(match_h >= 0)
    mh = match_h[mg]
    md = np.empty(len(mg))
    for t in range(len(mg)):
        md[t] = dist[mg[t], mh[t]]
    hyp_counted = np.ones(m, np.bool_)
    for t in range(made):
        if ignore[pair_g[t]]:
            hyp_counted[pair_h[t]] = False
    counted = np.flatnonzero(~ignore)
    n_counted, m_counted = len(counted), int(hyp_counted.sum())
    close = 0
    if n_counted and m_counted:
        for g in counted:
            for h in range(m):
                close += dist[g, h] <= thr and hyp_counted[h]
    close_gt, close_hyp = np.empty(close, np.int64), np.empty(close, np.int64)
    if close:
        at = 0
        for g in counted:
            for h in range(m):
                if dist[g, h] <= thr and hyp_counted[h]:
                    close_gt[at], close_hyp[at] = gt_ids[g], hyp_ids[h]
                    at += 1
    counts = np.array([n_counted, len(mg), m_counted, int(switched.sum()), swaps])
    return (next_gt, next_hyp, last_gt, last_hyp, hyp_key, hyp_gt, counts, pairwise(md, 0, len(md)), gt_ids[mg],
            hyp_ids[mh], md, new_gid[switched], hyp_ids[~hyp_counted], gt_ids[counted], match_h[counted] >= 0,
            close_gt, close_hyp)


def evaluate(gt: Sequence, tracks: Sequence, threshold: float = 1.0) -> dict:
    """CLEAR-MOT and the trajectory and identity measures of ``tracks`` against ``gt`` over every frame either
    has rows in (``ClearMotResult`` as JSON values; ``gt.ignore`` marks occluded or out-of-range persons)."""
    cm = ClearMot(threshold)
    accumulate([cm], [(gt, tracks)])
    return cm.result().as_dict()
