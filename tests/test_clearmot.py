"""CLEAR-MOT (Bernardin & Stiefelhagen 2008) on hand-worked cases; expected values are worked out in comments."""

import itertools
import json

import numpy as np
import pytest

from evaluation import ClearMot, FrameResult

SUMMARY_KEYS = {"mota", "motp_m", "fp", "fn", "id_switches", "id_swaps", "reinitialisations", "rids", "gt",
                "matches", "fp_rate", "miss_rate", "tsr", "mt", "pt", "ml", "fragmentations", "persons", "idf1",
                "idp", "idr", "idtp", "frames", "threshold_m"}


def frame(ids, pos):
    """(ids [n] int64, pos [n, 2]) from Python lists; empty lists give shapes (0,) and (0, 2)."""
    return np.asarray(ids, np.int64).reshape(-1), np.asarray(pos, float).reshape(-1, 2)


def step(cm, gt, hyp):
    return cm.update(*frame(*gt), *frame(*hyp))


def test_perfect_tracking_two_people_three_frames():
    cm = ClearMot()
    for t in range(3):
        a, b = (0.5 * t, 0.0), (5.0, 0.2 * t)
        r = step(cm, ([1, 2], [a, b]), ([10, 20], [(a[0] + 0.1, a[1]), (b[0], b[1] + 0.3)]))
        assert (r.gt, r.matches, r.fp, r.fn, r.id_switches) == (2, 2, 0, 0, 0)
        np.testing.assert_array_equal(r.matched_gt_ids, [1, 2])
        np.testing.assert_array_equal(r.matched_hyp_ids, [10, 20])
        np.testing.assert_allclose(r.distances, [0.1, 0.3], atol=1e-12)
    s = cm.result()
    # 6 matches, distances 3 * (0.1 + 0.3) = 1.2 -> MOTP 1.2 / 6 = 0.2; no errors -> MOTA 1.
    assert s.mota == 1.0
    assert s.motp_m == pytest.approx(0.2, abs=1e-12)
    assert (s.gt, s.matches, s.fp, s.fn, s.id_switches, s.frames) == (6, 6, 0, 0, 0, 3)
    assert s.fp_rate == 0.0 and s.miss_rate == 0.0


def test_false_positive():
    cm = ClearMot()
    step(cm, ([1], [(0, 0)]), ([7], [(0, 0)]))
    r = step(cm, ([1], [(0, 0)]), ([7, 8], [(0, 0), (50, 0)]))
    assert (r.fp, r.fn, r.matches) == (1, 0, 1)
    s = cm.result()
    # gt 2, fp 1 -> MOTA = 1 - 1/2 = 0.5, fp_rate 0.5.
    assert s.fp == 1 and s.gt == 2
    assert s.mota == 0.5 and s.fp_rate == 0.5 and s.miss_rate == 0.0


def test_miss():
    cm = ClearMot()
    step(cm, ([1], [(0, 0)]), ([7], [(0.2, 0)]))
    r = step(cm, ([1], [(0, 0)]), ([], []))
    assert (r.fn, r.fp, r.matches) == (1, 0, 0)
    step(cm, ([1], [(0, 0)]), ([7], [(0.2, 0)]))  # same hyp again: no switch
    s = cm.result()
    # gt 3, fn 1 -> MOTA = 1 - 1/3 = 2/3; MOTP = (0.2 + 0.2) / 2.
    assert (s.fn, s.id_switches, s.gt) == (1, 0, 3)
    assert s.mota == pytest.approx(2 / 3, abs=1e-15)
    assert s.miss_rate == pytest.approx(1 / 3, abs=1e-15)
    assert s.motp_m == pytest.approx(0.2, abs=1e-15)


def test_id_switch():
    cm = ClearMot()
    assert step(cm, ([1], [(0, 0)]), ([1], [(0, 0)])).id_switches == 0
    assert step(cm, ([1], [(1, 0)]), ([1], [(1, 0)])).id_switches == 0
    r = step(cm, ([1], [(2, 0)]), ([2], [(2, 0)]))
    assert r.id_switches == 1 and r.matched_hyp_ids.tolist() == [2]
    s = cm.result()
    # gt 3, ids 1 -> MOTA = 1 - 1/3 = 2/3.
    assert (s.id_switches, s.fp, s.fn, s.gt) == (1, 0, 0, 3)
    assert s.mota == pytest.approx(2 / 3, abs=1e-15)


def test_two_tracks_swap_identities():
    cm = ClearMot()
    step(cm, ([1, 2], [(0, 0), (3, 0)]), ([10, 20], [(0, 0), (3, 0)]))
    # Hyps swap: each gt's old hyp is 3 m away (over the threshold), so both get the other hyp -> 2 switches.
    r = step(cm, ([1, 2], [(0, 0), (3, 0)]), ([10, 20], [(3, 0), (0, 0)]))
    assert r.id_switches == 2
    np.testing.assert_array_equal(r.matched_hyp_ids, [20, 10])
    # gt 4, ids 2 -> MOTA 0.5.
    assert cm.result().mota == 0.5


def test_correspondence_kept_although_nearer_track_appears():
    cm = ClearMot()
    step(cm, ([1], [(0, 0)]), ([1], [(0.5, 0)]))
    r = step(cm, ([1], [(0, 0)]), ([1, 2], [(0.6, 0), (0.05, 0)]))
    assert r.matched_hyp_ids.tolist() == [1]
    assert (r.id_switches, r.fp, r.fn) == (0, 1, 0)
    s = cm.result()
    # gt 2, fp 1 -> MOTA 0.5; MOTP (0.5 + 0.6) / 2 = 0.55.
    assert s.mota == 0.5
    assert s.motp_m == pytest.approx(0.55, abs=1e-15)
    # Control: without the history, the nearer hyp 2 wins.
    assert step(ClearMot(), ([1], [(0, 0)]), ([1, 2], [(0.6, 0), (0.05, 0)])).matched_hyp_ids.tolist() == [2]


def test_hungarian_beats_greedy_on_total_distance():
    cm = ClearMot(threshold=5.0)
    # 1D: gt 1 at 0, gt 2 at 2; hyp 10 at 0.9, hyp 20 at -1.
    # Distances: 1-10 0.9, 2-10 1.1, 1-20 1.0, 2-20 3.0.
    # Greedy nearest first takes (1,10)=0.9, leaving (2,20)=3.0: total 3.9.
    # Optimal: (1,20)=1.0 + (2,10)=1.1 = 2.1.
    r = step(cm, ([1, 2], [(0, 0), (2, 0)]), ([10, 20], [(0.9, 0), (-1, 0)]))
    np.testing.assert_array_equal(r.matched_gt_ids, [1, 2])
    np.testing.assert_array_equal(r.matched_hyp_ids, [20, 10])
    np.testing.assert_allclose(r.distances, [1.0, 1.1], atol=1e-12)
    assert cm.result().motp_m == pytest.approx(1.05, abs=1e-12)


def test_hungarian_maximises_matches_within_threshold():
    cm = ClearMot()  # 1 m
    # gt 1 at 0, gt 2 at 0.85; hyp 10 at 0.4, hyp 20 at -0.5.
    # Distances: 1-10 0.4, 2-10 0.45, 1-20 0.5, 2-20 1.35 (> 1 m, forbidden).
    # Greedy takes (1,10)=0.4 and leaves gt 2 / hyp 20 unmatched; optimal matches both: (1,20) + (2,10).
    r = step(cm, ([1, 2], [(0, 0), (0.85, 0)]), ([10, 20], [(0.4, 0), (-0.5, 0)]))
    assert (r.matches, r.fp, r.fn) == (2, 0, 0)
    np.testing.assert_array_equal(r.matched_hyp_ids, [20, 10])


def test_over_threshold_is_not_a_match_and_threshold_is_inclusive():
    cm = ClearMot(threshold=1.0)
    r = step(cm, ([1], [(0, 0)]), ([1], [(1.2, 0)]))
    assert (r.matches, r.fp, r.fn) == (0, 1, 1)
    s = cm.result()
    # gt 1, fp 1, fn 1 -> MOTA = 1 - 2/1 = -1; no matches -> MOTP None.
    assert s.mota == -1.0 and s.motp_m is None
    # Exactly at the threshold is a match (inclusive), for a new pair ...
    r = step(ClearMot(1.0), ([1], [(0, 0)]), ([1], [(1.0, 0)]))
    assert r.matches == 1 and r.distances.tolist() == [1.0]
    # ... and for a kept one; a kept one over the threshold is dropped.
    cm = ClearMot(1.0)
    step(cm, ([1], [(0, 0)]), ([1], [(0.5, 0)]))
    assert step(cm, ([1], [(0, 0)]), ([1], [(1.0, 0)])).matches == 1
    assert step(cm, ([1], [(0, 0)]), ([1], [(1.0001, 0)])).matches == 0


def test_id_switch_after_gap():
    cm = ClearMot()
    step(cm, ([1], [(0, 0)]), ([1], [(0, 0)]))
    assert step(cm, ([1], [(0, 0)]), ([], [])).fn == 1
    r = step(cm, ([1], [(0, 0)]), ([3], [(0.1, 0)]))
    assert r.id_switches == 1  # last known correspondence (hyp 1) persists over the gap
    s = cm.result()
    # gt 3, fn 1, ids 1 -> MOTA = 1 - 2/3 = 1/3.
    assert (s.fn, s.id_switches) == (1, 1)
    assert s.mota == pytest.approx(1 / 3, abs=1e-15)


def test_step1_keeps_only_previous_frame_correspondences():
    # Documented choice: step 1 keeps the matches of frame t-1 only. After a gap the old hyp is not preferred,
    # so the nearer hyp 2 is matched by the Hungarian step, which is a switch against the last known hyp 1.
    cm = ClearMot()
    step(cm, ([1], [(0, 0)]), ([1], [(0.5, 0)]))
    step(cm, ([1], [(0, 0)]), ([1], [(1.5, 0)]))  # over threshold: fn + fp
    r = step(cm, ([1], [(0, 0)]), ([1, 2], [(0.6, 0), (0.05, 0)]))
    assert r.matched_hyp_ids.tolist() == [2] and r.id_switches == 1


def test_empty_frames():
    cm = ClearMot()
    r = step(cm, ([], []), ([], []))
    assert isinstance(r, FrameResult)
    assert (r.gt, r.matches, r.fp, r.fn, r.id_switches) == (0, 0, 0, 0, 0)
    assert r.matched_gt_ids.shape == (0,) and r.distances.shape == (0,)
    s = cm.result()
    assert s.mota is None and s.motp_m is None and s.fp_rate is None and s.miss_rate is None
    assert s.frames == 1 and s.gt == 0
    r = step(cm, ([1, 2], [(0, 0), (1, 1)]), ([], []))  # gt only
    assert (r.gt, r.fn, r.fp) == (2, 2, 0)
    r = step(cm, ([], []), ([4, 5, 6], [(0, 0), (1, 1), (2, 2)]))  # hyps only
    assert (r.gt, r.fn, r.fp) == (0, 0, 3)
    s = cm.result()
    # gt 2, fn 2, fp 3 -> MOTA = 1 - 5/2 = -1.5.
    assert (s.gt, s.fn, s.fp, s.matches, s.frames) == (2, 2, 3, 0, 3)
    assert s.mota == -1.5 and s.fp_rate == 1.5 and s.miss_rate == 1.0


def test_result_is_plain_json_as_a_dict():
    cm = ClearMot()
    step(cm, ([1, 2], [(0, 0), (3, 0)]), ([1], [(0.25, 0)]))
    s = cm.result().as_dict()
    assert set(s) == SUMMARY_KEYS
    assert json.loads(json.dumps(s)) == s
    for k in ("fp", "fn", "id_switches", "id_swaps", "reinitialisations", "gt", "matches", "mt", "pt", "ml",
              "fragmentations", "persons", "idtp", "frames"):
        assert type(s[k]) is int
    for k in ("mota", "motp_m", "fp_rate", "miss_rate", "rids", "tsr", "idf1", "idp", "idr", "threshold_m"):
        assert type(s[k]) is float
    assert s["mota"] == 0.5 and s["motp_m"] == 0.25


def test_non_finite_positions_never_match_and_bad_input_is_rejected():
    r = step(ClearMot(), ([1, 2], [(np.nan, 0), (0, 0)]), ([1, 2], [(0, 0), (np.inf, 0)]))
    assert (r.matches, r.fp, r.fn) == (1, 1, 1)
    assert (r.matched_gt_ids.tolist(), r.matched_hyp_ids.tolist()) == ([2], [1])
    with pytest.raises(ValueError):
        step(ClearMot(), ([1, 1], [(0, 0), (1, 0)]), ([], []))
    with pytest.raises(ValueError):
        ClearMot().update(np.array([1, 2]), np.zeros((3, 2)), np.zeros(0, int), np.zeros((0, 2)))
    with pytest.raises(ValueError):
        ClearMot(threshold=-1.0)


def _brute_force(gt_pos, hyp_pos, thr):
    """(most matches within thr, least total distance among those) by enumerating all assignments."""
    n, m = len(gt_pos), len(hyp_pos)
    d = np.linalg.norm(gt_pos[:, None] - hyp_pos[None], axis=2)
    best = (0, 0.0)
    for k in range(1, min(n, m) + 1):
        for rows in itertools.combinations(range(n), k):
            for cols in itertools.permutations(range(m), k):
                dd = d[list(rows), list(cols)]
                if np.all(dd <= thr):
                    cand = (k, float(dd.sum()))
                    if cand[0] > best[0] or (cand[0] == best[0] and cand[1] < best[1]):
                        best = cand
    return best


def test_single_frame_matching_equals_brute_force():
    rng = np.random.default_rng(0)
    for _ in range(200):
        n, m = rng.integers(0, 5, size=2)
        g = rng.uniform(0, 2.0, (n, 2))
        h = rng.uniform(0, 2.0, (m, 2))
        r = ClearMot(1.0).update(np.arange(n), g, np.arange(m) + 100, h)
        k, total = _brute_force(g, h, 1.0)
        assert r.matches == k
        assert float(r.distances.sum()) == pytest.approx(total, abs=1e-9)


def test_a_swap_between_two_tracked_people_is_counted_apart_from_a_reinitialisation():
    cm = ClearMot()
    a, b = (0.0, 0.0), (3.0, 0.0)
    step(cm, ([1, 2], [a, b]), ([10, 20], [a, b]))
    # frame 2: the tracks swap identities: 1 takes track 20 (last matched to person 2) and 2 takes track 10, two
    # ID switches, both id swaps
    r = step(cm, ([1, 2], [a, b]), ([10, 20], [b, a]))
    assert r.id_switches == 2
    # frame 3: person 1 is lost; frame 4: a new track 30 picks them up: a re-initialisation
    step(cm, ([1, 2], [a, b]), ([10], [b]))
    step(cm, ([1, 2], [a, b]), ([10, 30], [b, a]))
    s = cm.result()
    assert (s.id_switches, s.id_swaps, s.reinitialisations) == (3, 2, 1)
    # gt 8, tp 7 (frame 3 misses 1), IDS 3 -> rIDS = 3 * 8 / 7; seed 001's TSR = 7 / 8, MR = 1 / 8, GR = 0
    assert s.rids == pytest.approx(24 / 7, abs=1e-12)
    assert (s.tsr, s.miss_rate, s.fp_rate) == (7 / 8, 1 / 8, 0.0)


def test_an_occluded_person_matched_by_a_track_is_neither_a_false_positive_nor_a_miss():
    cm = ClearMot()
    a = (0.0, 0.0)
    step(cm, ([1], [a]), ([10], [(0.1, 0.0)]))
    # occluded: the track that follows them is no false positive and the pair no match; unmatched, no miss
    r = cm.update(*frame([1], [a]), *frame([10], [(0.2, 0.0)]), gt_ignore=np.array([True]))
    assert (r.gt, r.matches, r.fp, r.fn) == (0, 0, 0, 0)
    r = cm.update(*frame([1], [a]), *frame([], []), gt_ignore=np.array([True]))
    assert (r.gt, r.matches, r.fp, r.fn) == (0, 0, 0, 0)
    # a track far from the occluded person is a false positive all the same
    r = cm.update(*frame([1], [a]), *frame([11], [(5.0, 0.0)]), gt_ignore=np.array([True]))
    assert (r.fp, r.fn) == (1, 0)
    # visible again, picked up by track 11: an ID switch (their last counted correspondence was 10)
    r = step(cm, ([1], [a]), ([11], [(0.3, 0.0)]))
    assert (r.matches, r.id_switches) == (1, 1)
    s = cm.result()
    # counted: frames 1 and 5, both matched; MOTP (0.1 + 0.3) / 2; one FP; MOTA 1 - (1 + 0 + 1) / 2
    assert (s.gt, s.matches, s.fp, s.fn) == (2, 2, 1, 0)
    assert s.motp_m == pytest.approx(0.2, abs=1e-12) and s.mota == 0.0


def test_mostly_tracked_and_mostly_lost_at_their_boundaries():
    # five persons in 10 frames, matched in 9, 8, 2, 1 and 0 of them: ratios 0.9 (MT: more than 80%), 0.8 (PT),
    # 0.2 (PT), 0.1 (ML: fewer than 20%), 0 (ML)
    cm = ClearMot()
    matched_in = [9, 8, 2, 1, 0]
    for t in range(10):
        gt = [(k + 1, (10.0 * k, 0.0)) for k in range(5)]
        hyp = [(100 + k, (10.0 * k, 0.0)) for k, n in enumerate(matched_in) if t < n]
        step(cm, ([g[0] for g in gt], [g[1] for g in gt]), ([h[0] for h in hyp], [h[1] for h in hyp]))
    s = cm.result()
    assert (s.mt, s.pt, s.ml, s.persons) == (1, 2, 2, 5)


def test_fragmentations_count_interrupted_and_resumed_runs():
    # matched in frames 0-1, lost in 2, matched in 3, lost in 4-5, matched in 6: three runs, two fragmentations;
    # an occluded frame (7) between matched frames 6 and 8 does not interrupt
    cm = ClearMot()
    seen = [1, 1, 0, 1, 0, 0, 1, None, 1]
    for flag in seen:
        hyp = ([10], [(0.0, 0.0)]) if flag else ([], [])
        cm.update(*frame([1], [(0.0, 0.0)]), *frame(*hyp), gt_ignore=np.array([flag is None]))
    assert cm.result().fragmentations == 2


def test_idf1_assigns_identities_over_the_whole_sequence():
    # person 1 for 4 frames: tracks 10 (frames 0-2) then 20 (frame 3); person 2 for 2 frames: track 20 (frames
    # 0-1). IDTP pairs: (1,10) 3 frames, (1,20) 1, (2,20) 2. Best one-to-one: (1,10) + (2,20) = 5.
    # GT 6, H 6 -> IDF1 = 2 * 5 / 12, IDP = IDR = 5 / 6
    cm = ClearMot()
    a, b = (0.0, 0.0), (5.0, 0.0)
    step(cm, ([1, 2], [a, b]), ([10, 20], [a, b]))
    step(cm, ([1, 2], [a, b]), ([10, 20], [a, b]))
    step(cm, ([1], [a]), ([10], [a]))
    step(cm, ([1], [a]), ([20], [a]))
    s = cm.result()
    assert s.idtp == 5
    assert s.idf1 == pytest.approx(10 / 12, abs=1e-12)
    assert s.idp == pytest.approx(5 / 6, abs=1e-12) and s.idr == pytest.approx(5 / 6, abs=1e-12)


def test_evaluate_on_sequences_equals_stepping_frame_by_frame_and_breaks_correspondences_at_empty_frames():
    from evaluation import Sequence, evaluate

    rng = np.random.default_rng(3)
    gt_rows, hyp_rows = [], []
    cm = ClearMot(0.5)
    for t in range(40):
        ids = rng.choice(8, size=rng.integers(0, 6), replace=False)
        pos = rng.uniform(0, 3, (len(ids), 2))
        hids = rng.choice(12, size=rng.integers(0, 6), replace=False)
        hpos = rng.uniform(0, 3, (len(hids), 2))
        ign = rng.random(len(ids)) < 0.2
        cm.update(ids, pos, hids, hpos, gt_ignore=ign)
        gt_rows += [(t, i, *p, g) for i, p, g in zip(ids, pos, ign)]
        hyp_rows += [(t, i, *p) for i, p in zip(hids, hpos)]
    g, h = np.array(gt_rows), np.array(hyp_rows)
    got = evaluate(Sequence.from_rows(g[:, 0], g[:, 1], g[:, 2:4], ignore=g[:, 4] > 0),
                   Sequence.from_rows(h[:, 0], h[:, 1], h[:, 2:4]), 0.5)
    expect = cm.result().as_dict()
    expect["frames"] = len(np.unique(np.concatenate([g[:, 0], h[:, 0]])))  # frames with any row
    assert got == expect
    # person 1 matched by track 10 in frames 0 and 2 with frame 1 empty: the correspondence is not kept across the
    # gap, but re-made by the Hungarian step; with track 11 nearer in frame 2 the gt takes 11: an ID switch
    seq = lambda rows: Sequence.from_rows(*np.array(rows, float).T[:2], np.array(rows, float)[:, 2:])  # noqa: E731
    s = evaluate(seq([(0, 1, 0, 0), (2, 1, 0, 0)]), seq([(0, 10, 0.5, 0), (2, 10, 0.5, 0), (2, 11, 0.1, 0)]))
    assert (s["id_switches"], s["fp"]) == (1, 1)
    s = evaluate(seq([(0, 1, 0, 0), (1, 1, 0, 0)]), seq([(0, 10, 0.5, 0), (1, 10, 0.5, 0), (1, 11, 0.1, 0)]))
    assert (s["id_switches"], s["fp"]) == (0, 1)  # consecutive frames: kept although 11 is nearer


def test_image_boxes_match_at_iou_half_and_motp_is_the_mean_of_one_minus_iou():
    from pipeline.detectors.hog import box_iou

    # seed 003's 2D rule: a track's box matches a person's at IoU 0.5 or more
    people = np.array([[0.0, 0.0, 10.0, 20.0], [50.0, 0.0, 60.0, 20.0]])
    tracks = np.array([[0.0, 5.0, 10.0, 25.0],  # IoU 150 / 250 = 0.6 with the first
                       [50.0, 10.0, 60.0, 30.0]])  # IoU 100 / 300 = 1/3 with the second: no match
    cm = ClearMot(0.5)
    result = cm.update_dissimilarity(np.array([1, 2]), np.array([7, 8]), 1 - box_iou(people, tracks))
    assert (result.matches, result.fn, result.fp) == (1, 1, 1)
    s = cm.result()
    assert s.motp_m == pytest.approx(0.4) and s.mota == pytest.approx(0.0)  # mean IoU of the matches: 0.6
    with pytest.raises(ValueError, match=r"dissimilarity must be \[2, 2\], got \[2, 1\]"):
        cm.update_dissimilarity(np.array([1, 2]), np.array([7, 8]), np.zeros((2, 1)))


def test_distances_are_euclidean_on_the_ground():
    from evaluation.clearmot import _distances

    # a 3-4-5 triangle and a point onto itself; no rows or no columns give an empty matrix of the right shape
    d = _distances(np.array([[0.0, 0.0], [1.0, 1.0]]), np.array([[3.0, 4.0], [1.0, 1.0]]))
    assert d.tolist() == [[5.0, np.sqrt(2.0)], [np.sqrt(13.0), 0.0]]
    assert _distances(np.zeros((0, 2)), np.zeros((3, 2))).shape == (0, 3)
    assert _distances(np.zeros((2, 2)), np.zeros((0, 2))).shape == (2, 0)
