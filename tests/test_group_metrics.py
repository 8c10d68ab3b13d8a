"""Group metrics (evaluation/groups.py) on hand-worked cases: Setti et al.'s group precision and recall, G-MITRE,
pairwise relation scores and group MOTA. Unless a test says otherwise, person i is matched to track i."""

import json

import numpy as np
import pytest

from evaluation.groups import GroupFrame, GroupMetrics


def approx(x):
    return pytest.approx(x, abs=1e-12)


def frame(true_groups, detected, positions=None, tracks=None, excused=(), relations=()):
    """A GroupFrame: ``true_groups`` lists of person ids (a list of one: alone), ``detected`` {group id: member
    tracks}, ``tracks`` {person: track} (default: every person, same id), ``relations`` (a, b, strength)."""
    ids = [p for g in true_groups for p in g]
    group = [k if len(g) > 1 else -1 for k, g in enumerate(true_groups) for _ in g]
    tracks = {p: p for p in ids} if tracks is None else tracks
    pos = np.zeros((len(ids), 2)) if positions is None else positions
    rel = list(zip(*relations)) or [(), (), ()]
    return GroupFrame(gt_id=ids, gt_group=group, gt_position=pos, matched_gt=list(tracks),
                      matched_track=list(tracks.values()), excused_track=list(excused),
                      relation_a=rel[0], relation_b=rel[1], relation_strength=rel[2],
                      group_id=[g for g, m in detected.items() for _ in m],
                      group_track=[t for m in detected.values() for t in m])


def run(*frames, **kw):
    gm = GroupMetrics(**kw)
    for f in frames:
        gm.update(f)
    return gm.summary()


def setti(s, key):
    return s[key]["tp"], s[key]["precision"], s[key]["recall"], s[key]["f1"]


def gmitre(s):
    g = s["gmitre"]
    return g["precision"], g["recall"], g["f1"]


# The worked G-MITRE rows: GT / prediction -> P, R, F.
ROW1 = frame([[1, 2, 3], [4], [5]], {0: [1, 2], 1: [3, 4], 2: [5]})
ROW2 = frame([[1, 2], [3, 4]], {0: [1, 2, 3, 4]})
ROW3 = frame([[1], [2], [3]], {0: [1, 2, 3]})
ROW4 = frame([[1, 2, 3]], {0: [1], 1: [2], 2: [3]})


def test_gmitre_first_row_and_setti():
    s = run(ROW1)
    # Key {1,2,3},{4,4'},{5,5'}; response {1,2},{3,4},{5,5'}. R = ((3-2) + (2-2) + (2-1)) / (2+1+1) = 1/2;
    # P = ((2-1) + (2-2) + (2-1)) / (1+1+1) = 2/3; F = 2 (2/3)(1/2) / (7/6) = 4/7.
    assert gmitre(s) == (approx(2 / 3), approx(1 / 2), approx(4 / 7))
    # Setti, singletons left out: GT {1,2,3}; detected {1,2},{3,4}. T = 2/3: |{1,2,3} n {1,2}| / 3 = 2/3 -> TP 1,
    # P 1/2, R 1, F1 2/3. T = 1: TP 0, P 0, R 0, F1 0.
    assert s["true_groups"] == 1 and s["detected_groups"] == 2
    assert setti(s, "t_2_3") == (1, approx(1 / 2), approx(1.0), approx(2 / 3))
    assert setti(s, "t_1") == (0, 0.0, 0.0, 0.0)


def test_gmitre_other_rows():
    # {1,2},{3,4} / {1,2,3,4}: R = (1 + 1) / 2 = 1; P = (4 - 2) / 3 = 2/3; F = 0.8.
    assert gmitre(run(ROW2)) == (approx(2 / 3), approx(1.0), approx(0.8))
    # {1},{2},{3} / {1,2,3}: R = 0/3 (each {k,k'} splits); P = (3 - 3) / 2 = 0; F = 0.
    assert gmitre(run(ROW3)) == (0.0, 0.0, 0.0)
    # {1,2,3} / {1},{2},{3}: the mirror image.
    assert gmitre(run(ROW4)) == (0.0, 0.0, 0.0)


def test_setti_other_rows():
    s = run(ROW2)  # GT {1,2},{3,4}; detected {1,2,3,4}: 2 / 4 < 2/3 for both.
    assert setti(s, "t_2_3") == (0, 0.0, 0.0, 0.0) and setti(s, "t_1") == (0, 0.0, 0.0, 0.0)
    s = run(ROW3)  # no true group, one detected: P 0/1, R undefined.
    assert setti(s, "t_2_3") == (0, 0.0, None, None)
    s = run(ROW4)  # one true group, no detected group of two: P undefined, R 0/1.
    assert setti(s, "t_2_3") == (0, None, 0.0, None)


def test_false_positive_track_and_excused_track():
    # Persons 1,2 (group), 3,4 (group), 5 alone. Track 9 matches nobody (a false positive); tracks 7, 8 are matched
    # to ignored persons. Detected 100 = {1,2,9}: |D| = 3, |G n D| = 2 -> 2/3: a match at T = 2/3, not at T = 1.
    # 200 = {3,4,8} -> {3,4}: exact. 300 = {5,7} -> {5}: a singleton, left out.
    f = frame([[1, 2], [3, 4], [5]], {100: [1, 2, 9], 200: [3, 4, 8], 300: [5, 7]}, excused=[7, 8])
    s = run(f)
    assert s["true_groups"] == 2 and s["detected_groups"] == 2
    assert setti(s, "t_2_3") == (2, 1.0, 1.0, 1.0)
    assert setti(s, "t_1") == (1, 0.5, 0.5, 0.5)
    # G-MITRE over the persons only: the response restricted to them is {1,2},{3,4},{5} = the key.
    assert gmitre(s) == (1.0, 1.0, 1.0)
    assert s["tracking"] == {"gt": 2, "tp": 2, "fp": 0, "fn": 0, "id_switches": 0, "mota": 1.0}


def test_tracks_with_other_ids_and_unmatched_persons():
    # Persons 1,2,3 in one group, tracked as 11, 12; person 3 unmatched. Detected {11,12}: 2/3 -> match at T = 2/3.
    # G-MITRE: key {1,2,3}, response {1,2},{3,3'}: R = (3 - 2) / 2 = 1/2; P = (1 + 0) / (1 + 1) = 1/2.
    s = run(frame([[1, 2, 3]], {4: [11, 12]}, tracks={1: 11, 2: 12}))
    assert setti(s, "t_2_3") == (1, 1.0, 1.0, 1.0)
    assert gmitre(s) == (approx(1 / 2), approx(1 / 2), approx(1 / 2))


def test_pooling_over_two_frames():
    s = run(ROW1, ROW2)
    # G-MITRE: recall (2 + 2) / (4 + 2) = 2/3, precision (2 + 2) / (3 + 3) = 2/3, F 2/3 (the mean of the per-frame
    # recalls would be 3/4).
    assert gmitre(s) == (approx(2 / 3), approx(2 / 3), approx(2 / 3))
    # Setti T = 2/3: TP 1 + 0, detected 2 + 1, true 1 + 2 -> P = R = F1 = 1/3 (per-frame means: P 1/4, R 1/2).
    assert s["frames"] == 2 and s["true_groups"] == 3 and s["detected_groups"] == 3
    assert setti(s, "t_2_3") == (1, approx(1 / 3), approx(1 / 3), approx(1 / 3))


def pairwise_frame():
    # 1 (0,0) and 2 (1,0) share a group; 3 (-2.5,0) in another (alone among the counted): (1,2) +, (1,3) -,
    # (2,3) 3.5 m apart: left out. 4 (10,0), 5 (11,0), 6 (10,1) share a group, 6 unmatched: (4,5) +.
    # 7 (20,0) and 8 (21,0) are both alone: (7,8) -. Person i is track 100 + i.
    ids = [1, 2, 3, 4, 5, 6, 7, 8]
    pos = np.array([[0, 0], [1, 0], [-2.5, 0], [10, 0], [11, 0], [10, 1], [20, 0], [21, 0]], float)
    rel = [(102, 101, 0.9), (101, 103, 0.6), (107, 108, 0.0), (102, 103, 0.95), (101, 999, 0.7)]
    return GroupFrame(gt_id=ids, gt_group=[10, 10, 30, 20, 20, 20, -1, -1], gt_position=pos,
                      matched_gt=[1, 2, 3, 4, 5, 7, 8], matched_track=[101, 102, 103, 104, 105, 107, 108],
                      relation_a=[r[0] for r in rel], relation_b=[r[1] for r in rel],
                      relation_strength=[r[2] for r in rel])


def test_pairwise_relations():
    p = run(pairwise_frame())["pairwise"]
    # Scores: (1,2) + 0.9 (given as (102,101)); (1,3) - 0.6; (4,5) + 0 (no relation); (7,8) - 0.0.
    # Related (>= 0.5): (1,2), (1,3) -> TP 1: P 1/2, R 1/2, F1 1/2.
    # AUC over (pos, neg): 0.9 > 0.6, 0.9 > 0.0, 0 < 0.6, 0 = 0 (half) -> 2.5 / 4 = 5/8.
    # Brier: (0.01 + 0.36 + 1 + 0) / 4 = 0.3425.
    assert p["pairs"] == 4 and p["positives"] == 2
    assert (p["precision"], p["recall"], p["f1"]) == (approx(0.5), approx(0.5), approx(0.5))
    assert p["auc"] == approx(5 / 8)
    assert p["brier"] == approx(0.3425)


def test_pairwise_threshold_and_range():
    p = run(pairwise_frame(), relation_threshold=0.95)["pairwise"]
    assert (p["precision"], p["recall"], p["f1"]) == (None, 0.0, None)
    # Range 3.5 m (inclusive) also takes (2,3): negative, strength 0.95 -> related; AUC adds 0.9 < 0.95, 0 < 0.95.
    p = run(pairwise_frame(), relation_range=3.5)["pairwise"]
    assert p["pairs"] == 5 and p["positives"] == 2
    assert (p["precision"], p["recall"]) == (approx(1 / 3), approx(1 / 2))
    assert p["auc"] == approx(2.5 / 6)


def test_group_mota_and_id_switches():
    # Persons 1,2 (group A), 3,4 (group B), 5 alone; tracks 60, 61 match nobody.
    persons = [[1, 2], [3, 4], [5]]
    f0 = frame(persons, {5: [1, 2]})  # A <-> 5; B missed.
    f1 = frame(persons, {8: [3, 4], 9: [60, 61]})  # A missed; B <-> 8; 9: a false positive group.
    f2 = frame(persons, {7: [1, 2], 8: [3, 4]})  # A <-> 7: an ID switch (last matched to 5, in frame 0); B stays.
    s = run(f0, f1, f2)
    # GT 6, TP 1 + 1 + 2 = 4, FP 1, FN 1 + 1 = 2, IDS 1: MOTA = 1 - (2 + 1 + 1) / 6 = 1/3.
    t = s["tracking"]
    assert (t["gt"], t["tp"], t["fp"], t["fn"], t["id_switches"]) == (6, 4, 1, 2, 1)
    assert t["mota"] == approx(1 / 3)
    assert setti(s, "t_2_3")[:3] == (4, approx(4 / 5), approx(4 / 6))


def test_empty_frames():
    s = run(GroupFrame(), GroupFrame())
    assert s == {"frames": 2, "true_groups": 0, "detected_groups": 0,
                 "t_2_3": {"tp": 0, "precision": None, "recall": None, "f1": None},
                 "t_1": {"tp": 0, "precision": None, "recall": None, "f1": None},
                 "gmitre": {"precision": None, "recall": None, "f1": None},
                 "pairwise": {"pairs": 0, "positives": 0, "precision": None, "recall": None, "f1": None,
                              "auc": None, "brier": None},
                 "tracking": {"gt": 0, "tp": 0, "fp": 0, "fn": 0, "id_switches": 0, "mota": None}}


def test_summary_is_plain_json():
    s = run(ROW1, pairwise_frame())
    assert json.loads(json.dumps(s)) == s


def test_bad_input():
    with pytest.raises(ValueError):
        run(frame([[1, 2]], {0: [1, 2], 1: [2]}))  # track 2 in two groups
    with pytest.raises(ValueError):
        run(GroupFrame(gt_id=[1], gt_group=[-1], gt_position=[[0, 0]], matched_gt=[2], matched_track=[2]))
    with pytest.raises(ValueError):
        GroupMetrics(bins=0)
    # fields read by each other's rows, of different lengths: named, not read past their ends
    one = dict(gt_id=[1, 2], gt_group=[0, 0], gt_position=[[0, 0], [1, 0]], matched_gt=[1, 2], matched_track=[5, 6])
    for field, value, names in (("gt_group", [0], "gt_id and gt_group"),
                                ("matched_track", [5], "matched_gt and matched_track"),
                                ("group_track", [5], "group_id and group_track")):
        bad = {**one, "group_id": [9, 9], "group_track": [5, 6], field: value}
        with pytest.raises(ValueError, match=names):
            run(GroupFrame(**bad))


def reference(frames):
    """Plain set-based Setti counts at T = 2/3 and 1 and G-MITRE sums with explicit counterparts (lossGM.m),
    pooled."""
    tp = tp1 = det_n = true_n = 0
    sums = np.zeros(4)
    for f in frames:
        track_person = dict(zip(f.matched_track, f.matched_gt))
        members = {}
        for g, t in zip(f.group_id, f.group_track):
            if t not in f.excused_track:
                members.setdefault(g, set()).add(track_person.get(t, ("fp", t)))
        true = {}
        for p, g in zip(f.gt_id, f.gt_group):
            true.setdefault(g if g >= 0 else ("alone", p), set()).add(p)
        big_t = [s for s in true.values() if len(s) > 1]
        big_d = [s for s in members.values() if len(s) > 1]
        tp += sum(any(3 * len(g & d) >= 2 * max(len(g), len(d)) for d in big_d) for g in big_t)
        tp1 += sum(g in big_d for g in big_t)
        det_n, true_n = det_n + len(big_d), true_n + len(big_t)
        people = set(f.gt_id)
        response = [s & people for s in members.values() if s & people]
        response += [{p} for p in people - set().union(*response)]
        key = list(true.values())

        def augment(part):
            return [s | {("'", p) for p in s} if len(s) == 1 else s for s in part] + \
                [{("'", p)} for s in part if len(s) > 1 for p in s]

        ka, ra = augment(key), augment(response)
        for i, (a, b) in enumerate(((ka, ra), (ra, ka))):
            for s in a:
                sums[2 * i] += len(s) - sum(bool(s & c) for c in b)
                sums[2 * i + 1] += len(s) - 1
    return tp, tp1, det_n, true_n, sums


def test_against_plain_reference_on_random_frames():
    rng = np.random.default_rng(7)
    frames = []
    for _ in range(30):
        n = int(rng.integers(0, 12))
        group = rng.integers(-1, 3, n)
        matched = rng.permutation(n)[:int(rng.integers(n // 2, n + 1))]
        tracks = np.r_[matched + 100, 200, 201, 202]  # 200..202: false positives or excused
        # Tracked groups: mostly the true group of the track's person, otherwise (and for 200..202) at random.
        true_group = np.r_[group[matched], -1, -1, -1]
        tracked = np.where(rng.random(tracks.size) < 0.7, true_group, rng.integers(0, 4, tracks.size))
        member = rng.permutation(np.flatnonzero(tracked >= 0))
        frames.append(GroupFrame(
            gt_id=list(range(n)), gt_group=list(group), gt_position=np.zeros((n, 2)),
            matched_gt=list(matched), matched_track=list(matched + 100), excused_track=[202],
            group_id=list(tracked[member]), group_track=list(tracks[member])))
    s = run(*frames)
    tp, tp1, det_n, true_n, (rn, rd, pn, pd) = reference(frames)
    assert (s["t_2_3"]["tp"], s["t_1"]["tp"], s["detected_groups"], s["true_groups"]) == (tp, tp1, det_n, true_n)
    assert s["gmitre"]["recall"] == approx(rn / rd) and s["gmitre"]["precision"] == approx(pn / pd)


def test_close_pairs_in_triangle_order_by_hand():
    from evaluation.groups import _close_pairs

    # rows 3, 0, 2 of four points: rows 3 and 0 are 2.5 m apart, 3 and 2 exactly 3 m (kept: within is inclusive),
    # 0 and 2 are 5.2 m apart
    pos = np.array([[0.0, 0.0], [9.0, 9.0], [1.5, 5.0], [1.5, 2.0]])
    i, j = _close_pairs(pos, np.array([3, 0, 2]), 3.0)
    assert i.tolist() == [0, 0] and j.tolist() == [1, 2]
    assert _close_pairs(pos, np.array([1]), 3.0)[0].size == 0


def test_close_pairs_never_take_non_finite_positions():
    from evaluation.groups import _close_pairs

    # a NaN and an infinite position are never within range, of each other or of anyone; the two finite ones, 1 m
    # apart, are
    pos = np.array([[0.0, 0.0], [np.nan, 0.0], [np.inf, 0.0], [1.0, 0.0]])
    i, j = _close_pairs(pos, np.arange(4), 3.0)
    assert list(zip(i.tolist(), j.tolist())) == [(0, 3)]


def test_hash_lookups_of_arbitrary_ids_by_hand():
    from evaluation.groups import _numbered, _rows

    # ids far apart and negative: -7 is at 0, 2**40 at 1, 5 at 2 and 3 (the first is found); 6 is absent
    keys = np.array([-7, 2 ** 40, 5, 5])
    assert _rows(keys, np.array([5, -7, 6, 2 ** 40])).tolist() == [2, 0, -1, 1]
    assert _rows(keys[:0], np.array([1])).tolist() == [-1]
    # numbers in order of first appearance among the counted: 9 (row 1) is 0, 4 is 1; row 0's 4 is not counted
    label, distinct, count = _numbered(np.array([4, 9, 4, 9, 9]), np.array([False, True, True, True, True]))
    assert label.tolist() == [-1, 0, 1, 0, 0] and distinct.tolist() == [9, 4] and count.tolist() == [3, 1]


def test_tracked_groups_as_the_persons_see_them_by_hand():
    from evaluation.groups import _response

    # persons rows 0..3; CLEAR-MOT matched track 10 to row 2, 11 to row 0, 12 to row 3; track 13 was matched to an
    # ignored person (excused), 14 to nobody. Group 50 = {10, 14}, group 70 = {11, 13, 12}.
    response, ids, size = _response(4, np.array([2, 0, 3]), np.array([10, 11, 12]), np.array([13]),
                                    np.array([50, 50, 70, 70, 70]), np.array([10, 14, 11, 13, 12]))
    # 50 is number 0 (first seen), 70 number 1; 50 keeps its false positive 14 (size 2), 70 loses 13 (size 2);
    # rows 2 -> 0, 0 and 3 -> 1, row 1 in none
    assert ids.tolist() == [50, 70] and size.tolist() == [2, 2]
    assert response.tolist() == [1, -1, 0, 1]
    with pytest.raises(ValueError, match="one tracked group only"):
        _response(1, np.array([0]), np.array([10]), np.zeros(0, np.int64), np.array([1, 2]), np.array([10, 10]))


def test_group_matches_by_hand():
    from evaluation.groups import _group_matches

    # persons 0..6: true groups 0 = {0, 1, 2}, 1 = {3, 4}, 2 = {5} (one counted member), person 6 alone.
    # tracked groups 0 = {0, 1} plus a false positive (size 3), 1 = {3, 4}, 2 = {2, 5} (size 2), 3 = {6} (size 1).
    true_of, true_size = np.array([0, 0, 0, 1, 1, 2, -1]), np.array([3, 2, 1])
    response, det_size = np.array([0, 0, 2, 1, 1, 2, 3]), np.array([3, 2, 2, 1])
    n_true, n_det, tp, exact, matched_true, matched_det = _group_matches(true_of, true_size, response, det_size)
    # groups of 2+: true 0 and 1; tracked 0, 1, 2. T = 2/3: (0, 0) 3 * 2 >= 2 * 3 yes; (1, 1) 3 * 2 >= 2 * 2 yes;
    # tracked 2 meets true 0 once (3 < 6) and true 2 (size 1: left out). T = 1: only (1, 1) has |G n D| = max = 2.
    assert (n_true, n_det, tp, exact) == (2, 3, 2, 1)
    assert list(zip(matched_true.tolist(), matched_det.tolist())) == [(0, 0), (1, 1)]


def test_mitre_kernel_on_the_first_worked_row():
    from evaluation.groups import _mitre

    # ROW1: key {1,2,3}, {4}, {5}; response {1,2}, {3,4}, {5} (person 5's group alone): as labels, -1 alone.
    key, response = np.array([0, 0, 0, -1, -1]), np.array([0, 0, 1, 1, -1])
    # R: {1,2,3} spans 2 response clusters: 3 - 2 = 1; 4 is alone in the key but not in the response: 0; 5 alone
    # on both sides: 1. Denominator 5 - 1 = 4. P: {1,2} in one key cluster: 1; {3,4} spans 2: 0; 5: 1; over 5 - 2.
    assert _mitre(key, response) == (2, 4)
    assert _mitre(response, key) == (2, 3)
    assert _mitre(np.zeros(0, np.int64), np.zeros(0, np.int64)) == (0, 0)


def test_relation_strengths_either_order_missing_and_duplicate():
    from evaluation.groups import _relation_strengths

    # relations (7, 3) 0.8 and (3, 9) 0.4; the pairs asked for: tracks (3, 7), (9, 3), (7, 9) (none: 0)
    track = np.array([3, 7, 9])
    got = _relation_strengths(track, np.array([0, 2, 1]), np.array([1, 0, 2]), np.array([7, 3]), np.array([3, 9]),
                              np.array([0.8, 0.4]))
    assert got.tolist() == [0.8, 0.4, 0.0]
    with pytest.raises(ValueError, match="more than one relation"):  # (3, 7) and (7, 3) are one pair
        _relation_strengths(track, np.array([0]), np.array([1]), np.array([3, 7]), np.array([7, 3]),
                            np.array([0.1, 0.2]))


def test_tally_pairs_by_hand():
    from evaluation.groups import _tally_pairs

    # rows' true groups 5, 5, -1, -1: pair (0, 1) positive, (2, 3) negative (both alone), (0, 2) negative.
    # 4 bins of 0.25: 0.75 -> bin 3 (its lower edge); 1.2 clipped to 1 -> the last bin; -0.1 clipped to 0 -> bin 0.
    hist = np.zeros((2, 4), np.int64)
    positives, related, related_pos, squared_error = _tally_pairs(
        np.array([0.75, 1.2, -0.1]), np.array([5, 5, -1, -1]), np.array([0, 2, 0]), np.array([1, 3, 2]), 0.5, hist)
    assert (positives, related, related_pos) == (1, 2, 1)  # related: 0.75 and 1.2
    assert hist.tolist() == [[1, 0, 0, 1], [0, 0, 0, 1]]
    assert squared_error.tolist() == [0.0625, 1.44, 0.010000000000000002]  # (0.75 - 1)^2, 1.2^2, (-0.1)^2
    with pytest.raises(ValueError, match="NaN"):
        _tally_pairs(np.array([np.nan]), np.array([0, 0]), np.array([0]), np.array([1]), 0.5, hist)
