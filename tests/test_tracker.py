"""Nearest-neighbour tracker (seed 000 Eq. 1-2, Sec. III-B/C, Table II "Greedy NN"); hand-worked values in comments."""

import numpy as np
import pytest

from evaluation import ClearMot
from pipeline.tracking.association import gated_mahalanobis, greedy_assign, mahalanobis
from pipeline.tracking.imm import kalman_update, kalman_update_soa
from pipeline.tracking.initiation import CountInitiation
from pipeline.tracking.motion import ConstantVelocity
from pipeline.tracking.nnt import NearestNeighbourTracker
from pipeline.types import DetectedPersons

DT = 0.04  # 25 Hz


def dets(stamp, xy, sigma=0.05, frame="odom", first_id=0):
    """DetectedPersons at the 2D positions xy [m, 2] with covariance diag(sigma^2, sigma^2, 1e6)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    m = xy.shape[0]
    pos = np.zeros((m, 3))
    pos[:, :2] = xy
    cov = np.zeros((m, 3, 3))
    cov[:, 0, 0] = cov[:, 1, 1] = sigma**2
    cov[:, 2, 2] = 1e6
    return DetectedPersons(stamp, frame, "laser", np.arange(first_id, first_id + m, dtype=np.int64), pos, cov,
                           np.ones(m))


def cv(q):
    """The CV model (seed 000 Eq. 1-2) on the tracker's default state [x, y, vx, vy]."""
    return ConstantVelocity(q)


def run(tracker, truth, rng, sigma):
    """Feed truth [T, n, 2] (one frame per DT) with Gaussian noise sigma; returns the list of outputs."""
    outs = []
    for k, xy in enumerate(truth):
        z = xy + sigma * rng.standard_normal(xy.shape)
        outs.append(tracker.update(k * DT, dets(k * DT, z, sigma=sigma, first_id=k * len(xy))))
    return outs


# ---------------------------------------------------------------------------------------------------------------
# Small parts
# ---------------------------------------------------------------------------------------------------------------


def test_predict_matches_hand_worked_covariance():
    # State [x, y, vx, vy], dt = 0.5, q = 0.2.
    # P: variances 1, 2, 3, 4; cov(x, y) = 0.5, cov(vx, vy) = 0.4.
    # F P F^T (F: x += dt vx, y += dt vy):
    #   xx = 1 + 0.25*3 = 1.75          yy = 2 + 0.25*4 = 3.0        xy = 0.5 + 0.25*0.4 = 0.6
    #   x,vx = 0.5*3 = 1.5              y,vy = 0.5*4 = 2.0           x,vy = y,vx = 0.5*0.4 = 0.2
    #   vx,vx = 3, vy,vy = 4, vx,vy = 0.4
    # Q: t^3/3 q = 0.125/3*0.2 = 0.0083333, t^2/2 q = 0.125*0.2 = 0.025, t q = 0.1
    P = np.array([[1.0, 0.5, 0.0, 0.0], [0.5, 2.0, 0.0, 0.0], [0.0, 0.0, 3.0, 0.4], [0.0, 0.0, 0.4, 4.0]])
    q3 = 0.125 / 3 * 0.2
    expected = np.array([
        [1.75 + q3, 0.6, 1.5 + 0.025, 0.2],
        [0.6, 3.0 + q3, 0.2, 2.0 + 0.025],
        [1.525, 0.2, 3.1, 0.4],
        [0.2, 2.025, 0.4, 4.1],
    ])
    x = np.array([[1.0, 2.0, 3.0, -4.0]])
    x_pred, P_pred = cv(0.2).predict(x, P[None], 0.5)
    np.testing.assert_allclose(P_pred[0], expected, atol=1e-12)
    np.testing.assert_allclose(x_pred[0], [2.5, 0.0, 3.0, -4.0], atol=1e-12)  # x + dt v
    # inputs untouched, and a batch of two gives each its own result
    np.testing.assert_array_equal(x, [[1.0, 2.0, 3.0, -4.0]])
    _, P2 = cv(0.2).predict(np.zeros((2, 4)), np.stack([P, np.eye(4)]), 0.5)
    np.testing.assert_allclose(P2[0], expected, atol=1e-12)
    F, Q = cv(0.2).matrices(0.5)
    np.testing.assert_allclose(F, [[1, 0, 0.5, 0], [0, 1, 0, 0.5], [0, 0, 1, 0], [0, 0, 0, 1]])  # Eq. 1
    np.testing.assert_allclose(P2[1], F @ F.T + Q)


def test_process_noise_is_eq2():
    # dt = 1, q = 3: [[1/3, 1/2], [1/2, 1]] * 3 per axis
    np.testing.assert_allclose(cv(3.0).matrices(1.0)[1],
                               [[1, 0, 1.5, 0], [0, 1, 0, 1.5], [1.5, 0, 3, 0], [0, 1.5, 0, 3]])


def test_mahalanobis_hand_worked():
    # track at (0, 0) with position covariance diag(1, 3); detections with R = diag(1, 1):
    #   S = diag(2, 4); z = (2, 0) -> 4/2 = 2; z = (0, 4) -> 16/4 = 4; z = (2, 4) -> 6
    x = np.zeros((1, 4))
    P = np.diag([1.0, 3.0, 1.0, 1.0])[None]
    z = np.array([[2.0, 0.0], [0.0, 4.0], [2.0, 4.0]])
    R = np.repeat(np.eye(2)[None], 3, axis=0)
    np.testing.assert_allclose(mahalanobis(x, P, z, R), [[2.0, 4.0, 6.0]])
    # correlated S = [[2, 1], [1, 2]] (P xy = 1): S^-1 = [[2, -1], [-1, 2]] / 3; nu = (1, 1) -> (2 - 2 + 2) / 3 = 2/3
    P = np.array([[[1.0, 1.0, 0, 0], [1.0, 1.0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]])
    np.testing.assert_allclose(mahalanobis(x, P, np.array([[1.0, 1.0]]), np.eye(2)[None]), [[2.0 / 3.0]])


def test_gated_mahalanobis_is_the_full_matrix_within_the_gate():
    # 80 tracks x 70 detections, correlated and unequal covariances, some tracks far more uncertain than others,
    # detections sharing an x: every pair within the gate has the full matrix's value, bit for bit, no pair within it
    # is missed, and the windows skip most pairs (inf)
    rng = np.random.default_rng(3)
    n, m, gate = 80, 70, 13.82
    x = rng.uniform(0, 30, (n, 4))
    A = rng.normal(0, 0.3, (n, 4, 4)) * rng.choice([0.2, 1.0, 3.0], (n, 1, 1))
    P = A @ A.transpose(0, 2, 1) + 0.01 * np.eye(4)
    z = np.concatenate([x[:50, :2] + rng.normal(0, 0.3, (50, 2)), rng.uniform(0, 30, (20, 2))])
    z[60:65, 0] = z[10, 0]
    B = rng.normal(0, 0.2, (m, 2, 2))
    R = B @ B.transpose(0, 2, 1) + 0.005 * np.eye(2)
    full, gated = mahalanobis(x, P, z, R), gated_mahalanobis(x, P, z, R, gate)
    inside = full <= gate
    assert inside.sum() > 100 and np.isfinite(gated).sum() < n * m / 2  # a test of windows that skip pairs
    np.testing.assert_array_equal(gated <= gate, inside)
    np.testing.assert_array_equal(gated[inside], full[inside])
    # strided views (the tracker passes its state transposed) give the same numbers
    np.testing.assert_array_equal(mahalanobis(np.asfortranarray(x), P.transpose(0, 2, 1), z, R), full)


def test_gated_mahalanobis_windows_hand_worked():
    # a track at x = 0 with P_xx = 1, detections with R = I: S_xx = 2, and the window is |dx| <= sqrt(2 * 1.5 * 3)
    # = 3 for a gate of 3. Detections at x = 1 (d2 = 1/2), 2.9 (4.205: inside the window, beyond the gate), 3.1
    # (outside the window: inf), -2 (2)
    x, P = np.zeros((1, 2)), np.eye(2)[None]
    z = np.array([[1.0, 0.0], [2.9, 0.0], [3.1, 0.0], [-2.0, 0.0]])
    R = np.repeat(np.eye(2)[None], 4, axis=0)
    np.testing.assert_allclose(gated_mahalanobis(x, P, z, R, 3.0), [[0.5, 4.205, np.inf, 2.0]])
    np.testing.assert_allclose(mahalanobis(x, P, z, R), [[0.5, 4.205, 4.805, 2.0]])
    assert gated_mahalanobis(x, P, z[:0], R[:0], 3.0).shape == (1, 0)
    assert gated_mahalanobis(x[:0], P[:0], z, R, 3.0).shape == (0, 4)


def test_greedy_assign_takes_global_minimum_first():
    # cost [[1, 2], [1.5, 8]]: greedy takes (0,0)=1, then (1,1)=8 (the optimum would be (0,1)+(1,0) = 3.5)
    cost = np.array([[1.0, 2.0], [1.5, 8.0]])
    r, c = greedy_assign(cost, 9.21)
    assert r.tolist() == [0, 1] and c.tolist() == [0, 1]
    # with the gate below 8, row 1 stays unmatched
    r, c = greedy_assign(cost, 5.0)
    assert r.tolist() == [0] and c.tolist() == [0]
    # the tracker lets confirmed tracks choose first: row 1 alone takes (1,0)=1.5, row 0 then gets column 1 (2)
    r, c = greedy_assign(cost[1:], 9.21)
    assert r.tolist() == [0] and c.tolist() == [0]
    r, c = greedy_assign(cost[:1, 1:], 9.21)
    assert r.tolist() == [0] and c.tolist() == [0]
    # ties go to the smaller (row, col)
    r, c = greedy_assign(np.ones((2, 2)), 9.21)
    assert r.tolist() == [0, 1] and c.tolist() == [0, 1]
    r, c = greedy_assign(np.zeros((0, 3)), 9.21)
    assert r.size == 0 and c.size == 0


def test_kalman_update_hand_worked():
    # P: var x = var y = 1, var vx = var vy = 2, cov(x, vx) = cov(y, vy) = 0.5; R = I -> S = 2 I,
    # K = P H^T / 2 = [[.5, 0], [0, .5], [.25, 0], [0, .25]]; z = (2, -4), x = 0 -> x+ = (1, -2, 0.5, -1)
    # P+ = P - K H P: xx = 1 - .5 = .5, x,vx = .5 - .25 = .25, vx,vx = 2 - .25*.5 = 1.875 (same for y)
    P = np.array([[1.0, 0, 0.5, 0], [0, 1.0, 0, 0.5], [0.5, 0, 2.0, 0], [0, 0.5, 0, 2.0]])
    x_new, P_new = kalman_update(np.zeros((1, 4)), P[None], np.array([[2.0, -4.0]]), np.eye(2)[None])
    np.testing.assert_allclose(x_new[0], [1.0, -2.0, 0.5, -1.0])
    np.testing.assert_allclose(P_new[0], [[0.5, 0, 0.25, 0], [0, 0.5, 0, 0.25], [0.25, 0, 1.875, 0],
                                          [0, 0.25, 0, 1.875]])
    # log N(nu; 0, S) + log(2 pi) = -(nu^T S^-1 nu + log det S) / 2 = -(20 / 2 + log 4) / 2
    _, _, log_l = kalman_update(np.zeros((1, 4)), P[None], np.array([[2.0, -4.0]]), np.eye(2)[None], True)
    np.testing.assert_allclose(log_l, [-(10.0 + np.log(4.0)) / 2])


def test_kalman_update_of_an_imms_models_broadcasts_the_detection():
    # the IMM's layout: x [d, M, n] with z [2, 1, n]. Model 0 is the hand-worked case above; model 1 has P = I, so
    # S = 2 I, K = [[.5, 0], [0, .5], [0, 0], [0, 0]]: x+ = (1, -2, 0, 0), P+ = diag(.5, .5, 1, 1)
    P0 = np.array([[1.0, 0, 0.5, 0], [0, 1.0, 0, 0.5], [0.5, 0, 2.0, 0], [0, 0.5, 0, 2.0]])
    P = np.stack([P0, np.eye(4)], -1)[..., None]  # [4, 4, 2, 1]
    x_new, P_new, log_l = kalman_update_soa(np.zeros((4, 2, 1)), P, np.array([2.0, -4.0])[:, None, None],
                                            np.eye(2)[:, :, None, None], log_likelihood=True)
    np.testing.assert_allclose(x_new[:, :, 0].T, [[1.0, -2.0, 0.5, -1.0], [1.0, -2.0, 0.0, 0.0]])
    np.testing.assert_allclose(P_new[:, :, 1, 0], np.diag([0.5, 0.5, 1.0, 1.0]))
    np.testing.assert_allclose(P_new[:2, :2, 0, 0], 0.5 * np.eye(2))
    np.testing.assert_allclose(log_l[:, 0], [-(10.0 + np.log(4.0)) / 2] * 2)  # the same S and nu under both


# ---------------------------------------------------------------------------------------------------------------
# The tracker
# ---------------------------------------------------------------------------------------------------------------


def test_single_walker_velocity_converges_with_one_id():
    # 1.2 m/s along x, 25 Hz, sigma 0.02 m, 2 s. With q_L = 0.001 (a nearly-constant-velocity model, right for this
    # walker) the velocity at 2 s is within 0.1 m/s (over seeds 0-499 the worst axis error was 0.039 m/s).
    t = np.arange(51) * DT  # 0 .. 2.0 s
    truth = np.stack([1.2 * t, np.full_like(t, 3.0)], axis=1)[:, None, :]
    outs = run(NearestNeighbourTracker(motion=cv(0.001)), truth, np.random.default_rng(7), 0.02)
    last = outs[-1]
    assert len(last) == 1
    assert np.abs(last.velocity[0] - [1.2, 0.0]).max() < 0.1
    assert np.abs(last.position[0] - truth[-1, 0]).max() < 0.05
    ids = np.unique(np.concatenate([o.track_id for o in outs]))
    assert ids.tolist() == [1]
    # confirmed at the third detection (t = 0.08 s), matched every cycle since, age = time since the first
    assert [len(o) for o in outs[:3]] == [0, 0, 1]
    assert last.is_matched.all() and not last.is_occluded.any()
    assert last.detection_id[0] == 50
    assert last.age[0] == pytest.approx(2.0)
    assert last.position_covariance.shape == (1, 2, 2) and last.velocity_covariance.shape == (1, 2, 2)


def test_single_walker_default_params():
    # The default q_L = 0.267 follows manoeuvres, so one velocity estimate is noisy (the filter's own per-axis std
    # is 0.17 m/s here): check the mean over the last second (seeds 0-499: worst 0.044 m/s) and that the error at
    # 2 s is consistent with the reported covariance (NEES under the chi2(2) 0.999 quantile; seeds 0-499: <= 5.3).
    t = np.arange(51) * DT
    truth = np.stack([1.2 * t, np.full_like(t, 3.0)], axis=1)[:, None, :]
    outs = run(NearestNeighbourTracker(), truth, np.random.default_rng(7), 0.02)
    assert np.unique(np.concatenate([o.track_id for o in outs])).tolist() == [1]
    v_mean = np.mean([o.velocity[0] for o in outs[26:]], axis=0)
    assert np.abs(v_mean - [1.2, 0.0]).max() < 0.1
    e = outs[-1].velocity[0] - [1.2, 0.0]
    assert e @ np.linalg.solve(outs[-1].velocity_covariance[0], e) < 13.82
    assert np.sqrt(outs[-1].velocity_covariance[0, 0, 0]) == pytest.approx(0.169, abs=0.005)


def test_two_people_crossing_keep_their_ids():
    rng = np.random.default_rng(3)
    t = np.arange(0, 10.0, DT)
    s = 1.3 * t / np.sqrt(2.0)  # per-axis displacement; both reach (0, 0) at t = 5 sqrt(2) / 1.3 = 5.44 s
    a = np.stack([-5 + s, -5 + s], axis=1)  # (-5, -5) -> (5, 5)
    b = np.stack([-5 + s, 5 - s], axis=1)  # (-5, 5) -> (5, -5)
    truth = np.stack([a, b], axis=1)
    # Greedy NN can swap two people whose detections coincide; with these settings that happened in 3 of seeds
    # 0-299 (an early track loss in 1), so this checks the usual outcome, not a guarantee.
    outs = run(NearestNeighbourTracker(), truth, rng, sigma=0.03)

    def nearest_id(k, person):
        o = outs[k]
        return int(o.track_id[np.argmin(np.linalg.norm(o.position - truth[k, person], axis=1))])

    before, after = int(round(3.0 / DT)), int(round(9.0 / DT))
    assert (nearest_id(before, 0), nearest_id(before, 1)) == (nearest_id(after, 0), nearest_id(after, 1))
    assert nearest_id(before, 0) != nearest_id(before, 1)
    # and nothing else was ever confirmed: exactly two ids, each track near its own person all the way
    assert np.unique(np.concatenate([o.track_id for o in outs])).size == 2
    for k in range(3, len(outs)):
        assert len(outs[k]) == 2
        for person in (0, 1):
            i = outs[k].track_id == nearest_id(before, person)
            assert np.linalg.norm(outs[k].position[i][0] - truth[k, person]) < 0.2


@pytest.mark.parametrize("n_confirm", [1, 3, 5])
def test_initiation_after_n_confirm_detections(n_confirm):
    trk = NearestNeighbourTracker(initiation=CountInitiation(n_confirm))
    for k in range(n_confirm - 1):
        out = trk.update(k * DT, dets(k * DT, [[1.0, 2.0]], first_id=k))
        assert len(out) == 0  # seen k + 1 < n_confirm times: tentative only
        assert trk.num_tracks == 1
    k = n_confirm - 1
    out = trk.update(k * DT, dets(k * DT, [[1.0, 2.0]], first_id=k))
    assert out.track_id.tolist() == [1]
    assert out.is_matched.tolist() == [True] and out.detection_id.tolist() == [k]
    np.testing.assert_allclose(out.position, [[1.0, 2.0]], atol=1e-12)
    assert out.age[0] == pytest.approx(k * DT)


def test_ids_are_consecutive_over_confirmed_tracks_only():
    # a one-off false alarm at t=0 makes a tentative track that dies; the real person still gets id 1
    trk = NearestNeighbourTracker()
    trk.update(0.0, dets(0.0, [[0.0, 0.0], [10.0, 10.0]]))
    for k in range(1, 4):
        out = trk.update(k * DT, dets(k * DT, [[0.0, 0.0]], first_id=10 * k))
    assert out.track_id.tolist() == [1]
    assert trk.num_tracks == 1  # the false alarm was deleted after n_delete_tentative = 2 misses


def test_confirmed_track_deleted_after_n_delete_misses():
    trk = NearestNeighbourTracker()
    n_delete = trk.deletion.n_delete
    assert n_delete == 5
    for k in range(3):
        out = trk.update(k * DT, dets(k * DT, [[1.0, 2.0]], first_id=k))
    assert out.track_id.tolist() == [1]
    for miss in range(1, n_delete):
        stamp = (2 + miss) * DT
        out = trk.update(stamp, DetectedPersons.empty(stamp, "odom", "laser"))
        assert out.track_id.tolist() == [1], miss
        assert out.is_occluded.tolist() == [True] and out.is_matched.tolist() == [False]
        assert out.detection_id.tolist() == [-1]
    stamp = (2 + n_delete) * DT
    out = trk.update(stamp, DetectedPersons.empty(stamp, "odom", "laser"))
    assert len(out) == 0 and trk.num_tracks == 0


def test_occluded_track_is_recovered_with_its_id():
    trk = NearestNeighbourTracker()
    for k in range(10):
        trk.update(k * DT, dets(k * DT, [[1.3 * k * DT, 0.0]], first_id=k))
    for k in range(10, 13):  # 3 misses < n_delete: coasting
        out = trk.update(k * DT, DetectedPersons.empty(k * DT, "odom", "laser"))
        assert out.is_occluded.tolist() == [True]
    out = trk.update(13 * DT, dets(13 * DT, [[1.3 * 13 * DT, 0.0]], first_id=13))
    assert out.track_id.tolist() == [1] and out.is_matched.tolist() == [True] and out.detection_id.tolist() == [13]


def test_tentative_track_survives_one_miss_and_dies_after_two():
    trk = NearestNeighbourTracker()  # tentative = 2 misses, n_confirm = 3
    trk.update(0.0, dets(0.0, [[0.0, 0.0]]))
    trk.update(DT, DetectedPersons.empty(DT, "odom", "laser"))
    assert trk.num_tracks == 1
    trk.update(2 * DT, dets(2 * DT, [[0.0, 0.0]]))
    out = trk.update(3 * DT, dets(3 * DT, [[0.0, 0.0]]))
    assert out.track_id.tolist() == [1]  # three detections despite the miss: confirmed
    trk2 = NearestNeighbourTracker()
    trk2.update(0.0, dets(0.0, [[0.0, 0.0]]))
    trk2.update(DT, DetectedPersons.empty(DT, "odom", "laser"))
    trk2.update(2 * DT, DetectedPersons.empty(2 * DT, "odom", "laser"))
    assert trk2.num_tracks == 0


def test_confirmed_track_gets_detection_before_tentative_one():
    # confirmed track at (0, 0); a tentative candidate is born at (0.1, 0) (closer to the next detection);
    # the next detection at (0.08, 0) must go to the confirmed track, the candidate misses.
    trk = NearestNeighbourTracker()
    for k in range(3):
        trk.update(k * DT, dets(k * DT, [[0.0, 0.0]], sigma=0.1))
    trk.update(3 * DT, dets(3 * DT, [[0.0, 0.0], [0.1, 0.0]], sigma=0.1, first_id=30))
    out = trk.update(4 * DT, dets(4 * DT, [[0.1, 0.0]], sigma=0.1, first_id=40))
    assert out.detection_id.tolist() == [40]
    assert trk.num_tracks == 2  # the candidate missed once and is still held


def test_wrong_frame_raises_naming_both_frames():
    trk = NearestNeighbourTracker(frame="odom")
    with pytest.raises(ValueError) as e:
        trk.update(0.0, dets(0.0, [[1.0, 2.0]], frame="base_link"))
    assert "odom" in str(e.value) and "base_link" in str(e.value)


def test_bad_input_raises():
    trk = NearestNeighbourTracker()
    trk.update(1.0, dets(1.0, [[0.0, 0.0]]))
    with pytest.raises(ValueError, match="earlier"):
        trk.update(0.5, dets(0.5, [[0.0, 0.0]]))
    with pytest.raises(ValueError, match="finite"):
        trk.update(2.0, dets(2.0, [[np.nan, 0.0]]))
    with pytest.raises(ValueError, match="positive definite"):
        trk.update(2.0, dets(2.0, [[0.0, 0.0]], sigma=0.0))


def test_reset_restarts_ids_and_is_deterministic():
    rng = np.random.default_rng(11)
    truth = np.stack([np.stack([1.0 * np.arange(40) * DT, np.zeros(40)], 1),
                      np.stack([np.zeros(40), 5 - 1.0 * np.arange(40) * DT], 1)], axis=1)
    noise = 0.05 * rng.standard_normal(truth.shape)
    trk = NearestNeighbourTracker()

    def go():
        return [trk.update(k * DT, dets(k * DT, truth[k] + noise[k], first_id=2 * k)) for k in range(40)]

    first = go()
    trk.reset()
    assert trk.num_tracks == 0
    second = go()
    for a, b in zip(first, second):
        np.testing.assert_array_equal(a.track_id, b.track_id)
        np.testing.assert_array_equal(a.position, b.position)
    assert second[-1].track_id.tolist() == [1, 2]


def test_empty_input_and_empty_tracker():
    trk = NearestNeighbourTracker()
    out = trk.update(0.0, DetectedPersons.empty(0.0, "odom", "laser"))
    assert len(out) == 0 and out.frame == "odom" and out.position.shape == (0, 2)


def _crowd(n, steps, rng, size=30.0, sigma=0.05):
    """n walkers at ~1.3 m/s in a size x size box with a heading random walk, turned back smoothly at the walls."""
    pos = rng.uniform(0, size, (n, 2))
    hd = rng.uniform(-np.pi, np.pi, n)
    sp = np.clip(rng.normal(1.3, 0.15, n), 0.5, 2.0)
    truth, meas = [], []
    for _ in range(steps):
        hd += 0.5 * np.sqrt(DT) * rng.standard_normal(n)
        c = size / 2 - pos
        near = (np.abs(c) > size / 2 - 3).any(1)
        err = np.angle(np.exp(1j * (np.arctan2(c[:, 1], c[:, 0]) - hd)))
        hd[near] += np.clip(err[near], -1.5 * DT, 1.5 * DT)
        pos = pos + DT * sp[:, None] * np.stack([np.cos(hd), np.sin(hd)], 1)
        truth.append(pos.copy())
        meas.append(pos + sigma * rng.standard_normal(pos.shape))
    return truth, meas


def test_crowd_of_thirty_is_tracked_well():
    # 30 walkers, 20 s at 25 Hz, sigma 0.05 m, every person detected every frame. The first two frames lack tracks
    # (n_confirm = 3): FN >= 2 * 30 = 60. Over seeds 0-39: MOTA >= 0.9957, <= 2 ID switches (people walking
    # through each other), FN <= 61, MOTP <= 0.046 m.
    rng = np.random.default_rng(5)
    truth, meas = _crowd(30, 500, rng)
    trk = NearestNeighbourTracker()
    cm = ClearMot()
    gid = np.arange(30)
    for k in range(500):
        out = trk.update(k * DT, dets(k * DT, meas[k], first_id=30 * k))
        cm.update(gid, truth[k], out.track_id, out.position)
    s = cm.result()
    assert s.mota > 0.99
    assert s.id_switches <= 5
    assert 60 <= s.fn <= 65
    assert s.motp_m < 0.06
