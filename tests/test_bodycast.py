"""Exact ray casts against the body primitives, against hand-worked distances, and the wall camera's people drawn
over the world: hidden behind a wall, in their clothing colours where they show."""

import numpy as np
import pytest

from sensors import body, bodycast
from sensors.camera import GLRenderer, Intrinsics, RaycastRenderer, WallCamera, camera_pose
from sensors.scene import Scene

F = np.float32


def rays(origins, directions):
    o, d = np.asarray(origins, F).reshape(-1, 3), np.asarray(directions, F).reshape(-1, 3)
    return (*o.T, *d.T)


def test_capsule_side_end_caps_and_a_ray_along_its_axis():
    # segment (0,0,0)-(0,0,-1), radius 0.1
    e = np.array([[0.0, 0.0, -1.0]] * 5, F)
    t = bodycast.ray_capsule(*rays([[1, 0, -0.5], [0, 0, 1], [1, 0, 0.05], [1, 0, -0.5], [1, 0, 0.2]],
                                   [[-1, 0, 0], [0, 0, -1], [-1, 0, 0], [-2, 0, 0], [-1, 0, 0]]), e, F(0.1))
    # the side at 0.9; down the axis onto the top cap at 1 - 0.1; the cap at height 0.05, where its section's radius
    # is sqrt(0.1^2 - 0.05^2); a direction twice as long halves t; above the cap: a miss
    np.testing.assert_allclose(t[:4], [0.9, 0.9, 1 - np.sqrt(0.0075), 0.45], rtol=1e-5)
    assert np.isinf(t[4])


def test_closed_cylinder_side_top_and_miss():
    r, z0, z1 = F(0.2), F(0.5), F(1.5)
    o = np.array([[2, 0, 1], [0.1, 0, 3], [2, 0, 1.6], [2, 0, 1], [0.3, 0, 3]], F)
    d = np.array([[-1, 0, 0], [0, 0, -1], [-1, 0, 0], [1, 0, 0], [0, 0, -1]], F)
    t = bodycast.ray_vertical_cylinder(*o.T, *d.T, r, z0, z1)
    # side at 2 - 0.2; straight down onto the top at 3 - 1.5; above it; pointing away; outside the circle
    np.testing.assert_allclose(t[:2], [1.8, 1.5], rtol=1e-6)
    assert np.isinf(t[2:]).all()


def test_sphere_with_a_long_direction():
    t = bodycast.ray_sphere(*rays([[0, 0, 1], [0, 0.2, 1]], [[0, 0, -2], [0, 0, -2]]), F(0.1))
    np.testing.assert_allclose(t[0], 0.45, rtol=1e-6)
    assert np.isinf(t[1])


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
    d = (target - origin).astype(F)
    w = (origin - hip).astype(F)
    t_hip = bodycast.ray_sphere(*w.T, *d.T, F(body.LEG_RADIUS))
    t_torso = bodycast.ray_vertical_cylinder(*origin.T.astype(F), *d.T, F(body.TORSO_RADIUS), F(body.TORSO_BOTTOM),
                                             F(body.TORSO_TOP))
    assert np.isfinite(t_hip).all() and (t_torso <= t_hip).all()
