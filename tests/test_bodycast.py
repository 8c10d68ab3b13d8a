"""Exact ray casts against the body primitives, against hand-worked distances, and the wall camera's people drawn
over the world: hidden behind a wall, in their clothing colours where they show."""

import numpy as np
import pytest

from sensors import body, bodycast
from sensors.camera import GLRenderer, Intrinsics, RaycastRenderer, WallCamera, camera_pose
from sensors.scene import Scene

F = np.float32


def cast(primitive, origins, directions, *measures):
    """The scalar kernel ``primitive`` on each ray (origin relative to the primitive, direction), in float32."""
    o, d = np.asarray(origins, F).reshape(-1, 3), np.asarray(directions, F).reshape(-1, 3)
    return np.array([primitive(*oi, *di, *measures) for oi, di in zip(o, d)], F)


def test_capsule_side_end_caps_and_a_ray_along_its_axis():
    # segment (0,0,0)-(0,0,-1), radius 0.1
    t = cast(bodycast.ray_capsule, [[1, 0, -0.5], [0, 0, 1], [1, 0, 0.05], [1, 0, -0.5], [1, 0, 0.2]],
             [[-1, 0, 0], [0, 0, -1], [-1, 0, 0], [-2, 0, 0], [-1, 0, 0]], F(0), F(0), F(-1), F(0.1), True)
    # the side at 0.9; down the axis onto the top cap at 1 - 0.1; the cap at height 0.05, where its section's radius
    # is sqrt(0.1^2 - 0.05^2); a direction twice as long halves t; above the cap: a miss
    np.testing.assert_allclose(t[:4], [0.9, 0.9, 1 - np.sqrt(0.0075), 0.45], rtol=1e-5)
    assert np.isinf(t[4])
    # without the start's cap, the ray down the axis (parallel to the side) passes the start and meets the far
    # end's cap at its top, 1 + 1 - 0.1 away
    below = cast(bodycast.ray_capsule, [[0, 0, 1]], [[0, 0, -1]], F(0), F(0), F(-1), F(0.1), False)
    np.testing.assert_allclose(below, [1.9], rtol=1e-6)


def test_closed_cylinder_side_top_and_miss():
    r, z0, z1 = F(0.2), F(0.5), F(1.5)
    o = [[2, 0, 1], [0.1, 0, 3], [2, 0, 1.6], [2, 0, 1], [0.3, 0, 3], [0, 0, 1]]
    d = [[-1, 0, 0], [0, 0, -1], [-1, 0, 0], [1, 0, 0], [0, 0, -1], [1, 0, 0]]
    t = cast(bodycast.ray_vertical_cylinder, o, d, r, z0, z1)
    # side at 2 - 0.2; straight down onto the top at 3 - 1.5; above it; pointing away; outside the circle; from
    # the axis, inside: at once
    np.testing.assert_allclose(t[:2], [1.8, 1.5], rtol=1e-6)
    assert np.isinf(t[2:5]).all() and t[5] == 0.0


def test_sphere_with_a_long_direction():
    t = cast(bodycast.ray_sphere, [[0, 0, 1], [0, 0.2, 1], [0, 0, 1]], [[0, 0, -2], [0, 0, -2], [0, 0, 2]], F(0.1))
    # the near side at (1 - 0.1) / 2; a miss to one side; one pointing away
    np.testing.assert_allclose(t[0], 0.45, rtol=1e-6)
    assert np.isinf(t[1:]).all()


def test_nearest_parts_of_a_person_in_a_level_camera():
    # a level camera 4 m in front of an adult standing at the origin, looking +x from 1 m up; f = 100 px and the
    # centre at (49.5, 49.5), so pixel (49, 49) looks straight along +x
    scene = Scene(np.zeros((0, 2, 2)), 0.425, 1)
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1]), np.array([[0.0, 0.0]]))
    scene.person_scale[0] = 1.0
    origin = np.array([-4.0, 0.0, 1.0])
    rot = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # optical x right = -y, y down = -z
    part_lo = np.zeros((1, 4, 2), np.int64)
    part_hi = np.array([[[100, 100], [100, 100], [0, 0], [0, 0]]])  # the legs' boxes left empty
    owner, u, v, z, part, weight = bodycast.nearest_parts(origin, rot, 100.0, 49.5, 49.5, 100, 100, part_lo, part_hi,
                                                          np.array([True]), *bodycast.bodies(scene, np.array([0])),
                                                          False)
    hit = {(a, b): (c, p) for a, b, c, p in zip(u, v, z, part)}
    # straight ahead: the torso's front, 4 - 0.18 away (the z-depth is the ray's parameter, as its optical z is 1)
    t, p = hit[(49, 49)]
    assert p == bodycast.TORSO and t == pytest.approx(4 - body.TORSO_RADIUS, abs=1e-5)
    # row 34 looks up at 0.15 per metre: (t - 4)^2 + (0.15 t - 0.62)^2 = 0.1^2 (the head's centre 0.62 m above the
    # camera), whose nearer root is t = (8.186 - sqrt(8.186^2 - 4 x 1.0225 x 16.3744)) / (2 x 1.0225) = 3.90599
    t, p = hit[(49, 34)]
    assert p == bodycast.HEAD and t == pytest.approx(3.90599, abs=1e-4)
    # by rows; every hit in the image stands for one pixel; the top row looks 0.5 m up at 1 m: over the head
    assert (np.diff(v) >= 0).all() and (owner == 0).all() and (weight == 1.0).all()
    assert (49, 0) not in hit


CAM = {"name": "wall_cam", "position": [0.0, 0.0, 1.2], "yaw": 0.0, "pitch": 0.0, "fovy_deg": 50.0,
       "width": 320, "height": 240, "rate": 10.0, "rgb": True}


@pytest.mark.parametrize("renderer", ["gl", "raycast"])
def test_a_wall_camera_shows_people_in_their_colours_and_not_through_walls(renderer, monkeypatch):
    # a wall across the view at x = 5 from y = 0.8 to 3: person 1 at (6, 2) stands behind it, person 2 at (6, 0)
    # does not; a level camera at 1.2 m looking +x sees person 2's top face-on at the pixel its torso's front
    # projects to
    walls = np.array([[[5.0, 0.8], [5.0, 3.0]], [[-30.0, -30.0], [-30.0, 30.0]]])
    scene = Scene(walls, 0.425, 2, wall_cameras=[CAM])
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1, 2]), np.array([[6.0, 2.0], [6.0, 0.0]]))
    if renderer == "raycast":
        monkeypatch.setenv("MUJOCO_GL", "disable")
    camera = WallCamera(scene=scene, **CAM)
    assert isinstance(camera.renderer, GLRenderer if renderer == "gl" else RaycastRenderer)
    frame = camera.render(0.0)
    assert list(frame.ids) == [2]
    assert (frame.person_id == 1).sum() == 0 and (frame.person_id == 2).sum() > 500
    origin, rot = camera_pose(scene, CAM["name"])
    u, v = Intrinsics(320, 240, 50.0).project((np.array([[6.0 - body.TORSO_RADIUS, 0.0, 1.0]]) - origin) @ rot)[0]
    top = body.clothing(np.array([2]))[0][0]
    pixel = frame.rgb[int(v), int(u)] / 255.0
    assert frame.person_id[int(v), int(u)] == 2
    # lit by a light at the eye: the surface faces the camera, so the colour is the top's at full strength (to the
    # 8-bit step)
    np.testing.assert_allclose(pixel, top, atol=1.5 / 255)
    assert frame.visible_fraction[0] == pytest.approx(1.0, abs=0.03)


def test_normals_of_each_part():
    # one adult standing at (2, 3), legs straight: points on the torso's side and top, the head and a leg
    scene = Scene(np.zeros((0, 2, 2)), 0.425, 1)
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1]), np.array([[2.0, 3.0]]))
    r, hip = body.TORSO_RADIUS, body.HIP_HALF_WIDTH
    points = np.array([[2.0 + r, 3.0, 1.0], [2.0, 3.1, body.TORSO_TOP], [2.0, 3.0 - body.HEAD_RADIUS, body.HEAD_CENTRE],
                       [2.0 - body.LEG_RADIUS, 3.0 + hip, 0.4], [2.0, 3.0 - hip, 0.0]])
    part = np.array([bodycast.TORSO, bodycast.TORSO, bodycast.HEAD, bodycast.LEFT_LEG, bodycast.RIGHT_LEG])
    n = bodycast.normals(scene, np.zeros(5, np.int64), part, points)
    # side: +x; flat top: +z; head: -y; the left leg's back: -x; the right foot's tip, below the axis's end: -z
    np.testing.assert_allclose(n, [[1, 0, 0], [0, 0, 1], [0, -1, 0], [-1, 0, 0], [0, 0, -1]], atol=1e-9)


def test_the_hip_end_of_a_leg_lies_inside_the_torso():
    # rays from all round a person (one with a leg swung fully forward) aimed at points of the sphere that ends each
    # leg at the hip meet the torso no later: leaving that sphere out of the leg's cast changes no image
    assert body.HIP_INSIDE_TORSO
    scene = Scene(np.zeros((0, 2, 2)), 0.425, 1)
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1]), np.array([[0.0, 0.0]]), np.array([[1.0, 0.0]]),
               np.array([body.STRIDE / 4]))
    rng = np.random.default_rng(3)
    hip = scene.hips[0, rng.integers(0, 2, 500)]
    target = hip + body.LEG_RADIUS * rng.uniform(-1, 1, (500, 3)) / np.sqrt(3)
    origin = np.column_stack([rng.uniform(-5, 5, (500, 2)), rng.uniform(0.0, 3.0, 500)])
    origin[:, :2] *= 1 + 1 / np.linalg.norm(origin[:, :2], axis=1)[:, None]  # at least 1 m from the axis
    t_hip = cast(bodycast.ray_sphere, origin - hip, target - origin, F(body.LEG_RADIUS))
    t_torso = cast(bodycast.ray_vertical_cylinder, origin, target - origin, F(body.TORSO_RADIUS),
                   F(body.TORSO_BOTTOM), F(body.TORSO_TOP))
    assert np.isfinite(t_hip).all() and (t_torso <= t_hip).all()


def test_part_box_corners_of_a_standing_adult():
    # an adult at (2, 3), legs straight: the torso's box is its cylinder's, the head's its sphere's, each leg's the
    # box round its axis from hip to foot grown by its radius
    scene = Scene(np.zeros((0, 2, 2)), 0.425, 1)
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1]), np.array([[2.0, 3.0]]))
    corners = bodycast.part_box_corners(scene, np.array([0]))[0]
    r, h = body.TORSO_RADIUS, body.HEAD_RADIUS
    np.testing.assert_allclose(corners[:8].min(axis=0), [2 - r, 3 - r, body.TORSO_BOTTOM], atol=1e-12)
    np.testing.assert_allclose(corners[:8].max(axis=0), [2 + r, 3 + r, body.TORSO_TOP], atol=1e-12)
    np.testing.assert_allclose(corners[8], [2 - h, 3 - h, body.HEAD_CENTRE - h], atol=1e-12)  # corner (-1, -1, -1)
    np.testing.assert_allclose(corners[15], [2 + h, 3 + h, body.HEAD_CENTRE + h], atol=1e-12)
    for leg in (0, 1):
        ends = np.stack([scene.hips[0, leg], scene.feet[0, leg]])
        box = corners[16 + 8 * leg:24 + 8 * leg]
        np.testing.assert_allclose(box.min(axis=0), ends.min(axis=0) - body.LEG_RADIUS, atol=1e-12)
        np.testing.assert_allclose(box.max(axis=0), ends.max(axis=0) + body.LEG_RADIUS, atol=1e-12)
    with pytest.raises(ValueError, match="slot"):
        bodycast.part_box_corners(scene, np.array([5]))
