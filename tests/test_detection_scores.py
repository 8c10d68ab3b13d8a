"""Detection scores (evaluation/detection.py): AP, peak F1 and EER as DROW / DR-SPAAM compute them, on tiny cases
worked out by hand, plus a check against a literal re-implementation of DROW's per-threshold matching.

Notation in the comments: N ground-truth persons over all frames; the curve has one point (P, R) per distinct
confidence, thresholds descending; AP is the trapezoid rule from (0, P_1) through the points."""

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from evaluation.detection import (
    DetectionAccumulator,
    detection_scores,
    frame_true_positives,
    pr_scores,
    score_detections,
)

NONE = np.zeros((0, 2))


def frame(dets, confs, gts):
    return np.asarray(dets, float).reshape(-1, 2), np.asarray(confs, float), np.asarray(gts, float).reshape(-1, 2)


def test_perfect_detector():
    # N = 3, three detections on the persons: P = 1, 1, 1; R = 1/3, 2/3, 1.
    # AP = 1 (DR-SPAAM's auc, starting at R = 1/3, would give 2/3); F1 = 1 at the last point;
    # EER: |P - R| = 2/3, 1/3, 0 -> the last point, (1 + 1)/2 = 1.
    frames = [frame([[0, 0], [2, 0]], [0.9, 0.8], [[0, 0], [2, 0]]), frame([[1, 1]], [0.7], [[1, 1]])]
    s = score_detections(frames, 0.3)
    assert s.thresholds == pytest.approx([0.9, 0.8, 0.7])
    assert s.precision == pytest.approx([1, 1, 1])
    assert s.recall == pytest.approx([1 / 3, 2 / 3, 1])
    assert s.ap == pytest.approx(1.0)
    assert s.peak_f1 == pytest.approx(1.0) and s.peak_f1_threshold == pytest.approx(0.7)
    assert s.eer == pytest.approx(1.0) and s.eer_threshold == pytest.approx(0.7)
    assert (s.n_gt, s.n_detections, s.radius) == (3, 3, 0.3)


def test_false_positive_above_true_positives_and_eer_point():
    # N = 2; an FP at 0.9, TPs at 0.8 and 0.7.
    # points: k=1 TP=0 (P 0, R 0); k=2 TP=1 (1/2, 1/2); k=3 TP=2 (2/3, 1).
    # AP = 0 + 1/2 * (0 + 1/2)/2 + 1/2 * (1/2 + 2/3)/2 = 1/8 + 7/24 = 5/12.
    # F1: 0, 2*(1/4)/1 = 1/2, 2*(2/3)/(5/3) = 4/5 -> 0.8 at 0.7.
    # EER: the points with R > 0 are 2 and 3; P = R at point 2 -> 1/2 at 0.8.
    s = score_detections([frame([[10, 10], [0, 0], [3, 0]], [0.9, 0.8, 0.7], [[0, 0], [3, 0]])], 0.5)
    assert s.precision == pytest.approx([0, 1 / 2, 2 / 3])
    assert s.recall == pytest.approx([0, 1 / 2, 1])
    assert s.ap == pytest.approx(5 / 12)
    assert s.peak_f1 == pytest.approx(0.8) and s.peak_f1_threshold == pytest.approx(0.7)
    assert s.eer == pytest.approx(0.5) and s.eer_threshold == pytest.approx(0.8)


def test_just_inside_and_just_outside_radius():
    # frame A: detection 0.299 m from its person (TP at 0.3); frame B: 0.301 m (FP at 0.3). N = 2.
    # r = 0.3: points (P 1, R 1/2) at 0.9, (1/2, 1/2) at 0.8. AP = 1/2 * 1 + 0 = 1/2;
    #   F1 = 2*(1/2)/(3/2) = 2/3 at 0.9 (then 1/2); EER: |P - R| = 1/2, 0 -> 1/2 at 0.8.
    # r = 0.5: both TP: P 1, 1; R 1/2, 1 -> AP 1, F1 1, EER 1.
    frames = (f for f in [frame([[0.299, 0]], [0.9], [[0, 0]]), frame([[5.301, 5]], [0.8], [[5, 5]])])
    s = detection_scores(frames, radii=(0.3, 0.5))  # a generator, read once for both radii
    assert set(s) == {0.3, 0.5}
    a, b = s[0.3], s[0.5]
    assert a.precision == pytest.approx([1, 0.5]) and a.recall == pytest.approx([0.5, 0.5])
    assert a.ap == pytest.approx(0.5)
    assert a.peak_f1 == pytest.approx(2 / 3) and a.peak_f1_threshold == pytest.approx(0.9)
    assert a.eer == pytest.approx(0.5) and a.eer_threshold == pytest.approx(0.8)
    assert (b.ap, b.peak_f1, b.eer) == pytest.approx((1, 1, 1))


def test_radius_bound_counts_as_inside():
    # DROW counts a miss only when radius < distance: 0.5 m away matches at r = 0.5, not at r = 0.3.
    s = detection_scores([frame([[0.5, 0]], [0.9], [[0, 0]])], radii=(0.3, 0.5))
    assert s[0.3].recall == pytest.approx([0]) and s[0.3].ap == pytest.approx(0)
    assert s[0.5].recall == pytest.approx([1]) and s[0.5].ap == pytest.approx(1)


def test_two_detections_near_one_person():
    # One person, two detections within 0.3 m: the higher-confidence one (0.9, the farther one) is the TP, the
    # other an FP: a person is matched once, by confidence order, not by distance.
    # N = 1: points (P 1, R 1) at 0.9, (1/2, 1) at 0.6. AP = 1 (from (0, 1) to (1, 1), then zero width);
    # F1 = 1 at 0.9; EER: |P - R| = 0 at 0.9 -> 1.
    dets, confs, gts = frame([[0.25, 0], [0.05, 0]], [0.9, 0.6], [[0, 0]])
    assert frame_true_positives(confs, np.hypot(*(dets - gts).T)[:, None] <= 0.3).tolist() == [True, False]
    s = score_detections([(dets, confs, gts)], 0.3)
    assert s.precision == pytest.approx([1, 0.5]) and s.recall == pytest.approx([1, 1])
    assert s.ap == pytest.approx(1.0)
    assert s.peak_f1 == pytest.approx(1.0) and s.peak_f1_threshold == pytest.approx(0.9)
    assert s.eer == pytest.approx(1.0) and s.eer_threshold == pytest.approx(0.9)


def test_maximum_matching_not_greedy_nearest():
    # Persons A (0, 0) and B (0.4, 0). Detection 1 (0.9) at 0.19 m reaches both (0.19 / 0.21 m), detection 2 (0.8)
    # at -0.2 m reaches only A. Greedy nearest would give 1 -> A and leave 2 an FP; DROW's maximum matching pairs
    # 1 -> B, 2 -> A: both TP. N = 2: points (1, 1/2), (1, 1): AP 1, F1 1, EER 1.
    s = score_detections([frame([[0.19, 0], [-0.2, 0]], [0.9, 0.8], [[0, 0], [0.4, 0]])], 0.3)
    assert s.precision == pytest.approx([1, 1]) and s.recall == pytest.approx([0.5, 1])
    assert (s.ap, s.peak_f1, s.eer) == pytest.approx((1, 1, 1))


def test_missed_person_caps_recall():
    # N = 3, two TPs (0.9, 0.8), the third person never detected: points (1, 1/3), (1, 2/3).
    # AP = 2/3; F1 = 2*(2/3)/(5/3) = 4/5 at 0.8 (1/2 at 0.9); EER: |P - R| = 2/3, 1/3 -> (1 + 2/3)/2 = 5/6 at 0.8.
    s = score_detections([frame([[0, 0], [1, 0]], [0.9, 0.8], [[0, 0], [1, 0], [2, 0]])], 0.5)
    assert s.recall[-1] == pytest.approx(2 / 3)
    assert s.ap == pytest.approx(2 / 3)
    assert s.peak_f1 == pytest.approx(0.8) and s.peak_f1_threshold == pytest.approx(0.8)
    assert s.eer == pytest.approx(5 / 6) and s.eer_threshold == pytest.approx(0.8)


def test_frames_without_detections():
    # The perfect detector's frames plus a frame with one undetected person and two frames with nothing (one with
    # empty lists). N = 4: P 1, 1, 1; R 1/4, 1/2, 3/4. AP = 3/4; F1 = 2*(3/4)/(7/4) = 6/7 at 0.7;
    # EER: |P - R| smallest (1/4) at the last point -> (1 + 3/4)/2 = 7/8.
    frames = [frame([[0, 0], [2, 0]], [0.9, 0.8], [[0, 0], [2, 0]]), (NONE, [], [[4, 4]]), (NONE, [], NONE),
              ([], [], []), frame([[1, 1]], [0.7], [[1, 1]])]
    s = score_detections(frames, 0.5)
    assert s.n_gt == 4 and s.n_detections == 3
    assert s.recall == pytest.approx([0.25, 0.5, 0.75])
    assert s.ap == pytest.approx(0.75)
    assert s.peak_f1 == pytest.approx(6 / 7) and s.peak_f1_threshold == pytest.approx(0.7)
    assert s.eer == pytest.approx(7 / 8) and s.eer_threshold == pytest.approx(0.7)


def test_detections_only_in_frames_without_ground_truth_are_false_positives():
    # Frame 1: one TP (0.6); frame 2: no person, one detection (0.95) -> FP. N = 1.
    # points (0, 0) at 0.95, (1/2, 1) at 0.6. AP = 0 + 1 * (0 + 1/2)/2 = 1/4; F1 = 2*(1/2)/(3/2) = 2/3;
    # EER: only the second point has R > 0 -> (1/2 + 1)/2 = 3/4.
    s = score_detections([frame([[0, 0]], [0.6], [[0, 0]]), frame([[3, 3]], [0.95], NONE)], 0.3)
    assert s.precision == pytest.approx([0, 0.5]) and s.recall == pytest.approx([0, 1])
    assert (s.ap, s.peak_f1, s.eer) == pytest.approx((0.25, 2 / 3, 0.75))


def test_tied_confidences_make_one_point():
    # A TP and an FP of equal confidence 0.5, N = 1: one point (1/2, 1) (DR-SPAAM would make two).
    # AP = 1 * 1/2 = 1/2; F1 = 2/3; EER = 3/4.
    s = score_detections([frame([[0, 0], [9, 9]], [0.5, 0.5], [[0, 0]])], 0.3)
    assert s.thresholds == pytest.approx([0.5])
    assert (s.ap, s.peak_f1, s.eer) == pytest.approx((0.5, 2 / 3, 0.75))


def test_no_detection_at_all():
    s = score_detections([(NONE, [], [[0, 0]])], 0.5)
    assert len(s.precision) == len(s.recall) == len(s.thresholds) == 0
    assert (s.ap, s.peak_f1, s.eer) == (0.0, 0.0, 0.0)
    assert np.isnan(s.peak_f1_threshold) and np.isnan(s.eer_threshold)


def test_no_true_positive():
    # N = 1, one FP: point (0, 0): AP 0, F1 0, no EER point.
    s = score_detections([frame([[5, 5]], [0.9], [[0, 0]])], 0.5)
    assert (s.ap, s.peak_f1, s.eer) == (0.0, 0.0, 0.0) and np.isnan(s.eer_threshold)


def test_no_ground_truth_raises():
    with pytest.raises(ValueError, match="no ground truth"):
        score_detections([frame([[0, 0]], [0.9], NONE), (NONE, [], NONE)], 0.5)
    with pytest.raises(ValueError, match="no ground truth"):
        detection_scores(iter([]))


def test_bad_input_raises():
    with pytest.raises(ValueError):
        DetectionAccumulator().add([[0, 0]], [0.9, 0.8], NONE)  # one position, two confidences
    with pytest.raises(ValueError):
        DetectionAccumulator().add([[0, 0, 0]], [0.9], NONE)
    with pytest.raises(ValueError):
        DetectionAccumulator().add([[0, 0]], [np.nan], NONE)
    with pytest.raises(ValueError):
        DetectionAccumulator(radii=(0.3, -1))
    with pytest.raises(ValueError):
        pr_scores([0.9], [True, False], 1)


def _drow_reference(frames, radius):
    """DROW's procedure taken literally: admit detections one at a time by descending confidence; after each, a
    0/1-cost assignment in that detection's frame; TP = matched pairs within the radius summed over frames."""
    dets = [(c, f, xy) for f, (d, conf, _) in enumerate(frames) for xy, c in zip(d, conf)]
    dets.sort(key=lambda t: -t[0])
    admitted = [[] for _ in frames]
    tp_per_frame = np.zeros(len(frames), int)
    tps = []
    for c, f, xy in dets:
        admitted[f].append(xy)
        gts = frames[f][2]
        if len(gts):
            d = np.asarray(admitted[f])
            far = np.hypot(d[:, None, 0] - gts[None, :, 0], d[:, None, 1] - gts[None, :, 1]) > radius
            i, j = linear_sum_assignment(far)
            tp_per_frame[f] = int((~far[i, j]).sum())
        tps.append(tp_per_frame.sum())
    return np.array([t[0] for t in dets]), np.array(tps)


@pytest.mark.parametrize("seed", range(5))
def test_matches_drow_per_threshold_matching(seed):
    # Crowded random frames (many detections reach several persons), distinct confidences: our true-positive count
    # at every threshold equals DROW's maximum matching; our AP is DROW's auc plus the first segment R_1 * P_1.
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(30):
        n, m = rng.integers(0, 7), rng.integers(0, 6)
        frames.append((rng.uniform(0, 1.5, (n, 2)), rng.random(n), rng.uniform(0, 1.5, (m, 2))))
    n_gt = sum(len(f[2]) for f in frames)
    for radius, s in detection_scores(frames, radii=(0.3, 0.5)).items():
        conf, tps = _drow_reference(frames, radius)
        assert s.thresholds == pytest.approx(conf)
        assert s.recall * n_gt == pytest.approx(tps)
        assert s.precision == pytest.approx(tps / np.arange(1, len(tps) + 1))
        drow_auc = np.trapezoid(s.precision, s.recall)
        assert s.ap == pytest.approx(drow_auc + s.recall[0] * s.precision[0])
