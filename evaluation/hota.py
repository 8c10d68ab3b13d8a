"""HOTA (Higher Order Tracking Accuracy) for 2D point targets on the ground plane.

Why: MOTA (clearmot.py) is dominated by detection and charges an identity error once, at the switch; HOTA weighs
detection and association evenly and is what current tracking benchmarks rank by. We use

    J. Luiten, A. Osep, P. Dendorfer, P. Torr, A. Geiger, L. Leal-Taixe and B. Leibe, "HOTA: A Higher Order Metric
    for Evaluating Multi-Object Tracking", International Journal of Computer Vision 129:548-578, 2021.

with the point convention of the MOT benchmarks' 3D evaluation (TrackEval, MOT15-3D): the similarity of a ground-truth
point and a track point at ground-plane distance d is S = max(0, 1 - d / scale), scale = 2 m, so that alpha = 0.5
is the 1 m gate of clearmot.py.

1. Global alignment. In every frame each (gt, track) pair gets the soft IoU S / (row sum of S + column sum of S - S);
   summed over the frames per (gt id, track id) this is a soft count P of potential matches, and
   A = P / (n_gt + n_track - P), n being the number of frames each id is present in.
2. Matching. Per frame, the Hungarian method (``pipeline.lsap``, SciPy's algorithm) maximises the sum of A * S
   over the matched pairs. As in TrackEval, the code the benchmarks use, this one matching serves every alpha and a
   matched pair is a true positive (TP) at alpha when S >= alpha (up to 1e-12 of rounding). The paper's formulation
   leaves pairs below alpha out of the matching itself, a matching per alpha; that differs where a matched pair below
   alpha pre-empts one above it (see tests/test_hota.py).
3. Per alpha: FN = gt points - TP, FP = track points - TP, DetA = TP / (TP + FN + FP). A (gt id, track id) pair with
   TPA true positives has AssIoU = TPA / (n_gt + n_track - TPA); AssA = mean over the TPs of their pair's AssIoU;
   HOTA = sqrt(DetA * AssA); LocA = mean S over the TPs.
4. ``hota``, ``deta``, ``assa`` and ``loca`` are the means over the 19 alphas 0.05, 0.10, ..., 0.95 (the paper's
   integral over alpha).

Conventions (TrackEval's, so numbers equal the benchmarks'): at an alpha without TPs AssA = 0 (HOTA is 0 there
anyway, DetA being 0) and LocA = 1. Undefined values are ``None`` (NaN is not JSON): with no TP at any alpha, AssA
and LocA (means over TPs) are ``None`` (TrackEval: 0 and 1); with neither gt nor track points every score is
``None``. The caller removes ignored ground-truth rows first: every row counts. Ids must be unique within a frame;
non-finite positions never match.

Speed: only pairs closer than ``scale`` have S > 0, so pairs are generated vectorised and filtered, a pair alone in
its row and column is matched without a solve, and the Hungarian runs per frame on the rest only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evaluation.metric import Result, accumulate
from evaluation.sequence import Sequence, frames_of
from evaluation.tables import Slots, grown, pair_key, split_pair_key
from pipeline.compiled import kernel
from pipeline.lsap import linear_sum_assignment

__all__ = ["Hota", "HotaResult", "hota", "ALPHAS", "same_frame_pairs", "close_pairs", "matching_by_frame", "check_ids"]

ALPHAS = np.arange(1, 20) / 20  # 0.05 ... 0.95
_TOL = 1e-12  # a similarity this close below alpha still counts (rounding of d / scale)
_CHUNK = 1 << 18  # candidate pairs generated at once (memory bound: a few MB)
_EMPTY_I = np.zeros(0, np.int64)


def check_ids(seq: Sequence, name: str) -> None:
    """Raise if an id occurs twice in one frame: the matching would be ambiguous."""
    if len(seq) > 1:
        o = np.lexsort((seq.id, seq.frame))
        f, i = seq.frame[o], seq.id[o]
        if ((f[1:] == f[:-1]) & (i[1:] == i[:-1])).any():
            raise ValueError(f"{name} ids must be unique within a frame")


def same_frame_pairs(gt: Sequence, tracks: Sequence):
    """Every (gt row, track row) of the same frame, sorted by gt row then track row (so also by frame), in batches
    of about ``_CHUNK`` pairs (memory bound): an iterator of (gt rows, track rows)."""
    if not len(gt) or not len(tracks):
        return
    frames = frames_of(gt, tracks)
    tb = tracks.bounds(frames)
    k = np.searchsorted(frames, gt.frame)
    t0 = tb[k]
    cnt = tb[k + 1] - t0  # track rows in each gt row's frame
    ends = np.cumsum(cnt)
    lo, n = 0, len(gt)
    while lo < n:
        base = int(ends[lo - 1]) if lo else 0
        hi = max(lo + 1, int(np.searchsorted(ends, base + _CHUNK, side="right")))
        c = cnt[lo:hi]
        total = int(ends[hi - 1]) - base
        if total:
            # Track row = first track row of the frame + offset within this gt row's block.
            yield np.repeat(np.arange(lo, hi), c), np.arange(total) + np.repeat(t0[lo:hi] - (ends[lo:hi] - c - base), c)
        lo = hi


def close_pairs(gt: Sequence, tracks: Sequence, radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every (gt row, track row) of the same frame closer than ``radius`` (strictly; never for non-finite
    positions), with its distance, sorted by gt row then track row (so also by frame)."""
    if not len(gt) or not len(tracks):
        return _EMPTY_I, _EMPTY_I, np.zeros(0)
    frames = frames_of(gt, tracks)
    bounds, frame = tracks.bounds(frames), np.searchsorted(frames, gt.frame)
    first, last = bounds[frame], bounds[frame + 1]  # each gt row's frame's track rows
    return _close_pairs(np.ascontiguousarray(gt.position), np.ascontiguousarray(tracks.position), first, last,
                        float(radius), radius * radius * (1.0 + 1e-9))


@kernel
def _close_pairs(gt, tracks, first, last, radius, r2):
    """``close_pairs`` on the positions, each gt row i against the track rows first[i]:last[i]: the squared
    distance against ``r2`` (just above radius^2), then the distance against ``radius``; counted, then filled."""
    count = 0
    for i in range(len(gt)):
        for j in range(first[i], last[i]):
            dx, dy = gt[i, 0] - tracks[j, 0], gt[i, 1] - tracks[j, 1]
            d2 = dx * dx + dy * dy
            count += d2 < r2 and math.sqrt(d2) < radius
    rows, cols, dist = np.empty(count, np.int64), np.empty(count, np.int64), np.empty(count)
    at = 0
    for i in range(len(gt)):
        for j in range(first[i], last[i]):
            dx, dy = gt[i, 0] - tracks[j, 0], gt[i, 1] - tracks[j, 1]
            d2 = dx * dx + dy * dy
            if d2 < r2:
                d = math.sqrt(d2)
                if d < radius:
                    rows[at], cols[at], dist[at] = i, j, d
                    at += 1
    return rows, cols, dist


def _rank(a: np.ndarray) -> np.ndarray:
    """Rank of each value among the distinct values of ``a`` (small non-negative ints), by counting, not sorting."""
    used = np.zeros(int(a.max()) + 1, bool)
    used[a] = True
    return (np.cumsum(used) - 1)[a]


def matching_by_frame(rows: np.ndarray, cols: np.ndarray, weight: np.ndarray, group: np.ndarray) -> np.ndarray:
    """Indices of the pairs of a maximum-weight one-to-one matching of rows to columns.

    ``weight`` > 0; ``group``: the frame. Pairs are sorted by frame then row, and rows and columns are numbered in
    frame order (sequence rows), so a frame's rows, and its columns, are contiguous; frames are solved apart. A pair
    alone in its row and column is always matched; the Hungarian method solves each frame's other pairs (a
    maximum-weight assignment on the zero-filled dense block is a maximum-weight matching: the zero entries it picks
    are dropped).
    """
    if rows.size == 0:
        return _EMPTY_I
    lone = (np.bincount(rows)[rows] == 1) & (np.bincount(cols)[cols] == 1)
    rest = np.flatnonzero(~lone)
    chosen = [np.flatnonzero(lone)]
    if rest.size:
        r, c, w, g = rows[rest], cols[rest], weight[rest], group[rest]
        starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
        size = np.diff(np.r_[starts, rest.size])
        # Row and column numbers local to the group, without sorting: rank among the rows (columns) in use, minus
        # the group's first rank (the rows, and the columns, of a group are contiguous).
        lr, lc = _rank(r), _rank(c)
        lr -= np.repeat(lr[starts], size)
        lc -= np.repeat(np.minimum.reduceat(lc, starts), size)
        nr = np.maximum.reduceat(lr, starts) + 1
        nc = np.maximum.reduceat(lc, starts) + 1
        for s, e, a, b in zip(starts.tolist(), (starts + size).tolist(), nr.tolist(), nc.tolist()):
            flat = lr[s:e] * b + lc[s:e]
            dense = np.zeros(a * b)
            dense[flat] = w[s:e]
            where = np.full(a * b, -1)
            where[flat] = np.arange(s, e)
            i, j = linear_sum_assignment(dense.reshape(a, b), maximize=True)
            p = where[i * b + j]
            chosen.append(rest[p[p >= 0]])
    return np.sort(np.concatenate(chosen))


@dataclass(frozen=True)
class HotaPerAlpha(Result):
    """The figures at each alpha (lists over ``alpha``)."""

    alpha: list
    hota: list
    deta: list
    assa: list
    loca: list
    tp: list
    fn: list
    fp: list


@dataclass(frozen=True)
class HotaResult(Result):
    """HOTA, DetA, AssA, LocA: the means over alpha (module docstring), and ``per_alpha``."""

    hota: float | None
    deta: float | None
    assa: float | None
    loca: float | None
    per_alpha: HotaPerAlpha


def _jsonable(a) -> list:
    return [None if x is None else float(x) for x in a]


def _scale(scale: float) -> float:
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0.0:
        raise ValueError("scale must be finite and > 0")
    return scale


class Hota:
    """HOTA over a sequence given as chunks of whole frames in frame order, in two passes over the same chunks
    (evaluation/metric.py; steps 1 and 2-3 of the module docstring): ``add`` every chunk (counting), ``next_pass``
    (the alignment), ``add`` every chunk again (matching), ``result``. The state is per gt id, per track id and per
    (gt id, track id) pair ever closer than ``scale``; sums are taken in frame order, so the figures do not depend
    on where the chunks are cut."""

    passes = 2

    def __init__(self, scale: float = 2.0):
        self.scale = _scale(scale)
        self.gt_ids, self.track_ids, self.pairs = Slots(), Slots(), Slots()
        self.n_g = self.n_t = np.zeros(0, np.int64)  # frames each gt (track) id is present in
        self.potential = np.zeros(0)  # soft count of potential matches per pair
        self.alignment = None
        self.hits = np.zeros((0, ALPHAS.size + 1), np.int32)  # per pair: matches by the number of alphas <= S
        self.loc_sum = np.zeros(ALPHAS.size + 1)  # summed S of the matches, by the same number
        self.gt_points = self.track_points = 0

    def _close(self, gt: Sequence, tracks: Sequence, add: bool):
        """The chunk's close pairs with their similarity and pair slot."""
        check_ids(gt, "gt")
        check_ids(tracks, "tracks")
        gi, ti, d = close_pairs(gt, tracks, self.scale)
        g, t = self.gt_ids(gt.id, add), self.track_ids(tracks.id, add)
        return gi, ti, 1.0 - d / self.scale, self.pairs(pair_key(g[gi], t[ti]), add), g, t

    def add(self, gt: Sequence, tracks: Sequence) -> None:
        """A chunk of the first pass (counted) or, after ``next_pass``, of the second (matched)."""
        (self._count if self.alignment is None else self._match)(gt, tracks)

    def _count(self, gt: Sequence, tracks: Sequence) -> None:
        """Pass 1 (step 1): presence per id and the soft count of potential matches per pair."""
        gi, ti, s, pair, g, t = self._close(gt, tracks, add=True)
        self.n_g, self.n_t = grown(self.n_g, len(self.gt_ids)), grown(self.n_t, len(self.track_ids))
        np.add.at(self.n_g, g, 1)
        np.add.at(self.n_t, t, 1)
        row = np.bincount(gi, s, minlength=len(gt))
        col = np.bincount(ti, s, minlength=len(tracks))
        self.potential = grown(self.potential, len(self.pairs))
        np.add.at(self.potential, pair, s / (row[gi] + col[ti] - s))  # in frame order, as one bincount would

    def next_pass(self) -> None:
        """Between the passes: the global alignment score A of every pair."""
        g, t = split_pair_key(self.pairs.keys)
        pot = self.potential[:len(self.pairs)]
        with np.errstate(invalid="ignore"):
            self.alignment = pot / (self.n_g[g] + self.n_t[t] - pot)
        self.hits = np.zeros((len(self.pairs), ALPHAS.size + 1), np.int32)

    def _match(self, gt: Sequence, tracks: Sequence) -> None:
        """Pass 2 (steps 2-3): one matching per frame on A * S, and the matches counted per pair and alpha."""
        gi, ti, s, pair, _, _ = self._close(gt, tracks, add=False)
        m = matching_by_frame(gi, ti, self.alignment[pair] * s, gt.frame[gi])
        sm = s[m]
        k = np.searchsorted(ALPHAS - _TOL, sm, side="right")  # a match is a TP at the first k alphas
        np.add.at(self.hits, (pair[m], k), 1)
        np.add.at(self.loc_sum, k, sm)
        self.gt_points += len(gt)
        self.track_points += len(tracks)

    def result(self) -> HotaResult:
        """HOTA, DetA, AssA, LocA (module docstring)."""
        na = ALPHAS.size
        alpha = [round(float(a), 2) for a in ALPHAS]
        if not self.gt_points and not self.track_points:
            none = [None] * na
            return HotaResult(None, None, None, None, HotaPerAlpha(alpha, none, none, none, none, [0] * na, [0] * na,
                                                                   [0] * na))
        used = np.flatnonzero(self.hits.any(axis=1))
        g, t = split_pair_key(self.pairs.keys[used])
        order = np.lexsort((self.track_ids.keys[t], self.gt_ids.keys[g]))  # by (gt id, track id)
        used, g, t = used[order], g[order], t[order]
        tpa = np.cumsum(self.hits[used][:, ::-1], axis=1, dtype=np.int64)[:, ::-1][:, 1:]  # [pairs, alpha]: TPs
        tp = tpa.sum(axis=0)
        loc_sum = np.cumsum(self.loc_sum[::-1])[::-1][1:]
        ass_sum = (tpa * tpa / ((self.n_g[g] + self.n_t[t])[:, None] - tpa)).sum(axis=0)
        fn = self.gt_points - tp
        fp = self.track_points - tp
        has = tp > 0
        deta = tp / (tp + fn + fp)
        assa = np.where(has, ass_sum / np.maximum(tp, 1), 0.0)
        loca = np.where(has, loc_sum / np.maximum(tp, 1), 1.0)
        h = np.sqrt(deta * assa)
        any_tp = bool(has.any())
        per = HotaPerAlpha(alpha, _jsonable(h), _jsonable(deta), _jsonable(assa) if any_tp else [None] * na,
                           _jsonable(loca) if any_tp else [None] * na, tp.tolist(), fn.tolist(), fp.tolist())
        return HotaResult(float(h.mean()), float(deta.mean()), float(assa.mean()) if any_tp else None,
                          float(loca.mean()) if any_tp else None, per)


def hota(gt: Sequence, tracks: Sequence, scale: float = 2.0) -> dict:
    """HOTA, DetA, AssA, LocA of ``tracks`` against ``gt`` (see module docstring), as plain JSON-serialisable values:
    ``hota``, ``deta``, ``assa``, ``loca`` (means over alpha) and ``per_alpha`` (lists ``alpha``, ``hota``, ``deta``,
    ``assa``, ``loca``, ``tp``, ``fn``, ``fp``). ``scale``: distance (m) at which the similarity reaches 0."""
    h = Hota(scale)
    accumulate([h], [(gt, tracks)])
    return h.result().as_dict()
