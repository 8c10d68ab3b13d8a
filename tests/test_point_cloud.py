"""Seed 003's point-cloud steps by hand: voxel centroids, the ground plane from a noisy synthetic floor, Euclidean
clusters."""

import numpy as np
import pytest

from pipeline.detectors.point_cloud import euclidean_clusters, plane_distance, ransac_plane, voxel_grid


def test_voxel_grid_gives_each_cubes_centroid():
    points = np.array([[0.01, 0.01, 0.01], [0.03, 0.05, 0.07],  # one 0.1 m cube
                       [0.12, 0.0, 0.0],  # the next along x
                       [-0.05, 0.0, 0.0]])  # the one before
    np.testing.assert_allclose(voxel_grid(points, 0.1), [[-0.05, 0.0, 0.0], [0.02, 0.03, 0.04], [0.12, 0.0, 0.0]])
    assert voxel_grid(np.zeros((0, 3)), 0.1).shape == (0, 3)


def noisy_room(rng, n_floor=3000, height=1.1, noise=0.01):
    """A camera's points (optical frame: y down) of a floor ``height`` below it, 1-6 m ahead, with ``noise`` sd,
    and a person (a 0.25 m radius cylinder 1.7 m tall) standing on it 3 m ahead."""
    floor = np.column_stack([rng.uniform(-2, 2, n_floor), height + rng.normal(0, noise, n_floor),
                             rng.uniform(1, 6, n_floor)])
    angle, up = rng.uniform(0, 2 * np.pi, 1500), rng.uniform(0, 1.7, 1500)
    person = np.column_stack([0.25 * np.cos(angle), height - up, 3 + 0.25 * np.sin(angle)])
    return np.concatenate([floor, person])


def test_the_ground_plane_of_a_noisy_floor():
    rng = np.random.default_rng(0)
    points = noisy_room(rng)
    plane, inliers = ransac_plane(points, 0.03, rng, up=np.array([0.0, -1.0, 0.0]), max_tilt=np.radians(30))
    # the floor y = 1.1 with the normal up (-y): 0 x - y + 0 z + 1.1 = 0
    np.testing.assert_allclose(plane, [0.0, -1.0, 0.0, 1.1], atol=0.005)
    assert inliers[:3000].mean() > 0.99  # the floor's points, 3 sd of noise
    assert inliers[3000:].mean() < 0.03  # the person's lowest 3 cm only
    heights = plane_distance(points[3000:], plane)
    assert heights.max() == pytest.approx(1.7, abs=0.01)  # heights above the floor


def test_a_wall_is_not_taken_for_the_floor():
    rng = np.random.default_rng(1)
    floor = noisy_room(rng, n_floor=500)[:500]
    wall = np.column_stack([rng.uniform(-2, 2, 3000), rng.uniform(-1, 1.1, 3000), np.full(3000, 6.0)])
    plane, _ = ransac_plane(np.concatenate([floor, wall]), 0.03, rng, iterations=200,
                            up=np.array([0.0, -1.0, 0.0]), max_tilt=np.radians(30))
    np.testing.assert_allclose(plane[:3], [0.0, -1.0, 0.0], atol=0.01)  # the larger wall is too steep


def test_euclidean_clusters_join_points_nearer_than_the_tolerance():
    a = np.array([[0.0, 0, 0], [0.05, 0, 0], [0.10, 0, 0], [0.15, 0, 0]])  # a chain 5 cm apart
    b = np.array([[1.0, 0, 0], [1.0, 0.06, 0]])
    lone = np.array([[3.0, 0, 0]])
    points = np.concatenate([b, lone, a])
    clusters = euclidean_clusters(points, 0.06)
    assert [sorted(c.tolist()) for c in clusters] == [[3, 4, 5, 6], [0, 1], [2]]  # largest first
    assert [len(c) for c in euclidean_clusters(points, 0.06, min_size=2, max_size=3)] == [2]
    assert len(euclidean_clusters(points, 0.04)) == 7  # nothing within 4 cm


# --- people candidates (pipeline/detectors/head_clusters.py) --------------------------------------------------------

from pipeline.detectors.head_clusters import ClusterLimits, candidates, heads  # noqa: E402

FLOOR = np.array([0.0, -1.0, 0.0, 1.0])  # the camera 1 m up, optical y down: the floor is y = 1, its normal -y


def person(rng, x, z, n=4000):
    """The camera-facing half of a person standing at (x, z): a torso 0.18 m in radius up to 1.5 m and a head 0.11 m
    in radius at 1.6 m, as the camera's points (y down from the camera, 1 m up), in 6 cm voxels."""
    angle = rng.uniform(np.pi, 2 * np.pi, n)  # the half towards the camera (z smaller)
    up = rng.uniform(0, 1.5, n)
    torso = np.column_stack([x + 0.18 * np.cos(angle), 1.0 - up, z + 0.18 * np.sin(angle)])
    direction = rng.normal(size=(n // 4, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    direction[:, 2] = -np.abs(direction[:, 2])
    head = np.array([x, 1.0 - 1.6, z]) + 0.11 * direction
    return voxel_grid(np.concatenate([torso, head]), 0.06)


def test_two_people_side_by_side_are_split_at_their_heads_and_one_person_is_not():
    rng = np.random.default_rng(0)
    pair = np.concatenate([person(rng, -0.2, 3.0), person(rng, 0.2, 3.0)])  # 0.4 m apart: touching
    split = candidates(pair, FLOOR)
    assert len(split) == 2
    centres = sorted(pair[c, 0].mean() for c in split)
    np.testing.assert_allclose(centres, [-0.2, 0.2], atol=0.05)
    assert len(candidates(pair, FLOOR, split=False)) == 1  # without sub-clustering: one candidate
    alone = person(rng, 0.0, 3.0)
    assert len(candidates(alone, FLOOR)) == 1  # the shoulders are no heads: within 0.3 m of the head


def test_the_heads_of_a_height_map_keep_apart():
    # three columns of points, 0.2 m apart, 1.8, 1.7 and 1.75 m tall: the middle one is no maximum, and the third is
    # within 0.3 m of the first only if the distance is 0.4 m or less
    columns = [(-0.2, 1.8), (0.0, 1.7), (0.2, 1.75)]
    points = np.array([[x, 1.0 - h, 3.0] for x, h in columns])
    heights = points @ FLOOR[:3] + FLOOR[3]
    top = heads(points, heights, FLOOR, ClusterLimits(bin_size=0.1))
    assert top.tolist() == [0, 2]  # 0.4 m apart
    assert heads(points, heights, FLOOR, ClusterLimits(bin_size=0.1, head_distance=0.5)).tolist() == [0]


# --- the ground followed, a person's position (pipeline/detectors/ground.py) ---------------------------------------

from pipeline.detectors.ground import GroundTracker, head_position  # noqa: E402


def test_the_ground_is_found_then_followed_as_the_camera_tilts():
    rng = np.random.default_rng(2)
    tracker = GroundTracker(voxel=0.06)
    room = noisy_room(rng)
    floor = tracker.update(room)
    # within 1 cm: the floor band, two voxels (12 cm) deep, holds the person's feet too
    np.testing.assert_allclose(tracker.plane, [0.0, -1.0, 0.0, 1.1], atol=0.01)
    assert floor[:3000].mean() > 0.99 and floor[3000:].mean() < 0.1
    # the camera pitches down by 2 degrees (a robot's jolt): the floor's points turn about the camera's x axis
    a = np.radians(2.0)
    turn = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    tracker.update(room @ turn.T)
    expected = np.append(turn @ [0.0, -1.0, 0.0], 1.1)
    np.testing.assert_allclose(tracker.plane, expected, atol=0.01)
    kept = tracker.plane.copy()
    tracker.update(np.zeros((10, 3)) + [0, -5, 3])  # too few floor points near the plane: it is kept
    np.testing.assert_array_equal(tracker.plane, kept)


def test_a_persons_position_is_the_head_centroid_pushed_along_the_ray_onto_the_floor():
    rng = np.random.default_rng(3)
    standing = person(rng, 0.5, 3.0)  # head centre (0.5, -0.6, 3.0), the camera-facing half of it seen
    where, height = head_position(standing, FLOOR)
    assert height == pytest.approx(1.71, abs=0.03)  # the top of the head: 1.6 + 0.11
    # the visible half's centroid lies in front of the head's centre; 0.1 m further along the ray brings it near
    # the centre (x 0.5, z 3.0), and on the floor y = 1
    assert where[1] == pytest.approx(1.0)
    np.testing.assert_allclose(where[[0, 2]], [0.5, 3.0], atol=0.06)


# --- the detector's geometry (pipeline/detectors/rgbd.py) -----------------------------------------------------------

from pipeline.detectors.rgbd import RgbdPeopleDetector, person_box  # noqa: E402


def test_the_box_that_holds_a_person_from_head_to_ground_by_hand():
    k = np.array([[100.0, 0, 80], [0, 100.0, 60], [0, 0, 1]])
    # 4 m ahead on the floor 1 m below the camera, 1.7 m tall: feet at v = 60 + 100 / 4 = 85, head at 60 - 17.5 =
    # 42.5; the box is 42.5 px high, half as wide, around u = 80. A second person 0.5 m to the right at 2 m, 1.5 m
    # tall: u = 80 + 100 0.5 / 2 = 105, feet at 60 + 50 = 110, head at 60 - 25 = 35, 75 px high
    box = person_box(k, np.array([[0.0, 1.0, 4.0], [0.5, 1.0, 2.0]]), np.array([0.0, -1.0, 0.0]), np.array([1.7, 1.5]))
    np.testing.assert_allclose(box, [[80 - 42.5 / 4, 42.5, 80 + 42.5 / 4, 85], [105 - 75 / 4, 35, 105 + 75 / 4, 110]],
                               atol=1e-9)


def test_the_detector_finds_people_standing_side_by_side_and_alone():
    rng = np.random.default_rng(4)
    floor = noisy_room(rng, height=1.0, noise=0.005)[:3000]
    cloud = np.concatenate([floor, person(rng, -0.2, 3.0), person(rng, 0.2, 3.0), person(rng, 1.2, 4.5)])
    detector = RgbdPeopleDetector(hog=False)
    where, heights, members = detector.people(cloud)
    assert [len(m) > 30 for m in members] == [True] * 3
    order = np.argsort(where[:, 0])
    np.testing.assert_allclose(where[order][:, [0, 2]], [[-0.2, 3.0], [0.2, 3.0], [1.2, 4.5]], atol=0.08)
    np.testing.assert_allclose(where[:, 1], 1.0, atol=0.02)  # on the floor
    np.testing.assert_allclose(heights, 1.71, atol=0.05)
    assert len(RgbdPeopleDetector(sub_clustering=False, hog=False).people(cloud)[0]) == 2  # the pair stays one
