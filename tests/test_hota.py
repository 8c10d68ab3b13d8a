"""HOTA (Luiten et al. 2021) on hand-worked cases, and against a plain per-frame reference on random sequences.

Similarity S = max(0, 1 - d / 2 m); alphas 0.05, 0.10, ..., 0.95 (19); reported values are means over the alphas.
"""

import json
import math

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from evaluation.hota import ALPHAS, hota
from evaluation.sequence import Sequence

KEYS = {"hota", "deta", "assa", "loca", "per_alpha"}


def seq(*rows):
    """A Sequence from (frame, id, x, y) rows."""
    if not rows:
        return Sequence.from_rows([], [], np.zeros((0, 2)))
    f, i, x, y = zip(*rows)
    return Sequence.from_rows(f, i, np.column_stack([x, y]))


def approx(x):
    return pytest.approx(x, abs=1e-12)


def test_one_pair_half_a_metre_apart_for_two_frames():
    r = hota(seq((0, 1, 0, 0), (1, 1, 0, 0)), seq((0, 7, 0.5, 0), (1, 7, 0.5, 0)))
    assert set(r) == KEYS
    # S = 1 - 0.5 / 2 = 0.75 in both frames. A(1, 7) = 1 (the only pair), so both frames match.
    # alpha 0.05 .. 0.75 (15 values, 0.75 included: S >= alpha): TP 2, FN 0, FP 0 -> DetA 1; the id pair has TPA 2,
    #   n_gt 2, n_track 2 -> AssIoU 2 / (2 + 2 - 2) = 1 -> AssA 1, HOTA 1; LocA 0.75.
    # alpha 0.80 .. 0.95 (4 values): TP 0, FN 2, FP 2 -> DetA 0, AssA 0, HOTA 0; LocA 1 (no TP: TrackEval's value).
    # Means: HOTA = DetA = AssA = 15/19; LocA = (15 * 0.75 + 4 * 1) / 19 = 15.25 / 19.
    assert r["hota"] == approx(15 / 19) and r["deta"] == approx(15 / 19) and r["assa"] == approx(15 / 19)
    assert r["loca"] == approx(15.25 / 19)
    pa = r["per_alpha"]
    assert pa["alpha"] == [round(0.05 * k, 2) for k in range(1, 20)]
    assert pa["tp"] == [2] * 15 + [0] * 4
    assert pa["fn"] == [0] * 15 + [2] * 4 and pa["fp"] == [0] * 15 + [2] * 4
    assert pa["hota"] == [1.0] * 15 + [0.0] * 4
    assert pa["loca"] == [0.75] * 15 + [1.0] * 4


def test_scale_sets_where_similarity_reaches_zero():
    r = hota(seq((0, 1, 0, 0), (1, 1, 0, 0)), seq((0, 7, 0.5, 0), (1, 7, 0.5, 0)), scale=1.0)
    # S = 1 - 0.5 / 1 = 0.5: a TP at alpha 0.05 .. 0.50 (10 values) -> HOTA 10/19; LocA (10 * 0.5 + 9 * 1) / 19.
    assert r["hota"] == approx(10 / 19)
    assert r["loca"] == approx(14 / 19)
    with pytest.raises(ValueError):
        hota(seq(), seq(), scale=0.0)


def test_id_switch_halves_assa():
    gt = seq(*[(t, 1, t, 0) for t in range(4)])
    switched = seq((0, 7, 0, 0), (1, 7, 1, 0), (2, 8, 2, 0), (3, 8, 3, 0))
    r = hota(gt, switched)
    # Every frame a TP with S = 1, at every alpha: DetA 1, LocA 1.
    # Id pairs (1, 7) and (1, 8): TPA 2 each, n_gt 4, n_track 2 -> AssIoU 2 / (4 + 2 - 2) = 1/2 for each TP;
    # AssA = (2 * 1/2 + 2 * 1/2) / 4 = 1/2; HOTA = sqrt(1 * 1/2) at every alpha.
    assert r["deta"] == approx(1.0) and r["loca"] == approx(1.0)
    assert r["assa"] == approx(0.5)
    assert r["hota"] == approx(math.sqrt(0.5))
    # The same track all along: AssA 1.
    assert hota(gt, seq(*[(t, 7, t, 0) for t in range(4)]))["assa"] == approx(1.0)


def test_false_positive_and_miss():
    # gt 1 tracked exactly in frames 0 and 1; track 8 (10 m away, S = 0) is a false positive in frame 1.
    r = hota(seq((0, 1, 0, 0), (1, 1, 0, 0)), seq((0, 7, 0, 0), (1, 7, 0, 0), (1, 8, 10, 0)))
    # TP 2, FN 0, FP 1 -> DetA 2/3 at every alpha; AssA 1 -> HOTA sqrt(2/3).
    assert r["deta"] == approx(2 / 3) and r["assa"] == approx(1.0)
    assert r["hota"] == approx(math.sqrt(2 / 3))
    assert r["per_alpha"]["fp"] == [1] * 19
    # gt 2 is never tracked: TP 2, FN 2, FP 0 -> DetA 1/2, AssA 1 -> HOTA sqrt(1/2).
    r = hota(seq((0, 1, 0, 0), (0, 2, 5, 0), (1, 1, 0, 0), (1, 2, 5, 0)), seq((0, 7, 0, 0), (1, 7, 0, 0)))
    assert r["deta"] == approx(0.5) and r["hota"] == approx(math.sqrt(0.5))
    assert r["per_alpha"]["fn"] == [2] * 19


def test_matching_score_prefers_the_consistent_track():
    # gt 1 at the origin in frames 0-3; track 7 on it in frames 0-2 (S = 1) and 1 m off in frame 3 (S = 0.5);
    # track 8 appears in frame 3 only, 0.2 m off (S = 0.9). Matching on S alone would take 8 in frame 3.
    gt = seq(*[(t, 1, 0, 0) for t in range(4)])
    tracks = seq((0, 7, 0, 0), (1, 7, 0, 0), (2, 7, 0, 0), (3, 7, 1, 0), (3, 8, 0.2, 0))
    r = hota(gt, tracks)
    # Global alignment: frames 0-2 give (1, 7) soft IoU 1 each. Frame 3: row sum 0.5 + 0.9 = 1.4, so (1, 7) gets
    # 0.5 / 1.4 = 5/14 and (1, 8) 0.9 / 1.4 = 9/14. A(1, 7) = (3 + 5/14) / (4 + 4 - 47/14) = 47/65;
    # A(1, 8) = (9/14) / (4 + 1 - 9/14) = 9/61. Frame 3 scores: 7: 47/65 * 0.5 = 0.36; 8: 9/61 * 0.9 = 0.13 -> 7.
    # alpha 0.05 .. 0.50 (10 values): TP 4, FN 0, FP 1 (track 8) -> DetA 4/5; (1, 7): TPA 4, n 4 and 4 -> AssA 1;
    #   HOTA sqrt(4/5); LocA (1 + 1 + 1 + 0.5) / 4 = 0.875.
    # alpha 0.55 .. 0.95 (9 values): frame 3's pair fails -> TP 3, FN 1, FP 2 -> DetA 3/6; (1, 7): TPA 3 ->
    #   AssIoU 3 / (4 + 4 - 3) = 3/5 -> AssA 3/5; HOTA sqrt(3/10); LocA 1. (One matching serves every alpha, as in
    #   TrackEval: track 8, S = 0.9, stays a FP here although it alone would be a TP.)
    assert r["deta"] == approx((10 * 0.8 + 9 * 0.5) / 19)
    assert r["assa"] == approx((10 * 1 + 9 * 0.6) / 19)
    assert r["hota"] == approx((10 * math.sqrt(0.8) + 9 * math.sqrt(0.3)) / 19)
    assert r["loca"] == approx((10 * 0.875 + 9 * 1) / 19)
    assert r["per_alpha"]["fp"] == [1] * 10 + [2] * 9


def test_empty_cases_are_defined_and_json():
    # Nothing at all: every score undefined -> None.
    r = hota(seq(), seq())
    assert (r["hota"], r["deta"], r["assa"], r["loca"]) == (None, None, None, None)
    assert r["per_alpha"]["hota"] == [None] * 19 and r["per_alpha"]["tp"] == [0] * 19
    json.dumps(r, allow_nan=False)
    # Ground truth only: TP 0, FN 2 -> DetA 0, HOTA 0; AssA and LocA (means over TPs) undefined -> None.
    r = hota(seq((0, 1, 0, 0), (1, 1, 0, 0)), seq())
    assert (r["hota"], r["deta"], r["assa"], r["loca"]) == (0.0, 0.0, None, None)
    assert r["per_alpha"]["fn"] == [2] * 19
    json.dumps(r, allow_nan=False)
    # Tracks only: FP 1 -> HOTA 0.
    r = hota(seq(), seq((3, 7, 1, 1)))
    assert (r["hota"], r["deta"], r["assa"], r["loca"]) == (0.0, 0.0, None, None)
    assert r["per_alpha"]["fp"] == [1] * 19
    # A track never within 2 m: no TP either.
    assert hota(seq((0, 1, 0, 0)), seq((0, 7, 2.0, 0)))["assa"] is None


def test_ids_unique_within_a_frame():
    with pytest.raises(ValueError):
        hota(seq((0, 1, 0, 0), (0, 1, 1, 0)), seq())


def reference(gt, tracks, scale=2.0):
    """The definition written plainly: dense similarity per frame, one Hungarian per frame on A * S."""
    frames = np.union1d(gt.frame, tracks.frame)
    gu, tu = np.unique(gt.id), np.unique(tracks.id)
    per_frame = []
    for f in frames:
        g, t = np.flatnonzero(gt.frame == f), np.flatnonzero(tracks.frame == f)
        d = np.linalg.norm(gt.position[g][:, None] - tracks.position[t][None], axis=2)
        per_frame.append((np.searchsorted(gu, gt.id[g]), np.searchsorted(tu, tracks.id[t]),
                          np.maximum(0.0, 1.0 - d / scale)))
    pot = np.zeros((gu.size, tu.size))
    ng, nt = np.zeros(gu.size), np.zeros(tu.size)
    for gi, ti, s in per_frame:
        den = s.sum(0)[None, :] + s.sum(1)[:, None] - s
        pot[np.ix_(gi, ti)] += np.divide(s, den, out=np.zeros_like(s), where=den > 0)
        ng[gi] += 1
        nt[ti] += 1
    align = pot / np.maximum(ng[:, None] + nt[None, :] - pot, 1e-300)
    out = {k: [] for k in ("hota", "deta", "assa", "loca")}
    for alpha in ALPHAS:
        tp, loc, counts = 0, 0.0, np.zeros_like(pot)
        for gi, ti, s in per_frame:
            if gi.size and ti.size:
                r, c = linear_sum_assignment(align[np.ix_(gi, ti)] * s, maximize=True)
                ok = s[r, c] >= alpha - 1e-12
                tp += ok.sum()
                loc += s[r[ok], c[ok]].sum()
                np.add.at(counts, (gi[r[ok]], ti[c[ok]]), 1)
        deta = tp / (len(gt) + len(tracks) - tp)
        assa = (counts ** 2 / (ng[:, None] + nt[None, :] - counts)).sum() / tp if tp else 0.0
        out["deta"].append(deta)
        out["assa"].append(assa)
        out["hota"].append(math.sqrt(deta * assa))
        out["loca"].append(loc / tp if tp else 1.0)
    return out


def random_case(rng):
    """A few people, noisy tracks with id changes, missed points and clutter, within a few metres."""
    frames, people, side = int(rng.integers(1, 10)), int(rng.integers(1, 7)), rng.uniform(1.0, 5.0)
    g, t = [], []
    for f in range(frames):
        for i in range(people):
            if rng.random() < 0.8:
                x, y = rng.uniform(0, side, 2)
                g.append((f, i, x, y))
                if rng.random() < 0.8:
                    t.append((f, i + 10 * int(rng.integers(0, 3)), x + rng.normal(0, 0.5), y + rng.normal(0, 0.5)))
        for j in range(int(rng.integers(0, 3))):
            t.append((f, 100 + j, *rng.uniform(0, side, 2)))
    return seq(*g), seq(*t)


def test_matches_the_plain_reference_on_random_sequences():
    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(60):
        gt, tracks = random_case(rng)
        r, ref = hota(gt, tracks), reference(gt, tracks)
        if r["assa"] is None:
            continue
        compared += 1
        for key in ("hota", "deta", "assa", "loca"):
            np.testing.assert_allclose(r["per_alpha"][key], ref[key], atol=1e-12, err_msg=key)
            assert r[key] == pytest.approx(np.mean(ref[key]), abs=1e-12)
    assert compared > 40


def test_close_pairs_worked_by_hand():
    from evaluation.hota import close_pairs

    # frame 0: gt 1 at the origin, gt 2 at (10, 0); tracks 5 at (3, 4) (5 m from gt 1) and 6 at (1, 0);
    # frame 1: gt 1 at the origin, track 5 at (NaN, 0) (never close); frame 2 has tracks only
    gt = Sequence.from_rows(np.array([0, 0, 1]), np.array([1, 2, 1]), np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 0.0]]))
    tracks = Sequence.from_rows(np.array([0, 0, 1, 2]), np.array([5, 6, 5, 5]),
                                np.array([[3.0, 4.0], [1.0, 0.0], [np.nan, 0.0], [0.0, 0.0]]))
    rows, cols, d = close_pairs(gt, tracks, 5.0)  # strictly closer: (3, 4) at exactly 5 m is left out
    assert rows.tolist() == [0] and cols.tolist() == [1] and d.tolist() == [1.0]
    rows, cols, d = close_pairs(gt, tracks, 5.5)
    assert rows.tolist() == [0, 0] and cols.tolist() == [0, 1] and d.tolist() == [5.0, 1.0]
    assert [a.size for a in close_pairs(gt, tracks.select(np.zeros(4, bool)), 5.0)] == [0, 0, 0]
