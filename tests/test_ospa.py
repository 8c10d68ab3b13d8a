"""OSPA (Schuhmacher et al. 2008) and OSPA-T's labels (Ristic et al. 2011) on hand-worked cases, and against a
brute-force reference on random sequences. Defaults: c = 1 m, p = 1, label penalty = c."""

import json
import math

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from evaluation.ospa import Ospa, ospa
from test_hota import approx, seq

KEYS = {"ospa", "localisation", "cardinality", "ospa_t", "frames", "labelled_tracks", "per_frame"}


def track_labels(gt, tracks):
    """OSPA-T's step 1 alone: (track ids, their labels, whether labelled)."""
    o = Ospa()
    o.add(gt, tracks)
    o.next_pass()
    return o.track_labels()


def test_one_pair_0_3_m_apart():
    r = ospa(seq((0, 1, 0, 0)), seq((0, 7, 0.3, 0)))
    assert set(r) == KEYS
    # n = m = 1: OSPA = min(1, 0.3) = 0.3, all of it localisation; labels agree (7 -> 1) so OSPA-T is 0.3 too.
    assert r["ospa"] == approx(0.3) and r["localisation"] == approx(0.3) and r["cardinality"] == 0.0
    assert r["ospa_t"] == approx(0.3)
    assert (r["frames"], r["labelled_tracks"]) == (1, 1)


def test_missing_track_or_missing_person_costs_c():
    # One person, no track: OSPA(X, empty) = c = 1, all cardinality.
    r = ospa(seq((0, 1, 0, 0)), seq())
    assert (r["ospa"], r["localisation"], r["cardinality"], r["ospa_t"]) == (1.0, 0.0, 1.0, 1.0)
    # A track where nobody is: also c.
    assert ospa(seq(), seq((0, 7, 0, 0)))["ospa"] == 1.0
    # Two people, one track 0.3 m from the first: n = 2, m = 1 -> (0.3 + 1 * (2 - 1)) / 2 = 0.65,
    # localisation 0.3 / 2 = 0.15, cardinality 1 / 2 = 0.5 (p = 1: they add up).
    r = ospa(seq((0, 1, 0, 0), (0, 2, 5, 0)), seq((0, 7, 0.3, 0)))
    assert r["ospa"] == approx(0.65) and r["localisation"] == approx(0.15) and r["cardinality"] == approx(0.5)


def test_distance_is_cut_off_at_c():
    # 3 m apart: min(c, 3) = 1; one to one, so it is localisation, not cardinality.
    r = ospa(seq((0, 1, 0, 0)), seq((0, 7, 3, 0)))
    assert (r["ospa"], r["localisation"], r["cardinality"]) == (1.0, 1.0, 0.0)
    # With c = 5 m the distance counts in full.
    assert ospa(seq((0, 1, 0, 0)), seq((0, 7, 3, 0)), c=5.0)["ospa"] == approx(3.0)


def test_optimal_assignment_not_greedy():
    # People at x = 0 and 0.8; tracks at 0.45 and 1.3. Greedy nearest first takes (0.8, 0.45) = 0.35 and is left
    # with (0, 1.3) -> cut to 1: 1.35. The optimum is (0, 0.45) + (0.8, 1.3) = 0.45 + 0.5 = 0.95 -> OSPA 0.95 / 2.
    r = ospa(seq((0, 1, 0, 0), (0, 2, 0.8, 0)), seq((0, 7, 0.45, 0), (0, 8, 1.3, 0)))
    assert r["ospa"] == approx(0.475)


def test_order_p_2():
    # One person, track 0.3 m off, plus a false track: n = 2, m = 1.
    # OSPA = sqrt((0.3^2 + 1^2) / 2) = sqrt(0.545); localisation sqrt(0.09 / 2); cardinality sqrt(1 / 2).
    r = ospa(seq((0, 1, 0, 0)), seq((0, 7, 0.3, 0), (0, 8, 9, 9)), p=2.0)
    assert r["ospa"] == approx(math.sqrt(0.545))
    assert r["localisation"] == approx(math.sqrt(0.045)) and r["cardinality"] == approx(math.sqrt(0.5))


def test_label_error_with_the_penalty():
    # Person 1 at the origin in frames 0-2; track 7 0.1 m off in frames 0-1, then track 8 0.1 m off in frame 2.
    gt = seq((0, 1, 0, 0), (1, 1, 0, 0), (2, 1, 0, 0))
    tracks = seq((0, 7, 0.1, 0), (1, 7, 0.1, 0), (2, 8, 0.1, 0))
    # Step 1: distance(1, 7) = 0.1 + 0.1 (both present) + 1 (frame 2: only 1) = 1.2;
    # distance(1, 8) = 1 + 1 (frames 0-1: only 1) + 0.1 = 2.1 -> 7 gets label 1, 8 stays unlabelled.
    ids, labels, assigned = track_labels(gt, tracks)
    assert ids.tolist() == [7, 8] and assigned.tolist() == [True, False] and labels[0] == 1
    r = ospa(gt, tracks)
    # Plain OSPA 0.1 in every frame. OSPA-T: frames 0-1 0.1; frame 2 min(1, 0.1 + 1 * [labels differ]) = 1.
    # Mean (0.1 + 0.1 + 1) / 3 = 0.4.
    assert r["ospa"] == approx(0.1) and r["ospa_t"] == approx(0.4)
    assert r["per_frame"]["ospa_t"] == [approx(0.1), approx(0.1), approx(1.0)]
    # Penalty 0.5: frame 2 min(1, 0.1 + 0.5) = 0.6 -> (0.1 + 0.1 + 0.6) / 3. Penalty 0: OSPA-T = OSPA.
    assert ospa(gt, tracks, label_penalty=0.5)["ospa_t"] == approx(0.8 / 3)
    assert ospa(gt, tracks, label_penalty=0.0)["ospa_t"] == approx(0.1)


def test_label_assignment_counts_frames_where_only_one_exists():
    # Person 1 at the origin in frames 0-3. Track 7 0.6 m off in frames 0-3; track 8 0.1 m off in frames 0-3 and
    # alone, 10 m away, in frames 4-9.
    gt = seq(*[(t, 1, 0, 0) for t in range(4)])
    tracks = seq(*[(t, 7, 0.6, 0) for t in range(4)], *[(t, 8, 0.1 if t < 4 else 10, 0) for t in range(10)])
    # Step 1: distance(1, 7) = 4 * 0.6 = 2.4; distance(1, 8) = 4 * 0.1 + 6 * 1 (only 8 present) = 6.4 -> 7 gets label 1
    # (on closeness alone, 8 would).
    ids, labels, assigned = track_labels(gt, tracks)
    assert assigned.tolist() == [True, False] and labels[0] == 1
    r = ospa(gt, tracks)
    # Frames 0-3, n = 2, m = 1: OSPA (0.1 + 1) / 2 = 0.55; OSPA-T pairs 1 with 7 (0.6; 8 is mislabelled: 1) ->
    # (0.6 + 1) / 2 = 0.8. Frames 4-9: track 8 alone -> 1. Means over 10 frames: OSPA (4 * 0.55 + 6) / 10 = 0.82,
    # OSPA-T (4 * 0.8 + 6) / 10 = 0.92.
    assert r["ospa"] == approx(0.82) and r["ospa_t"] == approx(0.92)


def test_swapped_identities_cost_every_frame_they_last():
    # People 1 (x = 0) and 2 (x = 5) in frames 0-4; tracks 7 and 8 on them exactly, swapped in frames 3 and 4.
    gt = seq(*[(t, i, x, 0) for t in range(5) for i, x in ((1, 0), (2, 5))])
    tracks = seq(*[(t, i, x if t < 3 else 5 - x, 0) for t in range(5) for i, x in ((7, 0), (8, 5))])
    # Step 1: 7 -> 1 (distance 0 + 0 + 0 + 1 + 1 = 2, against 3 for 7 -> 2), 8 -> 2.
    # Frames 3-4: both pairs mislabelled, base distance min(1, 0 + 1) = 1 -> OSPA-T (1 + 1) / 2 = 1.
    # Mean over 5 frames: 2 / 5. Plain OSPA is 0 throughout.
    r = ospa(gt, tracks)
    assert r["ospa"] == 0.0 and r["ospa_t"] == approx(0.4) and r["labelled_tracks"] == 2


def test_frames_with_neither_are_not_averaged():
    # Rows only in frames 0, 5 (exact tracking: 0) and 7 (a false track only: c = 1); frames 1-4 and 6 have none.
    r = ospa(seq((0, 1, 0, 0), (5, 1, 1, 1)), seq((0, 7, 0, 0), (5, 7, 1, 1), (7, 8, 2, 2)))
    assert r["frames"] == 3 and r["per_frame"]["frame"] == [0, 5, 7]
    assert r["ospa"] == approx(1 / 3) and r["cardinality"] == approx(1 / 3)


def test_empty_and_invalid():
    r = ospa(seq(), seq())
    assert (r["ospa"], r["localisation"], r["cardinality"], r["ospa_t"], r["frames"]) == (None, None, None, None, 0)
    json.dumps(r, allow_nan=False)
    json.dumps(ospa(seq((0, 1, 0, 0)), seq((0, 7, np.nan, 0))), allow_nan=False)
    for bad in ({"c": 0.0}, {"p": 0.5}, {"label_penalty": -1.0}, {"c": float("inf")}):
        with pytest.raises(ValueError):
            ospa(seq(), seq(), **bad)
    with pytest.raises(ValueError):
        ospa(seq(), seq((0, 7, 0, 0), (0, 7, 1, 0)))


def reference(gt, tracks, c=1.0, p=1.0, alpha=1.0):
    """The definitions written plainly: label assignment from the paper's track distance, then per frame a square
    assignment padded with c (Schuhmacher et al. Sec. III)."""
    frames = np.union1d(gt.frame, tracks.frame)
    gu, tu = np.unique(gt.id), np.unique(tracks.id)
    where = {(s, f, i): k for s, q in (("g", gt), ("t", tracks)) for k, (f, i) in enumerate(zip(q.frame, q.id))}
    cost = np.zeros((gu.size, tu.size))
    for a, l in enumerate(gu):
        for b, r in enumerate(tu):
            for f in frames:
                x, y = where.get(("g", f, l)), where.get(("t", f, r))
                if x is not None and y is not None:
                    cost[a, b] += min(c, np.linalg.norm(gt.position[x] - tracks.position[y])) ** p
                elif x is not None or y is not None:
                    cost[a, b] += c ** p
    label = {}
    if cost.size:
        for a, b in zip(*linear_sum_assignment(cost)):
            label[tu[b]] = gu[a]
    out = {"ospa": [], "localisation": [], "cardinality": [], "ospa_t": []}
    for f in frames:
        g, t = np.flatnonzero(gt.frame == f), np.flatnonzero(tracks.frame == f)
        n, m = max(g.size, t.size), min(g.size, t.size)
        d = np.linalg.norm(gt.position[g][:, None] - tracks.position[t][None], axis=2)
        d = np.where(np.isfinite(d), d, np.inf)
        differ = np.array([[label.get(j) != i for j in tracks.id[t]] for i in gt.id[g]]).reshape(d.shape)
        for key, base in (("ospa", d ** p), ("ospa_t", d ** p + alpha ** p * differ)):
            square = np.full((n, n), c ** p)
            square[:g.size, :t.size] = np.minimum(c ** p, base)
            r, k = linear_sum_assignment(square)
            out[key].append((square[r, k].sum() / n) ** (1 / p))
            if key == "ospa":
                real = (r < g.size) & (k < t.size)
                out["localisation"].append((square[r[real], k[real]].sum() / n) ** (1 / p))
                out["cardinality"].append((c ** p * (n - m) / n) ** (1 / p))
    return out


def test_matches_brute_force_on_random_sequences():
    rng = np.random.default_rng(3)
    for case in range(60):
        c, p, alpha = (1.0, 1.0, 1.0) if case % 3 == 0 else (rng.uniform(0.5, 2), rng.uniform(1, 3), rng.uniform(0, 1))
        g, t = [], []
        for f in range(int(rng.integers(1, 8))):
            for i in range(int(rng.integers(0, 6))):
                x, y = rng.uniform(0, 3, 2)
                if rng.random() < 0.8:
                    g.append((f, i, x, y))
                if rng.random() < 0.8:
                    t.append((f, i + 10 * int(rng.integers(0, 2)), x + rng.normal(0, 0.4), y + rng.normal(0, 0.4)))
        gt, tracks = seq(*g), seq(*t)
        r, ref = ospa(gt, tracks, c=c, p=p, label_penalty=alpha), reference(gt, tracks, c, p, alpha)
        for key in ("ospa", "localisation", "cardinality", "ospa_t"):
            np.testing.assert_allclose(r["per_frame"][key], ref[key], atol=1e-9, err_msg=f"case {case} {key}")
