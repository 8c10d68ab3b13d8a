"""The person body: legs that swing with the distance walked, seen by a laser at 38 cm (seed 001) as two legs that
part and cross, and as one segment when the person stands; clothing colours that stay with the person."""

import mujoco
import numpy as np
import pytest

from scenarios.format import LASER
from scenarios.schema import validate
from sensors import body
from sensors.laser import Laser
from sensors.scene import Scene, parts_at

FAR_WALL = [[[10.0, -30.0], [10.0, 30.0]]]


def leg_laser(scene):
    # seed 001's leg laser: 180 degrees at 0.5 degrees, 38 cm above the floor; exact ranges
    params = validate({"name": "leg_laser", "mount": [0.0, 0.0, 0.0], "height": 0.38, "fov_deg": 180.0,
                       "resolution_deg": 0.5, "noise": []}, LASER, "<test>")
    return Laser(scene=scene, rng=np.random.default_rng(0), **params)


def runs_on(scan, person_id):
    """Maximal runs of consecutive beams that hit the person: the segments a jump-distance segmenter cuts out when
    the background is far behind."""
    on = np.concatenate([[0], (scan.person_id == person_id).astype(int), [0]])
    return int((np.diff(on) == 1).sum())


def test_feet_swing_forward_by_the_leg_length_times_the_sine_of_the_swing():
    # a person at (2, 1) walking along +y (heading 90 deg) with the left leg swung by 20 deg: the left foot lies
    # L sin(20 deg) ahead of its hip (+y), the right one as far behind; the hips are HIP_HALF_WIDTH to each side
    scene = Scene(np.array(FAR_WALL), 0.425, 1)
    swing = np.radians(20.0)
    walked = np.arcsin(swing / body.SWING_AMPLITUDE) * body.STRIDE / (2 * np.pi)  # sin(phase) = swing / amplitude
    scene.sync(np.array([-5.0, 0.0, 0.0]), np.array([1]), np.array([[2.0, 1.0]]), np.array([[0.0, 1.5]]),
               np.array([walked]))
    d, m = scene.data, scene.model
    left, right = (m.body(f"person0_{side}_leg").id for side in ("left", "right"))
    # the capsule's axis runs from the hip (the body origin) along the body's -z for LEG_LENGTH
    foot = {b: d.xpos[b] - d.xmat[b].reshape(3, 3)[:, 2] * body.LEG_LENGTH for b in (left, right)}
    reach = body.LEG_LENGTH * np.sin(swing)
    np.testing.assert_allclose(d.xpos[left], [2.0 - body.HIP_HALF_WIDTH, 1.0, body.HIP_HEIGHT], atol=1e-9)
    np.testing.assert_allclose(foot[left], [2.0 - body.HIP_HALF_WIDTH, 1.0 + reach,
                                            body.HIP_HEIGHT - body.LEG_LENGTH * np.cos(swing)], atol=1e-9)
    np.testing.assert_allclose(foot[right], [2.0 + body.HIP_HALF_WIDTH, 1.0 - reach,
                                             body.HIP_HEIGHT - body.LEG_LENGTH * np.cos(swing)], atol=1e-9)


def test_a_laser_at_38_cm_sees_two_legs_of_a_walker_for_most_of_the_cycle():
    # a person 3 m ahead walks across the view (+y) at 1.34 m/s; over one stride, the legs show as two segments
    # whenever they are apart by more than the beam spacing (2.6 cm at 3 m): the centres at 38 cm are
    # 2 (0.87 - 0.38) sin(swing) apart, the legs 12 cm wide, so two segments need |swing| > ~8 degrees, i.e.
    # |sin(phase)| > 0.34 of the 24.4-degree amplitude: about 78% of the cycle
    scene = Scene(np.array(FAR_WALL), 0.425, 1)
    laser = leg_laser(scene)
    counts = []
    for w in np.linspace(0.0, body.STRIDE, 200, endpoint=False):
        scene.sync(np.zeros(3), np.array([5]), np.array([[3.0, 0.0]]), np.array([[0.0, 1.34]]), np.array([w]))
        counts.append(runs_on(laser.scan(0.0, np.zeros(3)), 5))
    counts = np.array(counts)
    assert set(counts) <= {1, 2}
    assert 0.65 <= (counts == 2).mean() <= 0.9
    # mid-stance (phase 0 and pi: legs side by side, one behind the other as seen from the laser): one segment
    assert counts[0] == 1 and counts[100] == 1


@pytest.mark.parametrize("facing", [(1.0, 0.0), (0.0, 1.0), (0.7, 0.7)])
def test_a_standing_person_is_one_segment_at_38_cm(facing):
    # standing legs hang straight and touch: one segment whichever way the person faces (the heading comes from a
    # vanishing velocity, which turns the body without swinging the legs)
    scene = Scene(np.array(FAR_WALL), 0.425, 1)
    laser = leg_laser(scene)
    for walked in (0.0, 0.3, 0.9):
        scene.sync(np.zeros(3), np.array([5]), np.array([[3.0, 0.4]]), 1e-9 * np.array([facing]), np.array([walked]))
        assert runs_on(laser.scan(0.0, np.zeros(3)), 5) == 1


def test_clothing_colours_stay_with_the_person_and_differ_between_neighbours():
    scene = Scene(np.array(FAR_WALL), 0.425, 3)
    scene.sync(np.zeros(3), np.array([10, 11, 12]), np.array([[2.0, 0.0], [3.0, 0.0], [4.0, 0.0]]))

    def rgba(slot, part):
        return scene.model.geom_rgba[scene.model.geom(f"person{slot}_{part}").id].copy()

    first = [rgba(k, "torso")[:3] for k in range(3)]
    assert not np.allclose(first[0], first[1]) and not np.allclose(first[1], first[2])
    assert np.allclose(rgba(0, "left_leg"), rgba(0, "right_leg"))  # one pair of trousers
    # id 11 moves to slot 0: its colours go with it; the freed slots are parked and transparent
    scene.sync(np.zeros(3), np.array([11]), np.array([[3.0, 0.0]]))
    np.testing.assert_array_equal(rgba(0, "torso")[:3], first[1])
    for slot in (1, 2):
        for part in ("torso", "head", "left_leg", "right_leg"):
            assert rgba(slot, part)[3] == 0.0


def test_the_person_bodies_are_found_by_geom():
    scene = Scene(np.array(FAR_WALL), 0.425, 2)
    scene.sync(np.zeros(3), np.array([7, 8]), np.array([[2.0, 0.0], [4.0, 0.0]]))
    geoms = [scene.model.geom(f"person{k}_{part}").id for k in (0, 1)
             for part in ("torso", "head", "left_leg", "right_leg")]
    np.testing.assert_array_equal(scene.person_of_geom(np.array(geoms)), [7] * 4 + [8] * 4)
    np.testing.assert_array_equal(scene.person_of_geom(np.array([0, -1])), [-1, -1])  # a wall; no hit


def test_a_scene_holds_only_the_parts_its_sensors_see():
    # two 70 cm lasers see torsos only: one geom per person; a 38 cm laser, legs only
    assert parts_at(0.70) == {"torso"} and parts_at(0.38) == {"legs"} and parts_at(1.62) == {"head"}
    full, torsos = Scene(np.array(FAR_WALL), 0.425, 5), Scene(np.array(FAR_WALL), 0.425, 5, parts={"torso"})
    assert full.model.ngeom - torsos.model.ngeom == 5 * 4  # head, neck and two legs
    with pytest.raises(ValueError, match="unknown body parts"):
        Scene(np.array(FAR_WALL), 0.425, 5, parts={"arms"})
    # the torso-only scene gives a 70 cm laser the same scan as the full one
    for scene in (full, torsos):
        scene.sync(np.zeros(3), np.arange(5), np.array([[2.0, y] for y in (-2, -1, 0, 1, 2)]),
                   np.full((5, 2), 1.0), np.linspace(0, 1, 5))
    params = validate({"name": "l", "mount": [0.0, 0.0, 0.0], "noise": []}, LASER, "<test>")
    a, b = (Laser(scene=s, rng=np.random.default_rng(0), **params).scan(0.0, np.zeros(3)) for s in (full, torsos))
    np.testing.assert_array_equal(a.ranges, b.ranges)
    np.testing.assert_array_equal(a.person_id, b.person_id)


def test_a_ray_cast_skips_only_parts_it_cannot_meet():
    # at 70 cm the legs are inside the torso cylinder: casting against torsos alone gives the same ranges as
    # casting against everything, over a whole gait cycle of a person in every direction around the laser
    scene = Scene(np.array(FAR_WALL), 0.425, 8)
    assert list(Scene.groups_at(0.70)) == [1, 1, 0, 0, 0, 0] and list(Scene.groups_at(0.38)) == [1, 0, 0, 1, 0, 0]
    ang = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    xy = 1.5 * np.stack([np.cos(ang), np.sin(ang)], 1)
    vel = 1.3 * np.stack([np.cos(ang + 1.0), np.sin(ang + 1.0)], 1)
    vec = np.stack([np.cos(np.linspace(-np.pi, np.pi, 3600)), np.sin(np.linspace(-np.pi, np.pi, 3600)),
                    np.zeros(3600)], 1).ravel()
    for walked in np.linspace(0, body.STRIDE, 12, endpoint=False):
        scene.sync(np.array([-20.0, 0.0, 0.0]), np.arange(8), xy, vel, np.full(8, walked))
        out = {}
        for key, groups in (("all", None), ("torsos", Scene.groups_at(0.70))):
            geom, dist = np.zeros(3600, np.int32), np.zeros(3600)
            mujoco.mj_multiRay(scene.model, scene.data, np.array([0.0, 0.0, 0.70]), vec, groups, 1, -1, geom, dist,
                               None, 3600, 20.0)
            out[key] = dist
        np.testing.assert_array_equal(out["all"], out["torsos"])


def test_bodies_are_sized_by_the_crowd_radius_with_a_jitter_fixed_by_id():
    ids = np.arange(1, 2001)
    adults, children = body.body_scale(ids, np.full(2000, 0.25)), body.body_scale(ids, np.full(2000, 0.18))
    assert adults.min() >= 0.96 - 1e-9 and adults.max() <= 1.04 + 1e-9 and adults.std() > 0.015
    np.testing.assert_allclose(children / adults, 0.18 / 0.25)  # the same jitter, on a child's size
    np.testing.assert_array_equal(body.body_scale(ids, np.full(2000, 0.25)), adults)  # fixed by the id


def test_a_laser_sees_each_body_at_its_own_size_as_slots_change_hands():
    # a person 3 m ahead of a 70 cm laser at the origin (mount 0.25 m): the nearest return is 3 - 0.25 - 0.18 s;
    # a child (s 0.72) first, then an adult (s 1.0) in the same slot, then the child again
    scene = Scene(np.array(FAR_WALL), 0.425, 1, parts={"torso"})
    params = validate({"name": "l", "mount": [0.25, 0.0, 0.0], "noise": []}, LASER, "<test>")
    laser = Laser(scene=scene, rng=np.random.default_rng(0), **params)
    for scale in (0.72, 1.0, 0.72):
        scene.sync(np.zeros(3), np.array([1]), np.array([[3.0, 0.0]]), person_scale=np.array([scale]))
        scan = laser.scan(0.0, np.zeros(3))
        assert np.nanmin(scan.ranges) == pytest.approx(3.0 - 0.25 - body.TORSO_RADIUS * scale, abs=1e-9)
    with pytest.raises(ValueError, match="body scales"):
        scene.sync(np.zeros(3), np.array([1]), np.array([[3.0, 0.0]]), person_scale=np.array([2.0]))


def test_a_childs_head_is_lower_in_the_depth_image():
    # a level camera at 1.0 m, a child (s 0.72) 4 m ahead: the topmost pixel showing the child looks at the top
    # of the head, 1.72 x 0.72 = 1.24 m, that is atan(0.24 / 3.9) above the horizon
    from sensors.camera import DepthCamera, Intrinsics

    cam = {"name": "c", "position": [0.0, 0.0, 1.0], "yaw": 0.0, "pitch": 0.0, "fovy_deg": 43.0, "width": 160,
           "height": 120, "rate": 15.0, "range_min": 0.5, "range_max": 8.0, "noise": "none", "rgb": False}
    scene = Scene(np.array(FAR_WALL), 0.425, 1, robot_cameras=[cam])
    scene.sync(np.array([0.0, 0.0, 0.0]), np.array([3]), np.array([[4.0, 0.0]]), person_scale=np.array([0.72]))
    frame = DepthCamera(scene=scene, rng=np.random.default_rng(0), **cam).render(0.0)
    rows = np.flatnonzero((frame.person_id == 3).any(axis=1))
    k = Intrinsics(160, 120, 43.0)
    top = body.HEIGHT * 0.72
    expect_row = k.centre[1] - k.f * (top - 1.0) / (4.0 - body.HEAD_RADIUS * 0.72)  # the head's nearest side
    assert abs(rows.min() - expect_row) <= 1.5
