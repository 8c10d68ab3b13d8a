"""Cameras against hand-worked projections: the depth of a known plane, point clouds, Kinect noise, a wall camera's
box of a person at a known position, visible fractions, and agreement of segmentation with laser hits."""

import numpy as np
import pytest

from scenarios.format import DEPTH_CAMERA, LASER
from scenarios.schema import validate
from sensors import body
from sensors.camera import DepthCamera, GLRenderer, Intrinsics, RaycastRenderer, WallCamera, camera_pose
from sensors.laser import Laser
from sensors.scene import Scene

WALL_X = [[[5.0, -30.0], [5.0, 30.0]]]  # its face towards the robot at x = 4.95
DEPTH = validate({"name": "front_depth", "preset": "kinect_160", "position": [0.45, 0.0, 1.2], "noise": "none"},
                 DEPTH_CAMERA, "<test>")
WALL_CAM = {"name": "wall_cam", "position": [0.0, 0.0, 3.0], "yaw": 0.0, "pitch": float(np.radians(30.0)),
            "fovy_deg": 50.0, "width": 320, "height": 240, "rate": 10.0, "rgb": False}


def depth_scene(walls=WALL_X, capacity=4, **camera):
    cam = validate(dict(DEPTH, **camera), DEPTH_CAMERA, "<test>")
    return Scene(np.array(walls, float), 0.425, capacity, robot_cameras=[cam]), cam


def expected_depth(cam):
    """z-depth of each pixel of a level camera at height h facing +x: the wall face 4.95 m ahead where the ray
    meets it between the floor and the wall top (2.5 m), else the floor (z-depth h / (-v) for a ray (x, v, 1) with
    v the downward slope), else nothing."""
    k = Intrinsics(cam["width"], cam["height"], cam["fovy_deg"])
    rays = k.pixel_directions()  # optical: x right, y down, z forward (= world +x here)
    ahead = 4.95 - cam["position"][0]
    h = cam["position"][2]
    z_at_wall = h - ahead * rays[..., 1]  # height where the ray reaches the wall
    floor_depth = np.where(rays[..., 1] > 0, h / np.maximum(rays[..., 1], 1e-12), np.inf)
    return np.where((z_at_wall >= 0) & (z_at_wall <= 2.5), ahead, np.where(z_at_wall < 0, floor_depth, np.nan))


@pytest.mark.parametrize("renderer", ["gl", "raycast"])
def test_depth_of_a_known_plane_and_of_the_floor(renderer):
    scene, cam = depth_scene()
    scene.sync(np.zeros(3), np.zeros(0, np.int64), np.zeros((0, 2)))
    camera = DepthCamera(scene=scene, rng=np.random.default_rng(0), **cam)
    if renderer == "raycast":
        camera.renderer = RaycastRenderer(scene, camera.intrinsics, scene.robot_body)
    else:
        assert isinstance(camera.renderer, GLRenderer), "no GL context here: the raycast case covers the fallback"
    frame = camera.render(0.0)
    expect = expected_depth(cam)
    expect = np.where((expect >= 0.5) & (expect <= 8.0), expect, np.nan)
    # rows on either side of the wall's foot and top may differ by the rasterization of one edge: compare the rest
    got = frame.depth
    same_valid = np.isfinite(got) == np.isfinite(expect)
    assert same_valid.mean() > 0.97
    both = np.isfinite(got) & np.isfinite(expect)
    wall = both & (np.abs(expect - 4.5) < 1e-9)
    assert wall.sum() > 5000
    np.testing.assert_allclose(got[wall], 4.5, atol=1e-3)  # the plane 4.5 m ahead, to a millimetre
    floor = both & ~wall
    assert floor.sum() > 1000
    np.testing.assert_allclose(got[floor], expect[floor], rtol=5e-3)


def test_point_cloud_lies_on_the_wall():
    scene, cam = depth_scene()
    scene.sync(np.zeros(3), np.zeros(0, np.int64), np.zeros((0, 2)))
    frame = DepthCamera(scene=scene, rng=np.random.default_rng(0), **cam).render(0.0)
    origin, rot = camera_pose(scene, cam["name"])
    world = frame.points @ rot.T + origin
    on_wall = np.abs(world[:, 0] - 4.95) < 1e-3
    assert on_wall.sum() > 5000
    # the others lie on the floor, z = 0
    np.testing.assert_allclose(world[~on_wall, 2], 0.0, atol=0.02)
    assert len(frame.points) == np.isfinite(frame.depth).sum()


@pytest.mark.parametrize("sigma, subpixel", [(1.425e-3, 8), (2.85e-3, 64)])
def test_kinect_noise_has_the_configured_sigma_and_disparity_steps(sigma, subpixel):
    # the Kinect's at 4.5 m: sigma 1.425e-3 x 4.5^2 = 28.9 mm, and the depth quantized where 8 f b / z (f 580 px,
    # b 7.5 cm) is a whole number, 58 mm between levels; then twice the sigma on 1/64-pixel steps
    scene, cam = depth_scene(noise="kinect", range_max=20.0, noise_sigma=sigma, disparity_subpixel=subpixel)
    assert (cam["ir_focal_px"], cam["ir_baseline"]) == (580.0, 0.075)
    scene.sync(np.zeros(3), np.zeros(0, np.int64), np.zeros((0, 2)))
    frame = DepthCamera(scene=scene, rng=np.random.default_rng(3), **cam).render(0.0)
    wall = np.abs(expected_depth(cam) - 4.5) < 1e-9
    z = frame.depth[wall & np.isfinite(frame.depth)]
    steps = subpixel * 580.0 * 0.075 / z
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-3)
    step = 4.5**2 / (subpixel * 580.0 * 0.075)
    assert abs(z.mean() - 4.5) < 0.01
    assert z.std() == pytest.approx(np.hypot(sigma * 4.5**2, step / np.sqrt(12)), rel=0.15)


def test_wall_camera_box_of_a_person_is_its_projection_within_a_pixel():
    # a person standing at (6, 0.5), seen from (0, 0, 3) looking +x 30 degrees down: the box around the visible
    # pixels equals the box around the projection of the body's surface (torso cylinder, head sphere, legs)
    scene = Scene(np.array(WALL_X) * 3, 0.425, 2, wall_cameras=[WALL_CAM])
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([4]), np.array([[6.0, 0.5]]))
    frame = WallCamera(scene=scene, **WALL_CAM).render(0.0)
    assert list(frame.ids) == [4]
    origin, rot = camera_pose(scene, WALL_CAM["name"])
    a = np.linspace(0, 2 * np.pi, 720)
    ring = lambda c, r, z: np.stack([c[0] + r * np.cos(a), c[1] + r * np.sin(a), np.full_like(a, z)], 1)  # noqa: E731
    surface = [ring((6.0, 0.5), body.TORSO_RADIUS, z) for z in (body.TORSO_BOTTOM, body.TORSO_TOP)]
    for lat in np.linspace(-np.pi / 2, np.pi / 2, 181):  # the head
        r, z = body.HEAD_RADIUS * np.cos(lat), body.HEAD_CENTRE + body.HEAD_RADIUS * np.sin(lat)
        surface.append(ring((6.0, 0.5), r, z))
    for side in (1, -1):  # straight legs: vertical capsules from the floor to the hip
        for z in np.linspace(0.0, body.HIP_HEIGHT, 60):
            surface.append(ring((6.0, 0.5 + side * body.HIP_HALF_WIDTH), body.LEG_RADIUS, z))
    uv = Intrinsics(320, 240, 50.0).project((np.concatenate(surface) - origin) @ rot)
    expect = [uv[:, 0].min(), uv[:, 1].min(), uv[:, 0].max(), uv[:, 1].max()]
    np.testing.assert_allclose(frame.boxes[0], expect, atol=1.0)
    np.testing.assert_allclose(frame.full_boxes[0], expect, atol=1.0)
    assert frame.visible_fraction[0] == pytest.approx(1.0, abs=0.03)


def test_visible_fraction_of_a_half_hidden_person():
    # person 2 at (8, 0.5) behind person 1 at (6, 0.9), level camera at 1 m: person 1 covers about half of 2
    cam = dict(WALL_CAM, pitch=0.0, position=[0.0, 0.0, 1.0])
    scene = Scene(np.array(WALL_X) * 3, 0.425, 2, wall_cameras=[cam])
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1, 2]), np.array([[6.0, 0.78], [8.0, 0.85]]))
    frame = WallCamera(scene=scene, **cam).render(0.0)
    fraction = dict(zip(frame.ids.tolist(), frame.visible_fraction))
    assert fraction[1] == pytest.approx(1.0, abs=0.03)
    assert 0.2 < fraction[2] < 0.8
    # hidden entirely: person 2 right behind person 1 on the camera's line of sight
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1, 2]), np.array([[6.0, 0.0], [9.0, 0.0]]))
    frame = WallCamera(scene=scene, **cam).render(0.0)
    assert 2 not in frame.ids or dict(zip(frame.ids.tolist(), frame.visible_fraction))[2] < 0.05


def test_segmentation_agrees_with_laser_hits():
    # a depth camera and a laser at the same height and place see the same people: 14 persons scattered ahead,
    # some hiding others; everyone with 3 or more beams shows in the camera, and nobody the camera misses has a beam
    rng = np.random.default_rng(7)
    xy = np.stack([rng.uniform(1.5, 7.5, 14), rng.uniform(-2.5, 2.5, 14)], 1)
    scene, cam = depth_scene(capacity=14, position=[0.0, 0.0, 0.70], range_max=20.0)
    scene.sync(np.zeros(3), np.arange(14), xy)
    frame = DepthCamera(scene=scene, rng=np.random.default_rng(0), **cam).render(0.0)
    laser = Laser(scene=scene, rng=np.random.default_rng(0),
                  **validate({"name": "l", "mount": [0.0, 0.0, 0.0], "fov_deg": 56.0, "resolution_deg": 0.25,
                              "noise": []}, LASER, "<test>"))
    scan = laser.scan(0.0, np.zeros(3))
    beams = np.bincount(scan.person_id[scan.person_id >= 0], minlength=14)
    pixels = np.bincount(frame.person_id[frame.person_id >= 0], minlength=14)
    in_view = np.abs(np.degrees(np.arctan2(xy[:, 1], xy[:, 0]))) < 25  # inside both fields of view
    assert (pixels[in_view & (beams >= 3)] > 0).all()
    assert (beams[in_view & (pixels == 0)] == 0).all()
    assert (beams[in_view] == 0).any() and (beams[in_view] >= 3).any()  # some hidden, some seen


def test_wall_camera_calibration_maps_the_image_to_the_floor():
    scene = Scene(np.array(WALL_X) * 3, 0.425, 1, wall_cameras=[WALL_CAM])
    scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1]), np.array([[6.0, 0.5]]))
    camera = WallCamera(scene=scene, **WALL_CAM)
    floor = np.array([[4.0, -1.0], [6.0, 0.5], [9.0, 2.0]])
    origin, rot = camera_pose(scene, WALL_CAM["name"])
    uv = Intrinsics(320, 240, 50.0).project((np.column_stack([floor, np.zeros(3)]) - origin) @ rot)
    h = camera.ground_homography()
    mapped = np.column_stack([floor, np.ones(3)]) @ h.T
    np.testing.assert_allclose(mapped[:, :2] / mapped[:, 2:], uv, atol=1e-9)
    np.testing.assert_allclose(camera.image_to_ground(uv), floor, atol=1e-9)
    # the person's feet: the lowest visible pixel row of their box, mid-column, lands within 10 cm of their
    # position's near side (the camera 30 degrees down sees the front of the feet)
    frame = camera.render(0.0)
    u0, v0, u1, v1 = frame.boxes[0]
    feet = camera.image_to_ground(np.array([[(u0 + u1) / 2, v1]]))[0]
    assert np.hypot(*(feet - [6.0 - body.LEG_RADIUS, 0.5])) < 0.1
    # a point above the horizon has no floor under it
    assert np.isnan(camera.image_to_ground(np.array([[160.0, -500.0]]))).all()


def test_a_head_height_depth_camera_sees_the_floor_and_the_heads():
    # the default robot camera (1.45 m, tilted 0.15 rad down) and a person 3 m ahead: among the person's points
    # some lie at head height (the head spans 1.52-1.72 m), and the floor shows in front of them
    cam = dict(DEPTH, position=[0.45, 0.0, 1.45], pitch=0.15)
    scene = Scene(np.array(WALL_X) * 3, 0.425, 1, robot_cameras=[cam])
    scene.sync(np.zeros(3), np.array([9]), np.array([[3.5, 0.0]]))
    camera = DepthCamera(scene=scene, rng=np.random.default_rng(0), **cam)
    frame = camera.render(0.0)
    origin, rot = camera_pose(scene, cam["name"])
    valid = np.isfinite(frame.depth)
    world = frame.points @ rot.T + origin
    person = frame.person_id[valid] == 9
    head = person & (world[:, 2] > body.HEAD_CENTRE - body.HEAD_RADIUS)
    assert head.sum() > 10
    # on the head's sphere, to the tessellation MuJoCo draws it with (a few millimetres)
    np.testing.assert_allclose(np.linalg.norm(world[head] - [3.5, 0.0, body.HEAD_CENTRE], axis=1), body.HEAD_RADIUS,
                               atol=0.015)
    floor = ~person & (np.abs(world[:, 2]) < 0.01)
    assert floor.sum() > 1000 and world[floor, 0].min() < 3.0


def test_without_gl_the_cameras_fall_back_to_ray_casting_and_say_so(monkeypatch):
    scene, cam = depth_scene()
    scene.sync(np.zeros(3), np.zeros(0, np.int64), np.zeros((0, 2)))
    monkeypatch.setenv("MUJOCO_GL", "disable")
    camera = DepthCamera(scene=scene, rng=np.random.default_rng(0), **cam)
    assert camera.backend == "raycast"
    frame = camera.render(0.0)
    wall = np.abs(expected_depth(cam) - 4.5) < 1e-9
    np.testing.assert_allclose(frame.depth[wall], 4.5, atol=1e-6)
    assert WallCamera(scene=Scene(np.array(WALL_X), 0.425, 1, wall_cameras=[WALL_CAM]), **WALL_CAM).backend == "raycast"


def test_walls_out_of_view_are_left_out_without_changing_the_image():
    # a room with walls all round and inside it; the camera faces +x from its middle: walls behind it and beyond
    # 8 m are not drawn, and the depth image and segmentation are what they are with every wall drawn
    walls = [[[-10, -10], [10, -10]], [[10, -10], [10, 10]], [[10, 10], [-10, 10]], [[-10, 10], [-10, -10]],
             [[-6, -3], [-6, 3]], [[4, 2], [6, 2]], [[3, -1], [3, -4]], [[-2, 6], [2, 6]]]
    scene, cam = depth_scene(walls, capacity=3)
    scene.sync(np.zeros(3), np.array([1, 2, 3]), np.array([[2.0, 0.5], [5.0, -1.0], [-3.0, 0.0]]))
    camera = DepthCamera(scene=scene, rng=np.random.default_rng(0), **cam)
    assert isinstance(camera.renderer, GLRenderer), "no GL context here: the ray-casting renderer culls nothing"
    renderer = camera.renderer
    culled = renderer._walls[renderer._frustum(cam["name"], renderer._wall_corners)]
    assert 0 < len(culled) < len(renderer._walls)
    culled_frame = camera.render(0.0)
    renderer._walls, renderer._wall_corners = renderer._walls[:0], renderer._wall_corners[:0]  # draw every wall
    full_frame = camera.render(0.0)
    np.testing.assert_array_equal(culled_frame.depth, full_frame.depth)
    np.testing.assert_array_equal(culled_frame.person_id, full_frame.person_id)


def test_a_scene_grown_for_more_people_sees_what_a_big_one_does():
    # the same 50 people in a scene made for all of them and in one that started with 4 slots and grew while its
    # lasers and cameras were in use: the same scans, depth images and wall-camera frames, bit for bit
    from sensors.laser import LaserArray

    rng = np.random.default_rng(5)
    xy = np.column_stack([rng.uniform(1.5, 9.0, 50), rng.uniform(-4.0, 4.0, 50)])
    vel = rng.normal(0, 1, (50, 2))
    walked = rng.uniform(0, 10, 50)
    wall_cam = dict(WALL_CAM, rgb=True)
    out = []
    for initial in (60, 4):
        scene = Scene(np.array(WALL_X) * 3, 0.425, 60, robot_cameras=[DEPTH], wall_cameras=[wall_cam],
                      initial_capacity=initial)
        scene.sync(np.zeros(3), np.arange(3), xy[:3], vel[:3], walked[:3])
        lasers = LaserArray([Laser(scene=scene, rng=np.random.default_rng(0),
                                   **validate({"name": "l", "mount": [0, 0, 0], "noise": []}, LASER, "<test>"))], scene)
        depth = DepthCamera(scene=scene, rng=np.random.default_rng(0), **DEPTH)
        wall = WallCamera(scene=scene, **wall_cam)
        before = (lasers.scan(0.0, np.zeros(3), [0])[0].ranges, depth.render(0.0).depth, wall.render(0.0).rgb)
        scene.sync(np.zeros(3), np.arange(50), xy, vel, walked)
        assert scene.capacity == (60 if initial == 60 else 50)
        scan = lasers.scan(0.0, np.zeros(3), [0])[0]
        d, w = depth.render(0.0), wall.render(0.0)
        out.append((before, scan.ranges, scan.person_id, d.depth, d.person_id, w.rgb, w.person_id, w.boxes))
    for a, b in zip(*out):
        for x, y in zip(a, b) if isinstance(a, tuple) else [(a, b)]:
            np.testing.assert_array_equal(x, y)


def test_a_renderer_freed_leaves_the_others_images_alone():
    # freeing a GL renderer must not delete another one's buffers (GL object names are per context): the second
    # camera's image after the first is gone equals the first camera's
    import gc

    def camera():
        scene = Scene(np.array(WALL_X) * 3, 0.425, 2, wall_cameras=[dict(WALL_CAM, rgb=True)])
        scene.sync(np.array([-20.0, 0.0, 0.0]), np.array([1, 2]), np.array([[6.0, 0.5], [8.0, -1.0]]))
        return WallCamera(scene=scene, **dict(WALL_CAM, rgb=True))

    first = camera()
    image = first.render(0.0).rgb
    second = camera()
    del first
    gc.collect()
    np.testing.assert_array_equal(second.render(0.0).rgb, image)


@pytest.mark.parametrize("renderer", ["gl", "raycast"])
def test_a_fixed_camera_draws_the_robot_over_the_world_it_drew_once(renderer, monkeypatch):
    # a level wall camera 0.5 m up looking +x at the wall 4.95 m away; the robot (base radius 0.425, 0.95 m high)
    # drives into view: the pixels round the optical axis see the base's front at (3, 0), 3 - 0.425 away (GL draws
    # the cylinder as 16 flat sides, whose faces lie 0.425 cos(pi / 16) from the axis); then it leaves the view and
    # the wall shows again. Each image is the one drawn whole.
    if renderer == "raycast":
        monkeypatch.setenv("MUJOCO_GL", "disable")
    cam = dict(WALL_CAM, position=[0.0, 0.0, 0.5], pitch=0.0, rgb=True)
    scene = Scene(np.array(WALL_X, float), 0.425, 1, wall_cameras=[cam])
    camera = WallCamera(scene=scene, **cam)
    assert camera.renderer.fixed and (camera.backend == "raycast") == (renderer == "raycast")
    whole = (GLRenderer(scene, camera.intrinsics, rgb=True, people=False) if isinstance(camera.renderer, GLRenderer)
             else RaycastRenderer(scene, camera.intrinsics, people=False))
    for x, y, seen in ((-20.0, 0.0, False), (3.0, 0.0, True), (3.0, 0.7, True), (-3.0, 0.0, False)):
        scene.sync(np.array([x, y, 0.3]), np.zeros(0, np.int64), np.zeros((0, 2)))
        got = camera.renderer.render(cam["name"], depth=True, segmentation=False, rgb=True)
        drawn = whole.render(cam["name"], depth=True, segmentation=False, rgb=True)
        np.testing.assert_array_equal(got["depth"], drawn["depth"])
        np.testing.assert_array_equal(got["rgb"], drawn["rgb"])
        centre = got["depth"][119:121, 159:161]  # the four pixels round the optical axis
        if seen and y == 0.0:
            assert (centre >= 3.0 - 0.425 - 1e-3).all() and (centre <= 3.0 - 0.425 * np.cos(np.pi / 16) + 1e-3).all()
        elif not seen:
            np.testing.assert_allclose(centre, 4.95, atol=2e-3)


def test_shading_by_the_angle_to_the_eye():
    # colour (0.5, 1, 0.2): facing the eye (a view twice as long changes nothing) at full strength, 255 x colour
    # truncated; edge-on at 0.35 of it; 45 degrees at 0.35 + 0.65 cos 45 = 0.80962
    from sensors.camera import shade
    colour = np.array([[0.5, 1.0, 0.2]] * 3)
    normal = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-np.sqrt(0.5), np.sqrt(0.5), 0.0]])
    view = np.array([[2.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    np.testing.assert_array_equal(shade(colour, normal, view), [[127, 255, 51], [44, 89, 17], [103, 206, 41]])


def test_a_fixed_renderer_refuses_people():
    # people drawn into a world drawn once would stay where they were first drawn
    scene = Scene(np.array(WALL_X, float), 0.425, 1, wall_cameras=[WALL_CAM])
    k = Intrinsics(320, 240, 50.0)
    with pytest.raises(ValueError, match="no people"):
        RaycastRenderer(scene, k, people=True, fixed=True)
    with pytest.raises(ValueError, match="no people"):
        GLRenderer(scene, k, people=True, fixed=True)


def test_boxes_of_owners_pixels_in_any_order():
    # owner 0 has pixels (3, 5), (1, 7): box u 1..4, v 5..8; owner 2 one pixel (6, 0); owner 1 none
    from sensors.camera import _boxes_of
    boxes = _boxes_of(np.array([0, 2, 0]), np.array([3, 6, 1]), np.array([5, 0, 7]), 3)
    np.testing.assert_array_equal(boxes, [[1, 5, 4, 8], [0, 0, 0, 0], [6, 0, 7, 1]])


def test_kinect_noise_on_worked_depths():
    # f b s = 580 x 0.075 x 8 = 348: z 2.0 with draw 0 -> 348 / round(174) = 2.0; z 3.0 with draw 1 and sigma 0.01
    # (sigma z^2 = 0.09 in float32) -> 3.09 -> 348 / round(112.62) = 348 / 113; nothing seen stays inf
    from types import SimpleNamespace

    from sensors.camera import _kinect
    camera = SimpleNamespace(ir_focal_px=580.0, ir_baseline=0.075, disparity_subpixel=8)
    fb = camera.ir_focal_px * camera.ir_baseline * camera.disparity_subpixel
    out = _kinect(np.array([2.0, 3.0, np.inf], np.float32), np.array([0.0, 1.0, 5.0]), np.float32(0.01), fb)
    assert out.dtype == np.float32
    np.testing.assert_array_equal(out, np.array([fb / 174, fb / 113, np.inf], np.float32))


def test_measured_depths_keep_the_range_and_scale_the_rays():
    # range [0.5, 8]: 0.4 and 9 read NaN; the points are the valid pixels' rays times their depth, row by row
    from sensors.camera import measured
    z = np.array([[0.4, 2.0], [9.0, 8.0]], np.float32)
    rays = np.array([[[0.0, 0.0, 1.0], [0.5, -0.25, 1.0]], [[1.0, 1.0, 1.0], [-0.5, 0.0, 1.0]]])
    depth, points = measured(z, rays, 0.5, 8.0)
    np.testing.assert_array_equal(depth, np.array([[np.nan, 2.0], [np.nan, 8.0]], np.float32))
    np.testing.assert_array_equal(points, [[1.0, -0.5, 2.0], [-4.0, 0.0, 8.0]])
    with pytest.raises(ValueError, match="float32"):
        measured(z.astype(float), rays, 0.5, 8.0)


def test_gl_depth_buffer_to_metres():
    # near 1, far 3: b 0 -> 1 m, b 0.5 -> 3 / (3 - 1) = 1.5 m, b 1 (nothing drawn) -> inf
    from sensors.camera import _gl_depth
    np.testing.assert_array_equal(_gl_depth(np.array([[0.0, 0.5, 1.0]], np.float32), 3.0, 3.0, 2.0),
                                  np.array([[1.0, 1.5, np.inf]], np.float32))


def test_people_shaded_in_their_parts_colours_where_they_show():
    # person 1's head (part 1) at pixel 2 facing the eye: its colour at full strength; person 0's torso at pixel 0
    # edge-on: 0.35 of it; pixel 1 untouched
    from sensors.camera import _shade_people
    rgb = np.zeros((3, 3), np.uint8)
    palette = np.zeros((2, 4, 3))
    palette[1, 1], palette[0, 0] = [0.5, 1.0, 0.2], [1.0, 1.0, 1.0]
    normal = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    view = np.array([[2.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    _shade_people(rgb, np.array([2, 0]), np.array([1, 0]), np.array([1, 0]), palette, normal, view)
    np.testing.assert_array_equal(rgb, [[89, 89, 89], [0, 0, 0], [127, 255, 51]])


def test_part_boxes_of_projected_corners():
    # f 10, centre (4, 3), image 8 x 6; a person whose 32 corners lie at x in [-0.1, 0.1], y in [0, 0.2], z 1 (part 0
    # also at x 0.25): u 3..5 (part 0: 3..7), v 3..5; one with a corner behind the camera is not cast; one far left
    # of the image (u -16 clipped to -8 .. -6) is not cast either
    from sensors.camera import _part_boxes
    cam = np.zeros((3, 32, 3))
    cam[0, :, 0], cam[0, :, 1], cam[0, :, 2] = np.tile([-0.1, 0.1], 16), np.tile([0.0, 0.0, 0.2, 0.2], 8), 1.0
    cam[0, 3, 0] = 0.25
    cam[1] = cam[0]
    cam[1, 5, 2] = -1.0
    cam[2] = cam[0]
    cam[2, :, 0] = -2.0
    lo, hi, cast = _part_boxes(cam, 10.0, 4.0, 3.0, 8, 6)
    np.testing.assert_array_equal(lo[0], [[3, 3]] * 4)
    np.testing.assert_array_equal(hi[0], [[7, 5]] + [[5, 5]] * 3)
    np.testing.assert_array_equal(lo[1], [[14, 12]] * 4)  # corners at (1, 1, 1): u 4 + 10, v 3 + 10 clipped to 12
    np.testing.assert_array_equal(lo[2, :, 0], [-8] * 4)
    np.testing.assert_array_equal(hi[2, :, 0], [-8] * 4)
    np.testing.assert_array_equal(cast, [True, False, False])


def test_segments_of_a_segmentation_image():
    # person 7 at (0, 0) and (2, 1); person 3 at (1, 0): sorted ids, boxes (u0, v0, u1, v1) and pixel counts
    from sensors.camera import _segments
    seg = np.array([[7, 3, -1], [-1, -1, 7]])
    ids, boxes, counts = _segments(seg)
    np.testing.assert_array_equal(ids, [3, 7])
    np.testing.assert_array_equal(boxes, [[1, 0, 2, 1], [0, 0, 3, 2]])
    np.testing.assert_array_equal(counts, [1, 2])
