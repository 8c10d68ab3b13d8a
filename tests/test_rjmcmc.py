"""Seed 001's RJMCMC filter: each move's acceptance ratio worked by hand on one- and two-target cases, add and
remove as each other's reverse, the colour term, and two crossing people followed without a swap."""

import math

import numpy as np
import pytest

from evaluation.clearmot import ClearMot
from pipeline.appearance import BINS
from pipeline.fusion import fuse
from pipeline.tracking.rjmcmc import RjmcmcTracker, View, person_box
from pipeline.types import DetectedPersons

LASER = {"laser/legs": 1.0, "laser/blobs": 1.0}
NEWCOMER = 0.005  # a newcomer's prior odds per kernel area
CLUTTER = {"laser/blobs": 0.1, "camera_1/fseg": 0.1, "camera_1/hog": 0.1}  # false detections per m^2 and cycle
LOOKS = 5.0  # the weights, summing to 1, stand for five sources
# the parameters of these cases, so that the hand-worked numbers do not move with the defaults
CASE = {"clutter": CLUTTER, "looks": LOOKS, "newcomer": NEWCOMER}
SIGMA2 = 0.09  # Table 1's Sigma (m^2)


def g(d):
    """The peak-1 kernel at distance d."""
    return math.exp(-d * d / (2 * SIGMA2))


def detections(stamp, batches: dict) -> DetectedPersons:
    """Fused detections (distance 0: pooled as seed 001 does) from {source: points}."""
    parts, first = {}, 0
    for name, xy in batches.items():
        parts[name] = DetectedPersons.on_floor(stamp, "odom", name, first, np.asarray(xy, float).reshape(-1, 2), SIGMA2)
        first += len(parts[name].detection_id)
    return fuse(parts, 0.0)


def prepared(tracker, batches):
    tracker._prepare(detections(0.0, batches))
    return tracker


GAIN = 0.7 / (2 * math.pi * SIGMA2 * 0.1)  # p_D N(0; Sigma) / clutter: a detection's odds at a target's kernel peak


def blob_term(kernel_sum):
    """A laser blob's log-likelihood term for the summed kernels of the targets at it (the weight k = 1)."""
    return LOOKS * math.log1p(GAIN * kernel_sum)


MISS = 0.7 * LOOKS  # p_D times the weights of the sources that should see a target: the laser's


def test_add_ratio_one_target_to_two_by_hand_and_remove_is_its_reverse():
    tr = prepared(RjmcmcTracker(weights=LASER, **CASE),
                  {"laser/legs": [[0, 0], [2, 0]], "laser/blobs": [[0, 0], [2, 0]]})
    one = tr.state([7], [0.0], [0.0])
    log_beta, two = tr.propose_add(one, 2.0, 0.0)
    # each blob is explained by both targets' kernels: the near one's 1 and the far one's g(2)
    likelihood = 2 * blob_term(1 + g(2.0)) - blob_term(1.0) - blob_term(g(2.0)) - MISS
    interaction = math.log(1 - math.exp(-(2.0 / 0.75) ** 2))  # Eq. 4
    removal = 0.5  # Eq. 3's weights are all 0 (no last estimate: T = 0): uniform over the two targets
    birth = 0.5 * g(0.0) + 0.5 * g(2.0)  # detections drawn by k_d / N_d (1 - T) = 1/2 each
    expected = likelihood + interaction + math.log(NEWCOMER) + math.log(0.02 * removal) - math.log(0.15 * birth)
    assert log_beta == pytest.approx(expected, abs=1e-9)
    assert two.ids[0] == 7 and len(two.ids) == 2 and (two.xs[1], two.ys[1]) == (2.0, 0.0)
    back, again = tr.propose_remove(two, 1)
    assert back == pytest.approx(-log_beta, abs=1e-9)  # the reverse move's ratio is the inverse (Eq. 1)
    assert again.ids == [7] and again.log_pi == pytest.approx(one.log_pi)


def test_remove_of_the_only_target_by_hand():
    tr = prepared(RjmcmcTracker(weights=LASER, **CASE),
                  {"laser/legs": [[0, 0]], "laser/blobs": [[0, 0]]})
    one = tr.state([3], [0.1], [0.0])
    log_beta, empty = tr.propose_remove(one, 0)
    expected = (-(blob_term(g(0.1)) - MISS) - math.log(NEWCOMER) + math.log(0.15 * g(0.1))
                - math.log(0.02 * 1.0))
    assert log_beta == pytest.approx(expected, abs=1e-9)
    assert empty.ids == [] and empty.log_pi == 0.0


def test_update_ratio_one_target_and_two_targets_by_hand():
    tr = prepared(RjmcmcTracker(weights=LASER, **CASE), {"laser/legs": [[0, 0]], "laser/blobs": [[0, 0]]})
    log_beta, moved = tr.propose_update(tr.state([1], [0.3], [0.0]), 0, 0.1, 0.0)
    assert log_beta == pytest.approx(blob_term(g(0.1)) - blob_term(g(0.3)), abs=1e-12)
    assert (moved.xs, moved.ys) == ([0.1], [0.0])
    # a second target brought from 1.8 m to 0.5 m of the first: both explain the blob, Eq. 4 pushes them apart
    two = tr.state([1, 2], [0.0, 1.5], [0.0, 1.0])
    log_beta, _ = tr.propose_update(two, 1, 0.5, 0.0)
    phi = lambda d: 1 - math.exp(-(d / 0.75) ** 2)  # noqa: E731
    far = math.hypot(1.5, 1.0)
    expected = blob_term(1 + g(0.5)) - blob_term(1 + g(far)) + math.log(phi(0.5)) - math.log(phi(far))
    assert log_beta == pytest.approx(expected, abs=1e-9)


def test_mean_likelihood_is_eq5_as_written():
    tr = prepared(RjmcmcTracker(weights=LASER, likelihood="mean", **CASE),
                  {"laser/legs": [[0, 0]], "laser/blobs": [[0, 0], [3, 0]]})
    state = tr.state([1, 2], [0.0, 1.0], [0.0, 0.0])
    # (1/M) sum_i k (1/N) sum_j g(x_i; z_j), k = 1, N = 2 blobs, plus the empty state's 1e-3
    mean = ((g(0) + g(3)) / 2 + (g(1) + g(2)) / 2) / 2
    assert state.log_pi == pytest.approx(math.log(mean + 1e-3))


def camera_view(paint: dict) -> View:
    """A 320 x 240 camera 5 m behind the line y = 0 looking along +y, 1 m up, its bins image painted: {bin: box}."""
    rot = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # optical x, y, z in the floor's frame
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot, [0.0, -5.0, 1.0]
    bins = np.full((240, 320), BINS - 1, np.uint8)
    for value, (u0, v0, u1, v1) in paint.items():
        bins[v0:v1, u0:u1] = value
    return View("camera_1", bins, np.array([[200.0, 0, 160], [0, 200.0, 120], [0, 0, 1]]), pose)


def test_person_box_by_hand():
    view = camera_view({})
    # a person 5 m ahead: the feet 1 m below the camera, the head 0.7 m above: v = 120 + 200 * (1, -0.7) / 5
    assert person_box(view, 0.0, 0.0) == (150, 92, 170, 160)  # width 68 px * 0.5 / 1.7 = 20 px
    assert person_box(view, 0.0, -5.5) is None  # behind the camera


def test_swap_ratio_is_the_colour_terms_by_hand():
    view = camera_view({3: (0, 0, 160, 240), 10: (160, 0, 320, 240)})  # left half colour 3, right half colour 10
    tr = RjmcmcTracker(weights={"laser/legs": 1.0, "laser/blobs": 1.0, "camera_1/fseg": 1.0}, **CASE)
    tr.look([view])
    tr._prepare(detections(0.0, {"laser/legs": [[-0.5, 0], [0.5, 0]], "laser/blobs": [[-0.5, 0], [0.5, 0]],
                                 "camera_1/fseg": [[-0.5, 0], [0.5, 0]]}))
    tr._update_model(1, np.array([-0.5, 0.0]))  # colour 3 all over
    tr._update_model(2, np.array([0.5, 0.0]))  # colour 10
    state = tr.state([1, 2], [-0.5, 0.5], [0.0, 0.0])
    log_beta, swapped = tr.propose_swap(state, 0, 1)
    # each box then holds the other's colour: B = 1 in both, pi_B falls by exp(-lambda (1 + 1)), lambda = 20
    assert log_beta == pytest.approx(-40.0)
    assert swapped.ids == [2, 1] and swapped.log_pi == state.log_pi
    # an update that keeps target 1 in colour 3 has no colour term; one into colour 10 pays lambda * 1^2
    assert tr.propose_update(state, 0, -0.45, 0.0)[0] - tr.propose_update(state, 0, 0.4, 0.0)[0] == pytest.approx(
        20.0 + tr.propose_update(state, 0, -0.45, 0.0)[1].log_pi - tr.propose_update(state, 0, 0.4, 0.0)[1].log_pi
        + math.log(1 - math.exp(-(0.95 / 0.75) ** 2)) - math.log(1 - math.exp(-(0.1 / 0.75) ** 2)), abs=1e-9)


def test_swap_ratio_weighs_each_ids_last_positions():
    tr = prepared(RjmcmcTracker(weights=LASER, **CASE), {"laser/legs": [[0, 0]], "laser/blobs": [[0, 0]]})
    tr._by_id = {1: np.array([[0.0, 0.0]]), 2: np.array([[1.0, 0.0]])}
    log_beta, _ = tr.propose_swap(tr.state([1, 2], [0.0, 1.0], [0.0, 0.0]), 0, 1)
    assert log_beta == pytest.approx(2 * math.log(g(1.0)))  # both ids 1 m from where their particles had them


def crossing_views(a, b) -> list[View]:
    """The camera of ``camera_view`` seeing person a in colour 3 and b in colour 10."""
    probe = camera_view({})
    paint = {3: person_box(probe, *a), 10: person_box(probe, *b)}
    return [camera_view({k: v for k, v in paint.items() if v is not None})]


@pytest.mark.parametrize("seed", range(8))
def test_two_crossing_people_followed_without_a_swap(seed):
    """Two passers-by cross 0.5 m apart at 1.2 m/s, seen at 5 Hz by the laser and a camera that tells their colours
    apart: the filter keeps one id on each."""
    tr = RjmcmcTracker(weights={"laser/legs": 0.4, "laser/blobs": 0.4, "camera_1/fseg": 0.3, "camera_1/hog": 0.3},
                       seed=seed, **CASE)
    score = ClearMot(0.3)
    followed = {1: [], 2: []}
    for k in range(25):
        t = 0.2 * k
        a, b = (-2.5 + 1.2 * t, 0.25), (2.5 - 1.2 * t, -0.25)
        tr.look(crossing_views(a, b))
        tracks = tr.update(t, detections(t, {"laser/legs": [a, b], "laser/blobs": [a, b], "camera_1/fseg": [a, b],
                                             "camera_1/hog": [a, b]}))
        result = score.update(np.array([1, 2]), np.array([a, b]), tracks.track_id, tracks.position)
        for person, track in zip(result.matched_gt_ids, result.matched_hyp_ids):
            followed[int(person)].append(int(track))
    s = score.result()
    assert s.id_swaps == 0  # no track went from one of them to the other
    assert set(followed[1]).isdisjoint(followed[2])
    assert s.tsr >= 0.85  # both tracked from the second frame on, but for a frame or two
    assert s.fp <= 0.1 * s.gt  # a passing duplicate at most


def test_colour_models_follow_close_histograms_and_a_returning_person_gets_their_id():
    view = camera_view({3: (0, 0, 160, 240), 10: (160, 0, 320, 240)})  # left half colour 3, right half colour 10
    tr = RjmcmcTracker(weights={"laser/legs": 1.0, "laser/blobs": 1.0, "camera_1/fseg": 1.0}, **CASE)
    tr.look([view])
    tr._prepare(detections(0.0, {"laser/legs": [[-0.5, 0]], "laser/blobs": [[-0.5, 0]]}))
    tr._update_model(1, np.array([-0.5, 0.0]))
    red = tr._models[1]["camera_1"]
    assert red[3] == 1.0 and red.sum() == pytest.approx(1.0)
    # half the box in colour 10: B = sqrt(1 - sqrt(1/2)) = 0.54 > beta_t 0.24, so the model keeps its colour
    tr._update_model(1, np.array([-0.05, 0.0]))
    assert tr._models[1]["camera_1"][3] == 1.0
    # at x = -0.225 the 20-pixel box (141-160) has one column of colour 10: B = sqrt(1 - sqrt(0.95)) = 0.16, below
    # 0.24, so the model moves a tenth of the way there (Eq. 6, alpha 0.9)
    assert person_box(view, -0.225, 0.0) == (141, 92, 161, 160)
    sliver = np.zeros(BINS)
    sliver[3], sliver[10] = 0.95, 0.05
    tr._update_model(1, np.array([-0.225, 0.0]))
    np.testing.assert_allclose(tr._models[1]["camera_1"], 0.9 * red + 0.1 * sliver, atol=1e-12)
    # person 1 gone (not in the last estimate); a new id where colour 3 shows takes 1's id, one in colour 10 does not
    assert tr._reidentify({8: np.array([-0.5, 0.0])}) == {8: 1}
    assert tr._reidentify({8: np.array([0.5, 0.0])}) == {}
