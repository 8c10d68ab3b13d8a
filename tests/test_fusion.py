"""Bringing detections into one frame and fusing the detections of two lasers; hand-worked values in comments."""

import numpy as np
import pytest

from pipeline.frames import inverse
from pipeline.fusion import fuse, to_frame
from pipeline.types import UNKNOWN_VARIANCE, DetectedPersons


def dets(xy, cov_xy=None, frame="base_link", modality="laser2d", stamp=2.0, first_id=0, conf=None):
    """DetectedPersons at xy [m, 2] (z = 0.3) with 2x2 covariances cov_xy (default diag(0.1, 0.1)), z unknown."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    m = len(xy)
    pos = np.concatenate([xy, np.full((m, 1), 0.3)], 1)
    cov = np.zeros((m, 3, 3))
    cov[:, :2, :2] = np.diag([0.1, 0.1]) if cov_xy is None else cov_xy
    cov[:, 2, 2] = UNKNOWN_VARIANCE
    conf = np.ones(m) if conf is None else np.asarray(conf, float)
    return DetectedPersons(stamp, frame, modality, np.arange(first_id, first_id + m, dtype=np.int64), pos, cov, conf)


# ---------------------------------------------------------------------------------------------------------------
# to_frame
# ---------------------------------------------------------------------------------------------------------------


def test_to_frame_moves_positions_and_rotates_covariances():
    # Laser frame posed at (1, 2, 30 deg) in base_link; c = cos 30 = 0.8660, s = sin 30 = 0.5.
    # Point (2, 1): (1 + 2c - 1s, 2 + 2s + 1c) = (1 + 1.7321 - 0.5, 2 + 1 + 0.8660) = (2.2321, 3.8660).
    # Covariance diag(a, b) = diag(0.04, 0.01) rotated: R C R^T = [[a c^2 + b s^2, (a - b) c s],
    #                                                             [(a - b) c s, a s^2 + b c^2]]
    #   = [[0.03 + 0.0025, 0.03 x 0.4330], [., 0.01 + 0.0075]] = [[0.0325, 0.012990], [0.012990, 0.0175]].
    src = dets([(2.0, 1.0)], cov_xy=np.diag([0.04, 0.01]), frame="front_laser")
    out = to_frame(src, np.array([1.0, 2.0, np.radians(30.0)]), "base_link")
    assert out.frame == "base_link"
    np.testing.assert_allclose(out.position[0], [2.2320508, 3.8660254, 0.3], atol=1e-7)
    np.testing.assert_allclose(out.covariance[0, :2, :2], [[0.0325, 0.0129904], [0.0129904, 0.0175]], atol=1e-7)
    assert out.covariance[0, 2, 2] == UNKNOWN_VARIANCE
    np.testing.assert_array_equal(out.covariance[0, :2, 2], [0.0, 0.0])
    # the rest passes through; the input is left as it was
    assert out.stamp == 2.0 and out.modality == "laser2d"
    np.testing.assert_array_equal(out.detection_id, src.detection_id)
    np.testing.assert_array_equal(out.confidence, src.confidence)
    np.testing.assert_array_equal(src.position[0], [2.0, 1.0, 0.3])
    np.testing.assert_array_equal(src.covariance[0, :2, :2], np.diag([0.04, 0.01]))


def test_to_frame_from_a_backwards_mounted_laser():
    # Rear laser at (-0.25, 0, pi): a person 2 m ahead of it and 0.5 m to its left, (2, 0.5), is behind the robot
    # and to its right: (-0.25 - 2, -0.5) = (-2.25, -0.5). A covariance long along the laser's x stays long along x
    # (a rotation by pi flips the sign of nothing in R C R^T), an off-diagonal term keeps its sign as well.
    cov = np.array([[0.09, 0.02], [0.02, 0.01]])
    out = to_frame(dets([(2.0, 0.5)], cov_xy=cov, frame="rear_laser"), np.array([-0.25, 0.0, np.pi]), "base_link")
    np.testing.assert_allclose(out.position[0, :2], [-2.25, -0.5], atol=1e-12)
    np.testing.assert_allclose(out.covariance[0, :2, :2], cov, atol=1e-12)
    # a quarter turn swaps the axes and flips the sign of the cross term: [[0.01, -0.02], [-0.02, 0.09]]
    out = to_frame(dets([(2.0, 0.5)], cov_xy=cov), np.array([0.0, 0.0, np.pi / 2]), "odom")
    np.testing.assert_allclose(out.position[0, :2], [-0.5, 2.0], atol=1e-12)
    np.testing.assert_allclose(out.covariance[0, :2, :2], [[0.01, -0.02], [-0.02, 0.09]], atol=1e-12)


def test_to_frame_round_trip_with_the_inverse_pose():
    rng = np.random.default_rng(3)
    xy = rng.uniform(-10, 10, (5, 2))
    a = rng.normal(size=(5, 2, 2))
    cov = a @ a.transpose(0, 2, 1)
    src = dets(xy, cov_xy=cov, frame="front_laser")
    pose = np.array([0.7, -1.2, 2.4])
    back = to_frame(to_frame(src, pose, "odom"), inverse(pose), "front_laser")
    np.testing.assert_allclose(back.position, src.position, atol=1e-12)
    np.testing.assert_allclose(back.covariance, src.covariance, atol=1e-12)


# ---------------------------------------------------------------------------------------------------------------
# fuse
# ---------------------------------------------------------------------------------------------------------------


def pair(front: DetectedPersons, rear: DetectedPersons) -> dict[str, DetectedPersons]:
    return {"front_laser": front, "rear_laser": rear}


def by_x(d: DetectedPersons):
    order = np.argsort(d.position[:, 0])
    return d.position[order], d.covariance[order], d.confidence[order]


def test_close_detections_of_two_lasers_become_one_at_their_mean():
    # Front sees (1, 0) and (5, 0); rear sees (1.2, 0.1) (0.224 m from (1, 0), < 0.4) and (10, 0).
    # Fused: (1.1, 0.05, 0.3) with covariance (Ca + Cb) / 4, the variance of the mean of two independent estimates:
    #   Ca = [[0.04, 0.01], [0.01, 0.02]], Cb = diag(0.08, 0.06) -> [[0.03, 0.0025], [0.0025, 0.02]], z: 2e6 / 4.
    ca = np.array([[0.04, 0.01], [0.01, 0.02]])
    cb = np.diag([0.08, 0.06])
    front = dets([(1.0, 0.0), (5.0, 0.0)], cov_xy=ca, conf=[0.6, 0.9])
    rear = dets([(1.2, 0.1), (10.0, 0.0)], cov_xy=cb, conf=[0.8, 0.7])
    out = fuse({"front_laser": front, "rear_laser": rear}, 0.4, first_id=100)
    assert len(out) == 3
    pos, cov, conf = by_x(out)
    np.testing.assert_allclose(pos, [[1.1, 0.05, 0.3], [5.0, 0.0, 0.3], [10.0, 0.0, 0.3]], atol=1e-12)
    np.testing.assert_allclose(cov[0, :2, :2], [[0.03, 0.0025], [0.0025, 0.02]], atol=1e-12)
    assert cov[0, 2, 2] == pytest.approx(UNKNOWN_VARIANCE / 2)
    np.testing.assert_allclose(cov[1, :2, :2], ca, atol=1e-12)  # unfused ones keep theirs
    np.testing.assert_allclose(cov[2, :2, :2], cb, atol=1e-12)
    np.testing.assert_allclose(conf, [0.8, 0.9, 0.7])  # a fused detection keeps the higher confidence
    np.testing.assert_array_equal(np.sort(out.detection_id), [100, 101, 102])
    assert out.frame == "base_link" and out.stamp == 2.0 and out.modality == "laser2d"


def test_detections_of_one_batch_are_never_fused():
    # Two people 0.1 m apart seen by the same laser stay two, whatever the distance; so does a single batch.
    a = dets([(2.0, 0.0), (2.1, 0.0)])
    b = dets([(8.0, 0.0)])
    out = fuse({"front_laser": a, "rear_laser": b}, 0.4)
    pos, _, _ = by_x(out)
    np.testing.assert_allclose(pos[:, :2], [[2.0, 0.0], [2.1, 0.0], [8.0, 0.0]])
    assert len(fuse({"front_laser": a}, 0.4)) == 2


def test_distance_threshold_is_strict():
    # 0.5 m apart (exact in binary): not nearer than 0.5 -> two; 0.49 m apart -> one at (0.245, 0).
    assert len(fuse(pair(dets([(0.0, 0.0)]), dets([(0.5, 0.0)])), 0.5)) == 2
    out = fuse(pair(dets([(0.0, 0.0)]), dets([(0.49, 0.0)])), 0.5)
    assert len(out) == 1
    np.testing.assert_allclose(out.position[0, :2], [0.245, 0.0])


def test_nearest_pair_is_fused_first():
    # Front: (0, 0) and (0.5, 0); rear: (0.3, 0). Both front ones are within 0.4 of the rear one (0.3 and 0.2 m);
    # the nearer pair (0.5, 0)-(0.3, 0) is fused at (0.4, 0); (0, 0) stays alone.
    out = fuse(pair(dets([(0.0, 0.0), (0.5, 0.0)]), dets([(0.3, 0.0)])), 0.4)
    pos, cov, _ = by_x(out)
    np.testing.assert_allclose(pos[:, :2], [[0.0, 0.0], [0.4, 0.0]], atol=1e-12)
    np.testing.assert_allclose(cov[:, 0, 0], [0.1, 0.05])


def test_modalities_are_joined():
    out = fuse(pair(dets([(0.0, 0.0)], modality="laser2d"), dets([(0.1, 0.0)], modality="rgbd")), 0.4)
    assert out.modality == "laser2d+rgbd" and len(out) == 1


def test_empty_batches_fuse_to_nothing():
    out = fuse(pair(dets(np.zeros((0, 2))), dets(np.zeros((0, 2)))), 0.4)
    assert len(out) == 0 and out.position.shape == (0, 3) and out.covariance.shape == (0, 3, 3)
    out = fuse(pair(dets(np.zeros((0, 2))), dets([(1.0, 2.0)])), 0.4)
    np.testing.assert_allclose(out.position, [[1.0, 2.0, 0.3]])


def test_mixing_frames_raises():
    with pytest.raises(ValueError, match="one frame"):
        fuse(pair(dets([(0.0, 0.0)], frame="front_laser"), dets([(0.0, 0.0)], frame="base_link")), 0.4)


def test_to_frame_turns_the_full_covariance():
    # a yaw of 90 degrees: R C R^T with R the 3x3 yaw rotation, cross terms with z included
    cov = np.diag([0.04, 0.01, 0.09])
    cov[0, 2] = cov[2, 0] = 0.01
    d = DetectedPersons(0.0, "laser", "laser2d", np.array([0]), np.zeros((1, 3)), cov[None], np.ones(1))
    out = to_frame(d, np.array([0.0, 0.0, np.pi / 2]), "odom")
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(out.covariance[0], rot @ cov @ rot.T, atol=1e-12)
    # by hand: x-x and y-y swap, the x-z term moves to y-z
    np.testing.assert_allclose(out.covariance[0], [[0.01, 0, 0], [0, 0.04, 0.01], [0, 0.01, 0.09]], atol=1e-12)


def test_a_tie_goes_to_the_first_pair_and_nan_confidence_stays():
    # front: (0, 0); rear: (0.3, 0) and (-0.3, 0), both 0.3 from it, and (5, 0) alone. The pairs in order are
    # (front 0, rear 0) and (front 0, rear 1) at equal distance: the first merges, at (0.15, 0), and rear 1 stays
    # alone; the merged row's confidence is the larger, rear 1 keeps its NaN (numpy's maximum lets NaN through)
    fused = fuse({"front": dets([(0.0, 0.0)], conf=[0.6]),
                  "rear": dets([(0.3, 0.0), (-0.3, 0.0), (5.0, 0.0)], conf=[0.8, np.nan, 0.5])}, 0.4)
    np.testing.assert_allclose(fused.position[:, :2], [[0.15, 0.0], [-0.3, 0.0], [5.0, 0.0]], atol=1e-12)
    assert fused.originals["front"].tolist() == [0, -1, -1] and fused.originals["rear"].tolist() == [0, 1, 2]
    assert fused.confidence[0] == 0.8 and np.isnan(fused.confidence[1]) and fused.confidence[2] == 0.5
    # the mean of two estimates of variance 0.1 has variance 0.1 / 2; one alone keeps 0.1
    np.testing.assert_allclose(fused.covariance[:, 0, 0], [0.05, 0.1, 0.1], atol=1e-12)
