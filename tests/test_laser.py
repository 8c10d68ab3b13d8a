"""MuJoCo-cast 2D lasers against hand-worked ray-plane and ray-circle intersections.

Geometry used throughout: a wall segment from (5, -30) to (5, 30) is a box of thickness WALL_THICKNESS = 0.1 centred
on the segment, so the face the robot sees is the plane x = 5 - 0.05 = 4.95 (and x = -4.95 for the wall at x = -5).
A person is a vertical cylinder of radius PERSON_HIP_RADIUS = 0.18; the beams are horizontal at 0.70 m, below the
wall top (2.5 m), within the person's torso (0.62-1.45 m) and below the robot's base top (0.95 m), so they meet
each solid in its 2D section.
"""

import mujoco
import numpy as np
import pytest

from scenarios.format import LASER
from scenarios.schema import ScenarioError, validate
from sensors.laser import Laser
from sensors.scene import PERSON_HIP_RADIUS, WALL_THICKNESS, Scene

FRONT_WALL = [[5.0, -30.0], [5.0, 30.0]]
REAR_WALL = [[-5.0, -30.0], [-5.0, 30.0]]
FACE = 5.0 - WALL_THICKNESS / 2  # 4.95
WALL_HALF_LENGTH = 30.0 + WALL_THICKNESS / 2  # the box is padded by half a thickness at each end


def laser_params(**over) -> dict:
    """A laser dict as the scenario loader gives it: the LASER schema's defaults plus ``over``."""
    raw = {"name": "front_laser", "mount": [0.25, 0.0, 0.0]}
    raw.update(over)
    return validate(raw, LASER, "<test>")


def analytic_ranges(pose, angles, faces=(), circles=(), range_max=20.0):
    """Exact first-hit distances of horizontal beams from the laser pose (x, y, yaw), NaN beyond range_max.

    ``faces`` are planes x = x_f (wall faces, valid for |y| <= WALL_HALF_LENGTH); ``circles`` are (cx, cy) of
    radius PERSON_HIP_RADIUS. Returns (ranges, index of the circle hit or -1).
    """
    a = pose[2] + np.asarray(angles)
    u = np.stack([np.cos(a), np.sin(a)], 1)
    o = np.asarray(pose[:2], float)
    best = np.full(a.size, np.inf)
    which = np.full(a.size, -1)
    for xf in faces:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (xf - o[0]) / u[:, 0]  # ray-plane: o_x + t u_x = x_f
        y = o[1] + t * u[:, 1]
        t = np.where((t > 0) & (np.abs(y) <= WALL_HALF_LENGTH), t, np.inf)
        closer = t < best
        best[closer], which[closer] = t[closer], -1
    for k, c in enumerate(circles):
        oc = np.asarray(c, float) - o
        b = u @ oc  # ray-circle: |o + t u - c|^2 = r^2  ->  t = b - sqrt(b^2 - |oc|^2 + r^2)
        disc = b * b - (oc @ oc - PERSON_HIP_RADIUS**2)
        t = np.where(disc >= 0, b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        t = np.where(t > 0, t, np.inf)
        closer = t < best
        best[closer], which[closer] = t[closer], k
    ranges = np.where(best <= range_max, best, np.nan)
    return ranges, np.where(np.isfinite(ranges), which, -1)


def make(walls, persons=(), ids=None, robot_pose=(0.0, 0.0, 0.0), robot_radius=0.425, capacity=4, seed=0, **over):
    scene = Scene(np.array(walls, float).reshape(-1, 2, 2), robot_radius, capacity)
    ids = np.arange(len(persons)) + 100 if ids is None else np.asarray(ids)
    scene.sync(np.array(robot_pose, float), ids, np.array(persons, float).reshape(-1, 2))
    laser = Laser(scene=scene, rng=np.random.default_rng(seed), **laser_params(**over))
    return scene, laser


def test_beam_layout_of_the_default_laser():
    # 190 deg / 0.5 deg = 380 intervals -> 381 beams from -95 deg to +95 deg in 0.5 deg steps.
    _, laser = make([FRONT_WALL])
    scan = laser.scan(1.5, np.zeros(3))
    assert scan.ranges.shape == (381,) and scan.person_id.shape == (381,)
    assert scan.angle_min == pytest.approx(np.radians(-95.0))
    assert scan.angle_increment == pytest.approx(np.radians(0.5))
    assert scan.angles[-1] == pytest.approx(np.radians(95.0))
    assert scan.angles[190] == pytest.approx(0.0, abs=1e-12)
    assert scan.stamp == 1.5 and scan.frame == "front_laser" and scan.range_max == 20.0


def test_noisy_ranges_match_wall_and_person_within_noise():
    # Robot at the origin, laser at (0.25, 0) facing +x, person (id 7) at (3, 1).
    # Wall beams: t = (4.95 - 0.25) / cos(a), a hit while t <= 20 m, i.e. |a| <= acos(4.7 / 20) = 76.4 deg.
    # Person beams: t = b - sqrt(b^2 - |c - o|^2 + r^2), b = u . (c - o), for |a - atan2(1, 2.75)| <= asin(r/|c-o|).
    # The default noise is the LMS500's: an offset within +-25 mm (+-35 mm beyond 10 m) and 7 mm (9 mm) sigma.
    _, laser = make([FRONT_WALL], persons=[(3.0, 1.0)], ids=[7], seed=2)
    scan = laser.scan(0.0, np.zeros(3))
    pose = laser.pose_in(np.zeros(3))
    np.testing.assert_allclose(pose, [0.25, 0.0, 0.0])
    expect, which = analytic_ranges(pose, laser.angles, faces=[FACE], circles=[(3.0, 1.0)])

    # the same beams return, and every return is within the offset bound plus 4 sigma of the exact range
    np.testing.assert_array_equal(np.isfinite(scan.ranges), np.isfinite(expect))
    hit = np.isfinite(expect)
    bound = np.where(expect[hit] <= 10.0, 0.025 + 4 * 0.007, 0.035 + 4 * 0.009)
    assert np.all(np.abs(scan.ranges[hit] - expect[hit]) <= bound)

    # person: centre at atan2(1, 2.75) = 19.98 deg, half-width asin(0.18 / 2.926) = 3.53 deg -> beams at
    # 16.5 .. 23.5 deg, 15 of them; wall: |a| <= 76.4 deg -> beams -76 .. 76 deg, 305 in all returning
    on_person = which == 0
    assert on_person.sum() == 15
    np.testing.assert_allclose(np.degrees(laser.angles[on_person][[0, -1]]), [16.5, 23.5])
    assert hit.sum() == 305
    np.testing.assert_array_equal(scan.person_id, np.where(on_person, 7, -1))


def room_lasers(preset: str, half: float, seed: int = 5, **over):
    """A noisy laser of ``preset`` turned 360 degrees in 10,000 beams at the centre of a square room of walls at
    +-``half`` m, and its noise-free twin (whose ranges the tests above prove exact)."""
    walls = [[[-half, -half], [half, -half]], [[half, -half], [half, half]], [[half, half], [-half, half]],
             [[-half, half], [-half, -half]]]
    params = dict(preset=preset, mount=[0.0, 0.0, 0.0], fov_deg=360.0, resolution_deg=0.036, **over)
    scene, noisy = make(walls, seed=seed, **params)
    exact = Laser(scene=scene, rng=np.random.default_rng(0), **laser_params(**dict(params, noise=[])))
    return noisy, exact.scan(0.0, np.zeros(3)).ranges


def test_range_error_over_10000_beams_matches_the_lms500_datasheet():
    # walls 4.95 m from the centre: every range is within 7.0 m, in the 1-10 m band: the laser's offset (within
    # +-25 mm, the same on every beam) plus 7 mm Gaussian noise: over the beams, the mean is the offset and the
    # sd 7 mm, so a flat wall stays flat
    noisy, exact = room_lasers("sick_lms500", 5.0)
    assert noisy.n_beams == 10_000 and np.isfinite(exact).all() and exact.max() < 7.1
    err = noisy.scan(0.0, np.zeros(3)).ranges - exact
    offset = noisy._bias_share * 0.025
    assert abs(offset) <= 0.025 and abs(offset) > 1e-4
    assert err.mean() == pytest.approx(offset, abs=4 * 0.007 / np.sqrt(err.size))
    assert err.std() == pytest.approx(0.007, rel=0.05)
    # over 100 scans every beam keeps the offset and scatters by 7 mm about it
    errs = np.stack([noisy.scan(0.0, np.zeros(3)).ranges - exact for _ in range(100)])
    np.testing.assert_allclose(errs.mean(axis=0), offset, atol=5 * 0.007 / np.sqrt(100))
    assert (errs - offset).std() == pytest.approx(0.007, rel=0.05)
    # another laser of the same model has an offset of its own
    other, _ = room_lasers("sick_lms500", 5.0, seed=9)
    assert other._bias_share != noisy._bias_share


def test_range_error_follows_the_band_of_the_range():
    # Hokuyo UTM-30LX: +-30 mm and 10 mm sigma up to 10 m, +-50 mm and 30 mm beyond: with walls 14.95 m away every
    # range lies in 14.95-21.1 m, the far band: the offset is the laser's share of 50 mm, the sd 30 mm
    noisy, exact = room_lasers("hokuyo_utm30lx", 15.0)
    assert exact.min() > 10.0
    err = noisy.scan(0.0, np.zeros(3)).ranges - exact
    assert err.mean() == pytest.approx(noisy._bias_share * 0.050, abs=4 * 0.030 / np.sqrt(err.size))
    assert err.std() == pytest.approx(0.030, rel=0.05)


def test_presets_fill_the_keys_a_scenario_leaves_out():
    utm = laser_params(preset="hokuyo_utm30lx", rate=20.0)
    assert (utm["fov_deg"], utm["resolution_deg"], utm["range_min"], utm["range_max"]) == (270.0, 0.25, 0.1, 30.0)
    assert utm["rate"] == 20.0  # given keys win over the preset
    assert utm["height"] == 0.70  # the preset leaves the mount height to the scenario
    s300 = laser_params(preset="sick_s300")
    assert (s300["height"], s300["fov_deg"], s300["resolution_deg"]) == (0.37, 224.5, 0.5)
    # 270 deg / 0.25 deg -> 1081 beams; 224.5 / 0.5 -> 450, DROW's beam grid
    assert make([FRONT_WALL], preset="hokuyo_utm30lx")[1].n_beams == 1081
    assert make([FRONT_WALL], preset="sick_s300")[1].n_beams == 450
    with pytest.raises(ScenarioError, match=r"preset: expected one of sick_lms500, hokuyo_utm30lx, sick_s300"):
        laser_params(preset="velodyne")


def test_no_returns_read_range_max_when_configured_and_too_near_returns_are_none():
    # the wall face 4.70 m ahead: a beam at angle a meets it at 4.70 / cos(a), within 6 m for |a| <= 38.4 deg
    # (153 beams); the rest read range_max 6.0
    _, laser = make([FRONT_WALL], noise=[], no_return="range_max", range_max=6.0)
    scan = laser.scan(0.0, np.zeros(3))
    assert (scan.ranges < 6.0).sum() == 153 and (scan.ranges == 6.0).sum() == 381 - 153
    # range_min 4.8 m: the beams nearer than that, |a| < acos(4.7 / 4.8) = 11.8 deg (47 beams), return nothing too
    _, laser = make([FRONT_WALL], noise=[], no_return="range_max", range_min=4.8, range_max=6.0)
    scan = laser.scan(0.0, np.zeros(3))
    assert (scan.ranges < 6.0).sum() == 153 - 47
    assert np.all(scan.ranges[np.abs(np.degrees(scan.angles)) < 11.8] == 6.0)
    assert scan.ranges[scan.ranges < 6.0].min() >= 4.8


def test_noise_free_ranges_are_exact_for_a_turned_robot():
    # Robot at (1, 0.5) turned by 0.3 rad: the laser sits at (1 + 0.25 cos 0.3, 0.5 + 0.25 sin 0.3) facing 0.3 rad.
    robot = np.array([1.0, 0.5, 0.3])
    _, laser = make([FRONT_WALL], persons=[(3.0, 1.0), (2.5, 2.5)], ids=[3, 4], robot_pose=robot, noise=[])
    scan = laser.scan(0.0, robot)
    pose = np.array([1.0 + 0.25 * np.cos(0.3), 0.5 + 0.25 * np.sin(0.3), 0.3])
    expect, which = analytic_ranges(pose, laser.angles, faces=[FACE], circles=[(3.0, 1.0), (2.5, 2.5)])
    np.testing.assert_array_equal(np.isfinite(scan.ranges), np.isfinite(expect))
    np.testing.assert_allclose(scan.ranges, expect, atol=1e-6, equal_nan=True)
    np.testing.assert_array_equal(scan.person_id, np.select([which == 0, which == 1], [3, 4], -1))
    assert (which == 0).any() and (which == 1).any()


def test_rear_laser_sees_behind_the_robot_and_never_its_own_body():
    # Robot radius 1 m: both laser origins (+-0.25 m) are inside the robot's cylinder. Without excluding the robot,
    # a beam from (-0.25, 0) pointing backwards would leave the cylinder at 1 - 0.25 = 0.75 m (checked below).
    # Rear laser at (-0.25, 0) facing pi: the beam at 0 deg meets the face x = -4.95 at 4.95 - 0.25 = 4.70 m;
    # the person at (-3, -1) lies at 2.75 m behind and 1 m to the laser's left (its +y is the world -y).
    robot = np.zeros(3)
    scene, laser = make([FRONT_WALL, REAR_WALL], persons=[(-3.0, -1.0)], ids=[5], robot_radius=1.0,
                        name="rear_laser", mount=[-0.25, 0.0, float(np.pi)], noise=[])
    geom = np.zeros(1, np.int32)
    unexcluded = mujoco.mj_ray(scene.model, scene.data, np.array([-0.25, 0.0, 0.70]), np.array([-1.0, 0.0, 0.0]),
                               None, 1, -1, geom)
    assert unexcluded == pytest.approx(0.75)  # the robot body is really in the way of a naive cast

    scan = laser.scan(0.0, robot)
    pose = laser.pose_in(robot)
    np.testing.assert_allclose(pose[:2], [-0.25, 0.0], atol=1e-12)
    assert abs(abs(pose[2]) - np.pi) < 1e-12
    assert scan.ranges[190] == pytest.approx(4.70, abs=1e-6)
    expect, which = analytic_ranges(pose, laser.angles, faces=[-FACE], circles=[(-3.0, -1.0)])
    np.testing.assert_allclose(scan.ranges, expect, atol=1e-6, equal_nan=True)
    assert np.nanmin(scan.ranges) > 2.0  # nothing at the robot's 0.75 m
    # in the rear laser's frame the person is at (2.75, 1): to its left, beams 16.5 .. 23.5 deg (as for the front
    # laser in the test above, mirrored through the robot)
    person_angles = np.degrees(scan.angles[scan.person_id == 5])
    np.testing.assert_allclose(person_angles, np.arange(16.5, 23.6, 0.5), atol=1e-9)
    np.testing.assert_array_equal(scan.person_id, np.where(which == 0, 5, -1))


def test_beams_without_return_are_nan():
    # Only the wall at x = +5; the laser on a robot turned by pi faces -x: its beams point at pi +- 95 deg, the
    # most forward ones at 85 deg from +x, reaching x = 4.95 only after (4.95 + 0.25) / cos(85 deg) = 59.7 m > 20 m.
    robot = np.array([0.0, 0.0, np.pi])
    _, laser = make([FRONT_WALL], robot_pose=robot)
    scan = laser.scan(0.0, robot)
    assert np.all(np.isnan(scan.ranges))
    assert np.all(scan.person_id == -1)


def test_returns_beyond_range_max_are_nan():
    # range_max 5 m, wall face at 4.70 m ahead: the beam at angle a returns while 4.70 / cos(a) <= 5,
    # |a| <= acos(0.94) = 19.95 deg -> beams -19.5 .. 19.5 deg, 79 of them; the others are NaN.
    _, laser = make([FRONT_WALL], range_max=5.0, noise=[])
    scan = laser.scan(0.0, np.zeros(3))
    finite = np.isfinite(scan.ranges)
    assert finite.sum() == 79
    np.testing.assert_allclose(np.degrees(scan.angles[finite][[0, -1]]), [-19.5, 19.5])
    assert np.nanmax(scan.ranges) <= 5.0


def test_parked_slots_are_never_hit_and_ids_follow_resync():
    # Capacity 4. First three persons (ids 10, 11, 12) stand in front of the laser; then only id 99 is alive, placed
    # where id 11 was. Slots 1..3 must be parked (no return from (3, 1) or (2, -0.5)), and the beams towards (3, -1)
    # must now report id 99 (slot 0 reassigned), not 11.
    walls = [FRONT_WALL]
    scene, laser = make(walls, persons=[(3.0, 1.0), (3.0, -1.0), (2.0, -0.5)], ids=[10, 11, 12], noise=[])
    pose = laser.pose_in(np.zeros(3))
    first = laser.scan(0.0, np.zeros(3))
    exp, which = analytic_ranges(pose, laser.angles, faces=[FACE], circles=[(3.0, 1.0), (3.0, -1.0), (2.0, -0.5)])
    np.testing.assert_allclose(first.ranges, exp, atol=1e-6, equal_nan=True)
    np.testing.assert_array_equal(first.person_id, np.select([which == 0, which == 1, which == 2], [10, 11, 12], -1))

    scene.sync(np.zeros(3), np.array([99]), np.array([[3.0, -1.0]]))
    second = laser.scan(0.04, np.zeros(3))
    exp, which = analytic_ranges(pose, laser.angles, faces=[FACE], circles=[(3.0, -1.0)])
    np.testing.assert_allclose(second.ranges, exp, atol=1e-6, equal_nan=True)
    np.testing.assert_array_equal(second.person_id, np.where(which == 0, 99, -1))
    assert set(np.unique(second.person_id)) == {-1, 99}


def test_never_synced_slots_are_parked():
    # Capacity 6 with one person synced: five slots were never placed; the scan equals wall + one person exactly.
    _, laser = make([FRONT_WALL], persons=[(3.0, 1.0)], ids=[1], capacity=6, noise=[])
    pose = laser.pose_in(np.zeros(3))
    scan = laser.scan(0.0, np.zeros(3))
    exp, which = analytic_ranges(pose, laser.angles, faces=[FACE], circles=[(3.0, 1.0)])
    np.testing.assert_allclose(scan.ranges, exp, atol=1e-6, equal_nan=True)
    np.testing.assert_array_equal(scan.person_id, np.where(which == 0, 1, -1))


def test_sync_grows_past_capacity_when_more_persons_are_alive():
    # the capacity (crowd.max_agents) bounds the doubling, not the persons: the follow driver's target joins even a
    # crowd its sources filled (scenarios/costs.py refuses more persons at the start than max_agents)
    scene = Scene(np.array([FRONT_WALL], float), 0.425, 2)
    scene.sync(np.zeros(3), np.arange(3), np.array([[1.0, 1.0], [2.0, 1.0], [3.0, 1.0]]))
    assert (scene.capacity, scene.alive) == (3, 3)


def _ray_by_ray(scene, origin, vec, groups, exclude):
    """MuJoCo's ``mj_ray`` in the scene's own model, one ray at a time: it tests every geom, with no bounding
    volumes (its ``mj_multiRay`` culls by each body's bounding sphere as compiled, which a person scaled by ``sync``
    can poke out of)."""
    geom, dist, one = np.zeros(len(vec), np.int32), np.zeros(len(vec)), np.zeros(1, np.int32)
    for k, v in enumerate(vec):
        d = mujoco.mj_ray(scene.model, scene.data, origin, v, groups, 1, exclude, one)
        geom[k], dist[k] = one[0], d
    return geom, dist


def test_the_cast_model_gives_mujocos_own_hits_and_follows_each_sync():
    # Scene.cast casts in a copy with all persons' geoms in one body: the same geom ids, poses and sizes, so the same
    # hits to the bit as MuJoCo's exhaustive mj_ray. Persons of every size, some beyond the walls, parked slots, a
    # model grown past its capacity, and rays in 3D (a camera's) as well as a laser's flat fans.
    rng = np.random.default_rng(4)
    scene = Scene(np.array([FRONT_WALL, REAR_WALL], float), 0.425, 40, initial_capacity=4)
    a = np.linspace(-np.pi, np.pi, 721)
    flat = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], 1)
    tilted = np.stack([np.cos(a), np.sin(a), rng.uniform(-0.6, 0.6, a.size)], 1)
    hits = 0
    for n in (3, 9, 30, 0, 12):  # 9 and 30 grow the model; 0 parks everyone
        scene.sync(np.array([0.3, -0.2, 0.4]), np.arange(n) + 7, rng.uniform(-8.0, 8.0, (n, 2)),
                   rng.normal(0, 1, (n, 2)), rng.uniform(0, 9, n), rng.uniform(0.65, 1.05, n))
        for vec, z in ((flat, 0.70), (tilted, 1.2), (flat, 0.30)):
            origin, groups = np.array([0.5, -0.1, z]), np.ones(6, np.uint8)
            expected = _ray_by_ray(scene, origin, vec, groups, scene.robot_body)
            geom, dist = np.zeros(len(vec), np.int32), np.zeros(len(vec))
            scene.cast(origin, vec, groups, scene.robot_body, 1e4, geom, dist)  # a cutoff beyond everything
            np.testing.assert_array_equal(geom, expected[0])
            np.testing.assert_array_equal(dist, expected[1])
            hits += (scene.person_of_geom(geom) >= 0).sum()
    assert hits > 300  # 451: persons were hit, not only walls


def test_a_cast_after_a_sync_sees_the_persons_new_places():
    # hand-worked: an adult on the beam along +x at 3 m, then at 6 m: the torso's face at 3 - 0.18, then 6 - 0.18
    scene = Scene(np.zeros((0, 2, 2)), 0.425, 2)
    vec = np.array([[1.0, 0.0, 0.0]])
    geom, dist = np.zeros(1, np.int32), np.zeros(1)
    for x in (3.0, 6.0):
        scene.sync(np.array([-5.0, 0.0, 0.0]), np.array([1]), np.array([[x, 0.0]]))
        scene.cast(np.zeros(3) + [0.0, 0.0, 0.7], vec, np.ones(6, np.uint8), scene.robot_body, 20.0, geom, dist)
        assert dist[0] == pytest.approx(x - PERSON_HIP_RADIUS, abs=1e-12)
        assert scene.person_of_geom(geom)[0] == 1


def test_reading_kernel_bands_clips_and_maps_persons_as_worked_by_hand():
    from sensors.laser import _reading

    # one band edge at 10 m: up to 10 m statistical 0.01 and offset 0.005, beyond 0.02 and 0.01; range 0.1-20 m
    dist = np.array([-1.0, 5.0, 10.0, 15.0, 19.99, 25.0, 0.05])
    geom = np.array([-1, 3, 0, 4, 3, 3, 3], np.int32)
    noise = np.array([1.0, 1.0, -1.0, 2.0, 10.0, 0.0, 0.0])
    geom_slot = np.array([-1, -1, -1, 0, 1, -1])  # geoms 3 and 4 are slots 0 and 1; the last entry is geom -1's
    ranges, person = np.empty(7), np.empty(7, np.int64)
    _reading(dist, geom, noise, np.array([10.0]), np.array([0.01, 0.02]), np.array([0.005, 0.01]), 0.1, 20.0, np.nan,
             geom_slot, np.array([41, 42]), ranges, person)
    expected = [np.nan, 5.0 + (0.01 + 0.005), 10.0 + (-0.01 + 0.005), 15.0 + (0.04 + 0.01), 20.0, np.nan, np.nan]
    np.testing.assert_array_equal(ranges, expected)  # 10 m is the first band's (edges are upper bounds, inclusive)
    np.testing.assert_array_equal(person, [-1, 41, -1, 42, 41, -1, -1])


def test_shown_counts_each_persons_beams_and_tests_range_and_field_of_view():
    # a laser at (1, 2) heading +y (yaw pi/2), 5 m, a 90 degree field of view (45 each side). Persons 3, 7, 9, 12 at
    # (1, 4) ahead at 2 m: in view; (3, 2) to its right (bearing -90 degrees): out; (1, 8) ahead at 6 m: out of range;
    # (1.5, 3) ahead-right (bearing atan2(1, 0.5) - 90 = -26.6 degrees): in. Beams hit persons 7, 7, 12 and 3.
    from sensors.laser import _shown

    ids = np.array([3, 7, 9, 12])
    position = np.array([[1.0, 4.0], [3.0, 2.0], [1.0, 8.0], [1.5, 3.0]])
    beams, in_view = np.zeros(4), np.empty(4, bool)
    _shown(ids, position, np.array([-1, 7, 7, 12, -1, 3]), 1.0, 2.0, np.pi / 2, 5.0, np.radians(45.0), beams, in_view)
    assert beams.tolist() == [1.0, 2.0, 0.0, 1.0]
    assert in_view.tolist() == [True, False, False, True]
    # behind the laser is out of a 90 degree view, and in a 360 degree one
    _shown(ids[:1], np.array([[1.0, 0.0]]), np.array([-1]), 1.0, 2.0, np.pi / 2, 5.0, np.radians(45.0), beams[:1],
           in_view[:1])
    assert not in_view[0]
    _shown(ids[:1], np.array([[1.0, 0.0]]), np.array([-1]), 1.0, 2.0, np.pi / 2, 5.0, np.radians(180.0), beams[:1],
           in_view[:1])
    assert in_view[0]


def test_the_cast_models_tiles_gather_neighbours():
    # 20 persons on a line x = 0..19 (given in reverse), tiles of 8: ceil(20 / 8) = 3 tiles' worth, round(sqrt(3)) = 2
    # bands of 10 by x; each band by y (all 0: x order kept) into bodies of 8: band x = 0..9 fills body 0 (slots 0-7)
    # and body 1 (slots 8, 9); band x = 10..19 starts at body 2 (slots 16-23) and ends in body 3 (24, 25)
    from sensors.scene import TILE, _tile_count, _tiles

    assert TILE == 8
    xy = np.column_stack([np.arange(19.0, -1.0, -1.0), np.zeros(20)])
    slot, bodies = _tiles(xy, 8)
    x_of_slot = dict(zip(slot.tolist(), xy[:, 0].tolist()))
    assert bodies == 4 and sorted(x_of_slot) == [*range(10), *range(16, 26)]
    assert [x_of_slot[s] for s in [*range(10), *range(16, 26)]] == list(range(20))
    assert _tile_count(20) >= bodies
    # a band sorted by y: two columns of 8 at x = 0 and 0.1, y descending in the input; one band (round(sqrt(2)) = 1)
    xy = np.column_stack([np.repeat([0.0, 0.1], 8), np.tile(np.arange(7.0, -1.0, -1.0), 2)])
    slot, bodies = _tiles(xy, 8)
    assert bodies == 2 and sorted(slot.tolist()) == list(range(16))
    assert xy[np.argsort(slot), 1].tolist() == [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7]
    assert _tiles(np.zeros((0, 2)), 8)[1] == 0
