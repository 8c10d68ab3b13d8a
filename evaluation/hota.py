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
2. Matching. Per frame, the Hungarian method (``scipy.optimize.linear_sum_assignment``) maximises the sum of A * S
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

import numpy as np
from scipy.optimize import linear_sum_assignment

from evaluation.sequence import Sequence, frames_of

__all__ = ["hota", "ALPHAS", "close_pairs", "max_weight_matching", "check_ids"]

ALPHAS = np.arange(1, 20) / 20  # 0.05 ... 0.95
_TOL = 1e-12  # a similarity this close below alpha still counts (rounding of d / scale)
_CHUNK = 1 << 20  # candidate pairs generated at once (memory bound)
_EMPTY_I = np.zeros(0, np.int64)
_DENSE = 1 << 22  # largest (gt ids x track ids) table counted densely


def check_ids(seq: Sequence, name: str) -> None:
    """Raise if an id occurs twice in one frame: the matching would be ambiguous."""
    if len(seq) > 1:
        o = np.lexsort((seq.id, seq.frame))
        f, i = seq.frame[o], seq.id[o]
        if ((f[1:] == f[:-1]) & (i[1:] == i[:-1])).any():
            raise ValueError(f"{name} ids must be unique within a frame")


def close_pairs(gt: Sequence, tracks: Sequence, radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every (gt row, track row) of the same frame closer than ``radius`` (strictly; never for non-finite
    positions), with its distance, sorted by gt row then track row (so also by frame)."""
    if not len(gt) or not len(tracks):
        return _EMPTY_I, _EMPTY_I, np.zeros(0)
    frames = frames_of(gt, tracks)
    tb = tracks.bounds(frames)
    k = np.searchsorted(frames, gt.frame)
    t0 = tb[k]
    cnt = tb[k + 1] - t0  # track rows in each gt row's frame
    ends = np.cumsum(cnt)
    gx, gy = gt.position[:, 0], gt.position[:, 1]
    tx, ty = tracks.position[:, 0], tracks.position[:, 1]
    r2 = radius * radius * (1.0 + 1e-9)  # cheap pre-filter on squared distance, exact test below
    out_g, out_t, out_d = [], [], []
    lo, n = 0, len(gt)
    while lo < n:
        base = int(ends[lo - 1]) if lo else 0
        hi = max(lo + 1, int(np.searchsorted(ends, base + _CHUNK, side="right")))
        c = cnt[lo:hi]
        total = int(ends[hi - 1]) - base
        if total:
            # Track row = first track row of the frame + offset within this gt row's block.
            ti = np.arange(total) + np.repeat(t0[lo:hi] - (ends[lo:hi] - c - base), c)
            dx = np.repeat(gx[lo:hi], c) - tx[ti]
            dy = np.repeat(gy[lo:hi], c) - ty[ti]
            d2 = dx * dx + dy * dy
            near = np.flatnonzero(d2 < r2)
            d = np.sqrt(d2[near])
            ok = d < radius
            near = near[ok]
            out_g.append(lo + np.searchsorted(ends[lo:hi] - base, near, side="right"))
            out_t.append(ti[near])
            out_d.append(d[ok])
        lo = hi
    if not out_g:
        return _EMPTY_I, _EMPTY_I, np.zeros(0)
    return np.concatenate(out_g), np.concatenate(out_t), np.concatenate(out_d)


def _rank(a: np.ndarray) -> np.ndarray:
    """Rank of each value among the distinct values of ``a`` (small non-negative ints), by counting, not sorting."""
    used = np.zeros(int(a.max()) + 1, bool)
    used[a] = True
    return (np.cumsum(used) - 1)[a]


def max_weight_matching(rows: np.ndarray, cols: np.ndarray, weight: np.ndarray, group: np.ndarray) -> np.ndarray:
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


def _jsonable(a) -> list:
    return [None if x is None else float(x) for x in a]


def hota(gt: Sequence, tracks: Sequence, scale: float = 2.0) -> dict:
    """HOTA, DetA, AssA, LocA of ``tracks`` against ``gt`` (see module docstring), as plain JSON-serialisable values:
    ``hota``, ``deta``, ``assa``, ``loca`` (means over alpha) and ``per_alpha`` (lists ``alpha``, ``hota``, ``deta``,
    ``assa``, ``loca``, ``tp``, ``fn``, ``fp``). ``scale``: distance (m) at which the similarity reaches 0."""
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0.0:
        raise ValueError("scale must be finite and > 0")
    check_ids(gt, "gt")
    check_ids(tracks, "tracks")
    na = ALPHAS.size
    per = {"alpha": [round(float(a), 2) for a in ALPHAS]}
    if not len(gt) and not len(tracks):
        none = [None] * na
        per.update(hota=none, deta=none, assa=none, loca=none, tp=[0] * na, fn=[0] * na, fp=[0] * na)
        return {"hota": None, "deta": None, "assa": None, "loca": None, "per_alpha": per}

    g_ids, g_idx = np.unique(gt.id, return_inverse=True)
    t_ids, t_idx = np.unique(tracks.id, return_inverse=True)
    g_idx, t_idx = g_idx.reshape(-1), t_idx.reshape(-1)
    n_t_ids = max(t_ids.size, 1)
    n_g = np.bincount(g_idx, minlength=g_ids.size)  # frames each gt id is present in
    n_t = np.bincount(t_idx, minlength=n_t_ids)

    gi, ti, d = close_pairs(gt, tracks, scale)
    s = 1.0 - d / scale  # > 0 for every listed pair; all other pairs have S = 0

    # 1. Global alignment score A of every (gt id, track id) that ever has S > 0.
    row = np.bincount(gi, s, minlength=len(gt))
    col = np.bincount(ti, s, minlength=len(tracks))
    soft = s / (row[gi] + col[ti] - s)
    key = g_idx[gi] * n_t_ids + t_idx[ti]
    if g_ids.size * n_t_ids <= _DENSE:  # count by id pair in a dense table: no sort
        inv, n_keys = key, g_ids.size * n_t_ids
    else:
        inv = np.unique(key, return_inverse=True)[1].reshape(-1)
        n_keys = int(inv.max()) + 1 if inv.size else 0
    keys = np.zeros(n_keys, np.int64)
    keys[inv] = key
    kg, kt = keys // n_t_ids, keys % n_t_ids
    pot = np.bincount(inv, soft, minlength=n_keys)
    with np.errstate(invalid="ignore"):  # 0 / 0 for id pairs never close: unused
        align = pot / (n_g[kg] + n_t[kt] - pot)

    # 2. One matching per frame on A * S.
    m = max_weight_matching(gi, ti, align[inv] * s, gt.frame[gi])

    # 3. Per alpha. A matched pair with similarity S is a TP at the first k alphas, k = number of alphas <= S.
    sm = s[m]
    k = np.searchsorted(ALPHAS - _TOL, sm, side="right")
    pk, pinv = np.unique(inv[m], return_inverse=True)
    pinv = pinv.reshape(-1)
    hist = np.bincount(pinv * (na + 1) + k, minlength=pk.size * (na + 1)).reshape(pk.size, na + 1)
    tpa = np.cumsum(hist[:, ::-1], axis=1)[:, ::-1][:, 1:]  # [pairs, alpha]: TPs of each id pair at each alpha
    tp = tpa.sum(axis=0)
    loc_sum = np.cumsum(np.bincount(k, sm, minlength=na + 1)[::-1])[::-1][1:]
    ass_sum = (tpa * tpa / ((n_g[kg[pk]] + n_t[kt[pk]])[:, None] - tpa)).sum(axis=0)
    fn = len(gt) - tp
    fp = len(tracks) - tp
    has = tp > 0
    deta = tp / (tp + fn + fp)
    assa = np.where(has, ass_sum / np.maximum(tp, 1), 0.0)
    loca = np.where(has, loc_sum / np.maximum(tp, 1), 1.0)
    h = np.sqrt(deta * assa)

    any_tp = bool(has.any())
    per.update(hota=_jsonable(h), deta=_jsonable(deta),
               assa=_jsonable(assa) if any_tp else [None] * na, loca=_jsonable(loca) if any_tp else [None] * na,
               tp=tp.tolist(), fn=fn.tolist(), fp=fp.tolist())
    return {"hota": float(h.mean()), "deta": float(deta.mean()),
            "assa": float(assa.mean()) if any_tp else None, "loca": float(loca.mean()) if any_tp else None,
            "per_alpha": per}
