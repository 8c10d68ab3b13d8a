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


def test_voxel_centroids_come_in_the_order_of_the_cubes_coordinates_summed_in_point_order():
    # 1 m cubes: (0, 1, 0) twice, (0, 0, 5), (-1, 3, 0), (0, 0, 0): ordered by x, then y, then z
    points = np.array([[0.25, 1.5, 0.5], [0.1, 1.0, 0.0], [0.5, 0.5, 5.5], [-0.5, 3.5, 0.0], [0.0, 0.0, 0.0],
                       [0.75, 1.5, 0.5]])
    np.testing.assert_array_equal(voxel_grid(points, 1.0), [[-0.5, 3.5, 0.0], [0.0, 0.0, 0.0], [0.5, 0.5, 5.5],
                                                            [(0.25 + 0.1 + 0.75) / 3, 4 / 3, 1 / 3]])
    # in the order of the points: 1 + 1e-16 + 1e-16 is 1, not 1 + 2e-16 (the large one first)
    tiny = np.array([[1.0, 0, 0], [1e-16, 0, 0], [1e-16, 0, 0]])
    assert voxel_grid(tiny, 10.0)[0, 0] == 1.0 / 3
    assert voxel_grid(tiny[::-1], 10.0)[0, 0] == (2e-16 + 1.0) / 3


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


def test_a_pair_at_exactly_the_tolerance_is_joined_as_its_float_squared_distance_says():
    # as scipy's cKDTree.query_pairs: (dx^2 + dy^2) + dz^2 <= tolerance^2 in float64. 0.1 apart: 0.1^2 <= 0.1^2.
    # (0.3, 0.4, 1.2) is 1.3 away and 1.69 <= 1.6900000000000002; (0.1, 0.2, 0.2) is 0.3 away, but its squares sum
    # to 0.09000000000000002 > 0.09
    assert [c.tolist() for c in euclidean_clusters(np.array([[0.0, 0, 0], [0.1, 0, 0]]), 0.1)] == [[0, 1]]
    assert len(euclidean_clusters(np.array([[0.0, 0, 0], [0.1, 0, 0]]), np.nextafter(0.1, 0))) == 2
    assert len(euclidean_clusters(np.array([[0.0, 0, 0], [0.3, 0.4, 1.2]]), 1.3)) == 1
    assert len(euclidean_clusters(np.array([[5.0, 5, 5], [5.1, 5.2, 5.2]]) - 5, 0.3)) == 2


def test_euclidean_clusters_of_equal_size_come_in_the_order_of_their_lowest_point():
    # a chain 0.9 apart across several 0.52 m cubes, 0.9 m steps two cubes apart, and pairs and a triple 1.5 apart
    chain = np.column_stack([np.arange(6) * 0.9, np.zeros(6), np.zeros(6)])
    points = np.concatenate([[[20.0, 0, 0], [20.0, 0.0, 0.9]], chain + [0, 5, 0], [[-7.0, 0, 0], [-7.0, 0.6, 0.6]],
                             [[3.0, -8.0, 2.0]], [[9.0, 9.0, 9.0], [9.5, 9.5, 9.5]]])
    clusters = euclidean_clusters(points, 1.0)  # (0.6, 0.6) is 0.85 away; (0.5, 0.5, 0.5) 0.87
    assert [c.tolist() for c in clusters] == [[2, 3, 4, 5, 6, 7], [0, 1], [8, 9], [11, 12], [10]]
    assert [c.tolist() for c in euclidean_clusters(points, 0.8)] == [[0], [1], *[[k] for k in range(2, 13)]]
    assert euclidean_clusters(np.zeros((0, 3)), 1.0) == []
    assert [c.tolist() for c in euclidean_clusters(np.zeros((3, 3)), 1e-9)] == [[0, 1, 2]]  # one point thrice
    with pytest.raises(ValueError, match="finite"):
        euclidean_clusters(np.array([[0.0, 0, 0], [np.nan, 0, 0]]), 1.0)
    with pytest.raises(ValueError, match="too many cubes"):  # 1e6 m / 0.0577 m along each axis: 5e21 cubes
        euclidean_clusters(np.array([[0.0, 0, 0], [1e6, 1e6, 1e6]]), 0.1)


# --- people candidates (pipeline/detectors/head_clusters.py) --------------------------------------------------------

from pipeline.detectors.head_clusters import ClusterLimits, candidates, heads, merge_close, subclusters  # noqa: E402

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


def test_equal_heights_make_one_head_the_first_point_and_the_left_bin():
    # bins of 0.1 m: points 0 and 1 share the bin at x 0.05 and are equally high (the first is the bin's), the bin
    # at x 0.15 is as high (a plateau: its left end is the maximum), x 0.55 is lower but a maximum of its own; the
    # plateau and the lone head are equally high, the plateau's bin comes first
    points = np.array([[0.05, -0.8, 3.0], [0.06, -0.8, 3.1], [0.15, -0.8, 3.0], [0.35, 0.0, 3.0], [0.55, -0.7, 3.0],
                       [0.95, -0.8, 3.0]])
    heights = points @ FLOOR[:3] + FLOOR[3]
    assert heads(points, heights, FLOOR, ClusterLimits(bin_size=0.1)).tolist() == [0, 5, 4]
    # 0.3 m apart is far enough: 0.9 apart (0 and 5) and 0.5 (0 and 4) are kept; at 0.5 m, 4 is not
    assert heads(points, heights, FLOOR, ClusterLimits(bin_size=0.1, head_distance=0.5)).tolist() == [0, 5]


def test_points_go_to_the_nearest_head_on_the_ground_the_first_of_equals():
    # bins of 0.125 m (binary fractions: the distances are exact): heads at x -0.25 (1.75 m) and 0.25 (1.625 m), the
    # bins between lower. The point at x 0 is 0.25 from both (the first, higher head takes it); x -0.125 and 0.125 go
    # to the head 0.125 away; the one 0.5 m behind the second head is beyond head_distance 0.3: left out
    rows = [(-0.25, 1.75, 3.0), (0.25, 1.625, 3.0), (0.0, 0.5, 3.0), (0.125, 1.0, 3.0), (0.25, 1.0, 3.5),
            (-0.125, 1.0, 3.0)]
    points = np.array([[x, 1.0 - h, z] for x, h, z in rows])
    heights = points @ FLOOR[:3] + FLOOR[3]
    index = np.arange(10, 16)
    limits = ClusterLimits(bin_size=0.125, min_subcluster=0)
    assert heads(points, heights, FLOOR, limits).tolist() == [0, 1]
    assert [p.tolist() for p in subclusters(points, heights, FLOOR, limits, index)] == [[10, 12, 15], [11, 13]]
    limits = ClusterLimits(bin_size=0.125, min_subcluster=2)
    assert [p.tolist() for p in subclusters(points, heights, FLOOR, limits, index)] == [[10, 12, 15]]  # 2: dropped


def test_clusters_whose_centres_are_near_on_the_ground_merge_transitively():
    # centres on the floor at x 0, 0.35, 0.7 (each within 0.4 of the next, not of the one after) and 2.0; heights
    # do not count: the second cluster's points are 1 m up
    points = np.array([[0.0, 1.0, 3.0], [0.1, 1.0, 3.0], [0.3, 0.0, 3.0], [0.4, 0.0, 3.0], [0.7, 1.0, 3.0],
                       [2.0, 1.0, 3.0], [-0.1, 1.0, 3.0]])
    clusters = [np.array([5]), np.array([0, 1, 6]), np.array([2, 3]), np.array([4])]
    merged = merge_close(points, FLOOR, clusters, 0.4)
    assert [m.tolist() for m in merged] == [[5], [0, 1, 6, 2, 3, 4]]  # each set in the order of its least cluster
    assert [m.tolist() for m in merge_close(points, FLOOR, clusters, 0.3)] == [[5], [0, 1, 6], [2, 3], [4]]


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


def test_a_persons_position_by_hand():
    # the floor y = 1; a head 1.7 m high at (0, -0.7, 2.9) and (0, -0.7, 3.1), a shoulder at 1.45 m (below 7/8 of 1.7
    # = 1.4875) and a knee: the head's centroid (0, -0.7, 3) 0.1 m further along its ray, on the floor
    points = np.array([[0.0, -0.7, 2.9], [0.2, -0.45, 3.0], [0.0, -0.7, 3.1], [0.0, 0.5, 3.0]])
    where, height = head_position(points, FLOOR)
    assert height == pytest.approx(1.7, abs=1e-12)
    np.testing.assert_allclose(where, [0.0, 1.0, 3.0 * (1 + 0.1 / np.sqrt(0.49 + 9.0))], atol=1e-12)


# --- the detector's geometry (pipeline/detectors/rgbd.py) -----------------------------------------------------------

from pipeline.detectors.rgbd import RgbdPeopleDetector, _pixels_around, person_box  # noqa: E402


def test_the_box_that_holds_a_person_from_head_to_ground_by_hand():
    k = np.array([[100.0, 0, 80], [0, 100.0, 60], [0, 0, 1]])
    # 4 m ahead on the floor 1 m below the camera, 1.7 m tall: feet at v = 60 + 100 / 4 = 85, head at 60 - 17.5 =
    # 42.5; the box is 42.5 px high, half as wide, around u = 80. A second person 0.5 m to the right at 2 m, 1.5 m
    # tall: u = 80 + 100 0.5 / 2 = 105, feet at 60 + 50 = 110, head at 60 - 25 = 35, 75 px high
    box = person_box(k, np.array([[0.0, 1.0, 4.0], [0.5, 1.0, 2.0]]), np.array([0.0, -1.0, 0.0]), np.array([1.7, 1.5]))
    np.testing.assert_allclose(box, [[80 - 42.5 / 4, 42.5, 80 + 42.5 / 4, 85], [105 - 75 / 4, 35, 105 + 75 / 4, 110]],
                               atol=1e-9)


def test_a_candidates_colours_are_the_3_by_3_pixels_round_each_point_clipped_to_the_image():
    rgb = np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3)  # 4 rows, 5 columns
    # a point at pixel (u 2.5 -> 2, v 1.9 -> 1) and one at the top left corner (u 0.4, v -0.3: both 0)
    colours = _pixels_around(np.array([[5.0, 3.8, 2.0], [0.8, -0.6, 2.0]]), rgb)
    rows = [0, 1, 2] * 3 + [0, 0, 1] * 3
    columns = [1, 1, 1, 2, 2, 2, 3, 3, 3] + [0, 0, 0, 0, 0, 0, 1, 1, 1]  # column by column, each top down
    np.testing.assert_array_equal(colours, rgb[rows, columns])


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
