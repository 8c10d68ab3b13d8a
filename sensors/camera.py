"""Cameras: the robot's RGB-D cameras and the fixed wall cameras, rendered by MuJoCo offscreen.

Rendering runs on MuJoCo's OpenGL renderer (EGL or OSMesa, chosen in sensors/__init__.py); where no GL context can
be made, on ray casting (``mj_multiRay`` from the camera, one ray per pixel, flat shading), and ``backend`` says
which ran. Shadows, reflections, the skybox, fog and multisampling are off: nothing here needs them and they cost.

Frames: MuJoCo's camera looks along its -z with y up; images and point clouds here use the optical frame (x right,
y down, z forward). Pixel (u, v) covers [u, u + 1) x [v, v + 1); its centre looks along ((u + 0.5 - cx) / f,
(v + 0.5 - cy) / f, 1) with f = (h / 2) / tan(fovy / 2), cx = w / 2, cy = h / 2 (MuJoCo's pinhole, square pixels).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import mujoco
import numpy as np

from pipeline.types import CameraFrame, DepthFrame

from . import body
from .scene import Scene

# Kinect depth noise after Khoshelham & Elberink 2012 (Sensors 12(2) 1437-1454): sigma_z = 1.425e-3 z^2 m, and
# depth quantized through the disparity, measured in 1/8 pixel by an IR camera of f = 580 px on a 7.5 cm baseline
KINECT_SIGMA = 1.425e-3  # 1/m
KINECT_FOCAL_PX = 580.0
KINECT_BASELINE = 0.075  # m
KINECT_SUBPIXEL = 8
MUJOCO_TO_OPTICAL = np.diag([1.0, -1.0, -1.0])  # MuJoCo camera axes (x right, y up, z back) -> optical
NEAR_CLIP, FAR_CLIP = 0.05, 200.0  # m, the GL clipping planes


@dataclass(frozen=True)
class Intrinsics:
    width: int
    height: int
    fovy_deg: float

    @property
    def f(self) -> float:
        return self.height / 2 / np.tan(np.radians(self.fovy_deg) / 2)

    @property
    def centre(self) -> tuple[float, float]:
        return self.width / 2, self.height / 2

    def pixel_directions(self) -> np.ndarray:
        """[h, w, 3] optical-frame directions through the pixel centres, z = 1."""
        cx, cy = self.centre
        u = (np.arange(self.width) + 0.5 - cx) / self.f
        v = (np.arange(self.height) + 0.5 - cy) / self.f
        uu, vv = np.meshgrid(u, v)
        return np.stack([uu, vv, np.ones_like(uu)], -1)

    def project(self, points: np.ndarray) -> np.ndarray:
        """Pixel coordinates [n, 2] (u, v) of optical-frame points [n, 3] in front of the camera."""
        cx, cy = self.centre
        return np.stack([cx + self.f * points[:, 0] / points[:, 2], cy + self.f * points[:, 1] / points[:, 2]], 1)


def camera_pose(scene: Scene, camera: str) -> tuple[np.ndarray, np.ndarray]:
    """The camera's position and optical-frame rotation (columns: right, down, forward) in the world."""
    cam = scene.model.camera(camera).id
    return scene.data.cam_xpos[cam].copy(), scene.data.cam_xmat[cam].reshape(3, 3) @ MUJOCO_TO_OPTICAL


class GLRenderer:
    """MuJoCo's offscreen OpenGL rendering for one camera size.

    One pass draws every geom in its id colour (MuJoCo's segmentation mode) and gives the z-depth and the geom
    segmentation together; colour images take a second pass in a scene of their own, so neither pass ever switches
    render state (which costs far more than a pass under Mesa).
    """

    def __init__(self, scene: Scene, intrinsics: Intrinsics, rgb: bool = False):
        self.backend = os.environ.get("MUJOCO_GL", "glfw")
        self.scene = scene
        m = scene.model
        self.shape = (intrinsics.height, intrinsics.width)
        self.context = mujoco.GLContext(intrinsics.width, intrinsics.height)
        self.context.make_current()
        # near and far clipping planes in metres (MuJoCo scales them by the model's extent)
        m.vis.map.znear, m.vis.map.zfar = NEAR_CLIP / m.stat.extent, FAR_CLIP / m.stat.extent
        self.mjr = mujoco.MjrContext(m, mujoco.mjtFontScale.mjFONTSCALE_100)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self.mjr)
        self.rect = mujoco.MjrRect(0, 0, intrinsics.width, intrinsics.height)
        self.option = mujoco.MjvOption()
        self.option.geomgroup[:] = 1  # body parts live in groups 1-3; MuJoCo shows only 0-2 by default
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self.ids = mujoco.MjvScene(m, maxgeom=m.ngeom + 100)
        self.colour = mujoco.MjvScene(m, maxgeom=m.ngeom + 100) if rgb else None
        for sc in (self.ids, self.colour):
            if sc is None:
                continue
            for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION,
                         mujoco.mjtRndFlag.mjRND_SKYBOX, mujoco.mjtRndFlag.mjRND_FOG):
                sc.flags[flag] = False
        self.ids.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
        self.ids.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        self._seg = np.empty((*self.shape, 3), np.uint8)
        self._depth = np.empty(self.shape, np.float32)

    def _draw(self, scene: mujoco.MjvScene, camera: str) -> None:
        self.camera.fixedcamid = self.scene.model.camera(camera).id
        mujoco.mjv_updateScene(self.scene.model, self.scene.data, self.option, None, self.camera,
                               mujoco.mjtCatBit.mjCAT_ALL, scene)
        mujoco.mjr_render(self.rect, scene, self.mjr)

    def render(self, camera: str, depth: bool = True, segmentation: bool = True, rgb: bool = False) -> dict:
        self.context.make_current()
        out = {}
        if depth or segmentation:
            self._draw(self.ids, camera)
            mujoco.mjr_readPixels(self._seg if segmentation else None, self._depth if depth else None, self.rect,
                                  self.mjr)
            if depth:
                # OpenGL's depth buffer b in [0, 1] is 1/z mapped from [1/near, 1/far]:
                # z = near far / (far - b (far - near)); b = 1 where nothing was drawn
                m = self.scene.model
                near, far = m.vis.map.znear * m.stat.extent, m.vis.map.zfar * m.stat.extent
                b = self._depth[::-1].astype(np.float64)
                z = near * far / (far - b * (far - near))
                out["depth"] = np.where(b < 1.0, z, np.inf).astype(np.float32)
            if segmentation:
                code = self._seg[::-1].astype(np.int64)
                segid = code[..., 0] + (code[..., 1] << 8) + (code[..., 2] << 16)  # 0: background, k + 1: geom k
                lookup = np.full(self.ids.ngeom + 1, -1, np.int64)
                for k in range(self.ids.ngeom):
                    g = self.ids.geoms[k]
                    if g.segid >= 0 and g.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                        lookup[g.segid + 1] = g.objid
                out["geom"] = lookup[np.minimum(segid, self.ids.ngeom)]
        if rgb:
            if self.colour is None:
                raise ValueError("this renderer was made without colour")
            self._draw(self.colour, camera)
            image = np.empty((*self.shape, 3), np.uint8)
            mujoco.mjr_readPixels(image, None, self.rect, self.mjr)
            out["rgb"] = image[::-1].copy()
        return out


class RaycastRenderer:
    """The fallback without OpenGL: one ray per pixel from the camera, flat colours shaded by the surface angle."""

    backend = "raycast"

    def __init__(self, scene: Scene, intrinsics: Intrinsics, exclude_body: int = -1):
        self.scene = scene
        self.exclude_body = exclude_body
        dirs = intrinsics.pixel_directions().reshape(-1, 3)
        self.z_per_metre = 1.0 / np.linalg.norm(dirs, axis=1)  # z-depth per metre along a pixel's ray
        self.unit = dirs * self.z_per_metre[:, None]
        self.shape = (intrinsics.height, intrinsics.width)

    def render(self, camera: str, depth: bool = True, segmentation: bool = True, rgb: bool = False) -> dict:
        m, d = self.scene.model, self.scene.data
        origin, rot = camera_pose(self.scene, camera)
        vec = self.unit @ rot.T
        n = len(vec)
        geom, dist, normal = np.zeros(n, np.int32), np.zeros(n), np.zeros(3 * n)
        mujoco.mj_multiRay(m, d, origin, vec.ravel(), None, 1, self.exclude_body, geom, dist, normal, n, 1e4)
        hit = dist >= 0
        out = {}
        if depth:
            out["depth"] = np.where(hit, dist * self.z_per_metre, np.inf).reshape(self.shape).astype(np.float32)
        if segmentation:
            out["geom"] = np.where(hit, geom, -1).reshape(self.shape)
        if rgb:
            shade = 0.35 + 0.65 * np.abs(np.einsum("ij,ij->i", normal.reshape(-1, 3), vec))
            colour = np.where(hit[:, None], m.geom_rgba[np.maximum(geom, 0), :3] * shade[:, None], 0.0)
            out["rgb"] = (255 * np.clip(colour, 0, 1)).astype(np.uint8).reshape(*self.shape, 3)
        return out


def make_renderer(scene: Scene, intrinsics: Intrinsics, exclude_body: int = -1, rgb: bool = False):
    """MuJoCo's GL renderer where a context can be made, else ray casting."""
    if os.environ.get("MUJOCO_GL", "") not in ("disable", "disabled", "off", "false", "0"):
        try:
            return GLRenderer(scene, intrinsics, rgb)
        except Exception:  # no usable GL context: fall back, and the backend name says so
            pass
    return RaycastRenderer(scene, intrinsics, exclude_body)


def kinect_noise(depth: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Khoshelham & Elberink's Kinect depth error: Gaussian with sigma 1.425e-3 z^2, then quantization of the
    disparity to 1/8 pixel."""
    seen = np.isfinite(depth)
    noisy = np.where(seen, depth, 0.0) + rng.standard_normal(depth.shape) * (KINECT_SIGMA * np.where(seen, depth, 0.0) ** 2)
    fb = KINECT_FOCAL_PX * KINECT_BASELINE * KINECT_SUBPIXEL
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(seen, fb / np.round(fb / noisy), np.inf).astype(np.float32)


class DepthCamera:
    """An RGB-D camera on the robot: z-depth with Kinect noise, a point cloud, segmentation, optional colour."""

    def __init__(self, params: dict, scene: Scene, rng: np.random.Generator):
        self.p = params
        self.name = params["name"]
        self.scene = scene
        self.rng = rng
        self.intrinsics = Intrinsics(params["width"], params["height"], params["fovy_deg"])
        self.period = 1.0 / params["rate"]
        self.renderer = make_renderer(scene, self.intrinsics, scene.robot_body, params["rgb"])
        self._rays = self.intrinsics.pixel_directions()

    @property
    def backend(self) -> str:
        return self.renderer.backend

    def capture(self, stamp: float) -> DepthFrame:
        """Render the scene as it was last synced."""
        out = self.renderer.render(self.name, depth=True, segmentation=True, rgb=self.p["rgb"])
        z = out["depth"]
        if self.p["noise"] == "kinect":
            z = kinect_noise(z, self.rng)
        valid = (z >= self.p["range_min"]) & (z <= self.p["range_max"])
        z = np.where(valid, z, np.nan).astype(np.float32)
        points = self._rays[valid] * z[valid][:, None]
        return DepthFrame(stamp, self.name, z, points, self.scene.person_of_geom(out["geom"]), out.get("rgb"))

    def visibility(self, frame: DepthFrame) -> tuple[np.ndarray, np.ndarray]:
        """Ids of the persons the image shows and the share of each that shows (the scene as at the capture)."""
        ids, _, _, fraction = person_boxes(self.scene, self.name, self.intrinsics, frame.person_id)
        return ids, fraction


class WallCamera:
    """A fixed camera: RGB and segmentation, and for every person in view the visible box and visible fraction."""

    def __init__(self, params: dict, scene: Scene):
        self.p = params
        self.name = params["name"]
        self.scene = scene
        self.intrinsics = Intrinsics(params["width"], params["height"], params["fovy_deg"])
        self.period = 1.0 / params["rate"]
        self.renderer = make_renderer(scene, self.intrinsics, rgb=params["rgb"])

    @property
    def backend(self) -> str:
        return self.renderer.backend

    def capture(self, stamp: float) -> CameraFrame:
        out = self.renderer.render(self.name, depth=False, segmentation=True, rgb=self.p["rgb"])
        seg = self.scene.person_of_geom(out["geom"])
        ids, boxes, full_boxes, fraction = person_boxes(self.scene, self.name, self.intrinsics, seg)
        return CameraFrame(stamp, self.name, out.get("rgb"), seg, ids, boxes, full_boxes, fraction)


def person_boxes(scene: Scene, camera: str, intrinsics: Intrinsics, seg: np.ndarray):
    """For every person a segmentation image shows: id, box around the visible pixels, box around the person as it
    would show with nobody and nothing in front and no image border (so it may reach outside the image), and the
    share of those pixels that show."""
    ids, counts = np.unique(seg[seg >= 0], return_counts=True)
    boxes = np.zeros((len(ids), 4))
    for k, pid in enumerate(ids):
        v, u = np.nonzero(seg == pid)
        boxes[k] = u.min(), v.min(), u.max() + 1, v.max() + 1
    full_boxes, full_counts = silhouettes(scene, camera, intrinsics, ids)
    return ids, boxes, full_boxes, np.minimum(counts / np.maximum(full_counts, 1), 1.0)


def silhouettes(scene: Scene, camera: str, intrinsics: Intrinsics, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Box and pixel count of each person (by id) as it would show with nobody and nothing in front: every pixel
    of the person's bounding box ray-cast against that person's own torso, head and legs."""
    origin, rot = camera_pose(scene, camera)
    k = intrinsics
    boxes, counts = np.zeros((len(ids), 4)), np.zeros(len(ids), np.int64)
    for row, pid in enumerate(ids):
        slot = int(np.flatnonzero(scene.slot_person_id == pid)[0])
        pixels = _box_pixels(scene, slot, origin, rot, k)
        if pixels is None:
            continue
        u, v = pixels
        dirs = np.stack([(u + 0.5 - k.centre[0]) / k.f, (v + 0.5 - k.centre[1]) / k.f, np.ones(len(u))], 1) @ rot.T
        hit = _hits_person(scene, slot, origin, dirs)
        if hit.any():
            boxes[row] = u[hit].min(), v[hit].min(), u[hit].max() + 1, v[hit].max() + 1
            counts[row] = hit.sum()
    return boxes, counts


def _box_pixels(scene: Scene, slot: int, origin: np.ndarray, rot: np.ndarray, k: Intrinsics):
    """The pixels of the box around the projection of the person's bounding box (None when behind the camera or
    out of the image)."""
    x, y = scene.person_xy[slot]
    reach = body.TORSO_RADIUS + body.LEG_LENGTH * np.sin(body.SWING_AMPLITUDE)
    corners = np.array([[x + sx * reach, y + sy * reach, z] for sx in (-1, 1) for sy in (-1, 1)
                        for z in (0.0, body.HEIGHT)])
    cam = (corners - origin) @ rot
    if (cam[:, 2] <= 1e-3).any():
        return None
    uv = k.project(cam)
    # not clipped to the image: a person cut by its border shows only part of the silhouette (within a margin of
    # one image size, which bounds the work for someone right in front of the lens)
    u0, v0 = np.maximum(np.floor(uv.min(axis=0)).astype(int), [-k.width, -k.height])
    u1, v1 = min(int(np.ceil(uv[:, 0].max())), 2 * k.width), min(int(np.ceil(uv[:, 1].max())), 2 * k.height)
    if u1 <= max(u0, 0) or v1 <= max(v0, 0) or u0 >= k.width or v0 >= k.height:
        return None
    vv, uu = np.mgrid[v0:v1, u0:u1]
    return uu.ravel(), vv.ravel()


def _hits_person(scene: Scene, slot: int, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Which rays from ``o`` along ``d`` [n, 3] meet the person's torso cylinder, head sphere or legs."""
    x, y = scene.person_xy[slot]
    hit = _ray_vertical_cylinder(o, d, np.array([x, y]), body.TORSO_RADIUS, body.TORSO_BOTTOM, body.TORSO_TOP)
    hit |= _ray_sphere(o, d, np.array([x, y, body.HEAD_CENTRE]), body.HEAD_RADIUS)
    for hip, foot in zip(scene.hips[slot], scene.feet[slot]):
        hit |= _ray_capsule(o, d, hip, foot, body.LEG_RADIUS)
    return hit


def _ray_vertical_cylinder(o, d, centre, r, z0, z1) -> np.ndarray:
    p = o[:2] - centre
    a = d[:, 0] ** 2 + d[:, 1] ** 2
    b = 2 * (d[:, :2] @ p)
    c = p @ p - r * r
    disc = b * b - 4 * a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        sq = np.sqrt(np.maximum(disc, 0.0))
        t0, t1 = (-b - sq) / (2 * a), (-b + sq) / (2 * a)
        flat = a < 1e-12  # a vertical ray: inside the circle or not at all
        t0 = np.where(flat, np.where(c <= 0, -np.inf, np.inf), t0)
        t1 = np.where(flat, np.where(c <= 0, np.inf, -np.inf), t1)
        za, zb = (z0 - o[2]) / d[:, 2], (z1 - o[2]) / d[:, 2]
        level = np.abs(d[:, 2]) < 1e-12
        tz0 = np.where(level, np.where((z0 <= o[2]) & (o[2] <= z1), -np.inf, np.inf), np.minimum(za, zb))
        tz1 = np.where(level, np.where((z0 <= o[2]) & (o[2] <= z1), np.inf, -np.inf), np.maximum(za, zb))
    enter = np.maximum(np.maximum(t0, tz0), 0.0)
    return (disc >= 0) & (enter <= np.minimum(t1, tz1))


def _ray_sphere(o, d, centre, r) -> np.ndarray:
    w = o - centre
    a = np.einsum("ij,ij->i", d, d)
    b = 2 * (d @ w)
    disc = b * b - 4 * a * (w @ w - r * r)
    return (disc >= 0) & (-b + np.sqrt(np.maximum(disc, 0.0)) >= 0)


def _ray_capsule(o, d, a, b, r) -> np.ndarray:
    """Rays within r of the segment a-b: the closest points of ray and segment, the ray's parameter kept >= 0."""
    e = b - a
    w0 = o - a
    A = np.einsum("ij,ij->i", d, d)
    B = d @ e
    C = e @ e
    D = d @ w0
    E = e @ w0
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.clip(np.where(A * C - B * B > 1e-12, (A * E - B * D) / (A * C - B * B), 0.0), 0.0, 1.0)
    t = np.maximum((B * s - D) / A, 0.0)
    s = np.clip((E + t * B) / C, 0.0, 1.0)
    gap = w0[None, :] + t[:, None] * d - s[:, None] * e[None, :]
    return np.einsum("ij,ij->i", gap, gap) <= r * r
