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

from pipeline.camera_geometry import floor_homography, image_to_floor
from pipeline.compiled import kernel
from pipeline.frames import inverse, rotation
from pipeline.params import REQUIRED, param
from pipeline.types import CameraFrame, DepthFrame

from . import body, bodycast
from .base import Periodic
from .scene import LEG_GROUP, PARTS, ROBOT_GROUP, STATIC_GROUP, TORSO_GROUP, Scene

MUJOCO_TO_OPTICAL = np.diag([1.0, -1.0, -1.0])  # MuJoCo camera axes (x right, y up, z back) -> optical
NEAR_CLIP, FAR_CLIP = 0.05, 200.0  # m, the GL clipping planes
OBJ_GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)  # a segmentation colour's object type when it shows a geom


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

    def rays(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Optical-frame directions [..., 3] (z = 1) through the centres of pixels (u, v)."""
        cx, cy = self.centre
        return np.stack([(u + 0.5 - cx) / self.f, (v + 0.5 - cy) / self.f, np.ones(np.shape(u))], -1)

    def pixel_directions(self) -> np.ndarray:
        """[h, w, 3] optical-frame directions through every pixel's centre, z = 1."""
        return self.rays(*np.meshgrid(np.arange(self.width), np.arange(self.height)))

    @property
    def camera_matrix(self) -> np.ndarray:
        """K, for pixel u covering [u, u + 1) (the convention of ``rays`` and ``project``)."""
        cx, cy = self.centre
        return np.array([[self.f, 0.0, cx], [0.0, self.f, cy], [0.0, 0.0, 1.0]])

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
    render state (which costs far more than a pass under Mesa). Colour and depth without segmentation take the
    colour pass alone. ``people=False`` draws the world without the people.

    ``fixed=True`` is for a camera that never moves (a wall camera) and draws no people: the world that never moves
    (floor, walls, obstacles) is drawn once per camera and kept, and each render draws the robot alone, reads back
    only the pixels its box covers and keeps those as near as the kept world's or nearer, as GL's depth test would
    have. That costs a quarter of drawing the whole view under Mesa. It gives depth and colour, not segmentation, and
    the same images as drawing the whole view but where the robot and the floor tie in depth (one pixel of 1,200
    frames of the airport's wall cameras, none of what a run writes).
    """

    def __init__(self, scene: Scene, intrinsics: Intrinsics, rgb: bool = False, people: bool = True,
                 range_max: float = np.inf, fixed: bool = False):
        if fixed and people:
            raise ValueError("a fixed camera's renderer draws no people (they would stay as drawn first)")
        self.backend = os.environ.get("MUJOCO_GL", "glfw")
        self.scene = scene
        self.intrinsics = intrinsics
        self.shape = (intrinsics.height, intrinsics.width)
        self.context = mujoco.GLContext(intrinsics.width, intrinsics.height)
        self.rect = mujoco.MjrRect(0, 0, intrinsics.width, intrinsics.height)
        self.option = mujoco.MjvOption()
        self.option.geomgroup[:] = 1  # body parts live in groups 1-3; MuJoCo shows only 0-2 by default
        self.option.geomgroup[TORSO_GROUP:LEG_GROUP + 1] = people
        self.people = people
        self.rgb = rgb
        self.range_max = range_max  # nothing wholly farther than this (z-depth) is drawn
        self.fixed = fixed
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self.mjr = None
        self._remake()
        self._seg = np.empty((*self.shape, 3), np.uint8)
        self._depth = np.empty(self.shape, np.float32)

    def _remake(self) -> None:
        """The GL context's model data and the scenes to draw, for the scene's current model (it is made anew
        when more persons come than it holds)."""
        m = self.scene.model
        self.version = self.scene.version
        self.context.make_current()
        # near and far clipping planes in metres (MuJoCo scales them by the model's extent)
        m.vis.map.znear, m.vis.map.zfar = NEAR_CLIP / m.stat.extent, FAR_CLIP / m.stat.extent
        self._clip = m.vis.map.znear * m.stat.extent, m.vis.map.zfar * m.stat.extent  # as MuJoCo holds them (float32)
        if self.mjr is not None:
            self.mjr.free()
        self.mjr = mujoco.MjrContext(m, mujoco.mjtFontScale.mjFONTSCALE_100)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self.mjr)
        # the corners of the walls and obstacles (boxes that never move), to leave out those outside the view
        boxes = np.flatnonzero((m.geom_type == mujoco.mjtGeom.mjGEOM_BOX) & (m.geom_bodyid == 0))
        d = mujoco.MjData(m)  # the world body's geoms placed (the scene may not have been synced yet)
        mujoco.mj_kinematics(m, d)
        self._walls = boxes
        self._wall_corners = geom_box_corners(m, d, boxes)
        self.ids = mujoco.MjvScene(m, maxgeom=m.ngeom + 100)
        self.colour = mujoco.MjvScene(m, maxgeom=m.ngeom + 100) if self.rgb else None
        for sc in (self.ids, self.colour):
            if sc is None:
                continue
            for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION,
                         mujoco.mjtRndFlag.mjRND_SKYBOX, mujoco.mjtRndFlag.mjRND_FOG):
                sc.flags[flag] = False
        self.ids.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
        self.ids.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        self._static = {}  # a fixed camera's world without the robot: colour and depth, by camera and colour or not

    def __del__(self):
        # GL object names belong to a context: the MjrContext must be freed with its own context current, or it
        # deletes whatever another renderer's context holds under the same names
        try:
            self.context.make_current()
            if self.mjr is not None:
                self.mjr.free()
            self.context.free()
        except Exception:  # interpreter shutdown: nothing left to free
            pass

    def _draw(self, scene: mujoco.MjvScene, camera: str) -> None:
        self.camera.fixedcamid = self.scene.model.camera(camera).id
        mujoco.mjv_updateScene(self.scene.model, self.scene.data, self.option, None, self.camera,
                               mujoco.mjtCatBit.mjCAT_ALL, scene)
        mujoco.mjr_render(self.rect, scene, self.mjr)

    def _frustum(self, camera: str, points: np.ndarray) -> np.ndarray:
        """Which groups of points [n, k, 3] (world) lie wholly outside one plane of the camera's view (behind it,
        beyond one side, or, for a depth camera, beyond its range)."""
        origin, rot = camera_pose(self.scene, camera)
        c = (points - origin) @ rot
        k = self.intrinsics
        tan_x, tan_y = k.width / 2 / k.f, k.height / 2 / k.f
        x, y, z = c[..., 0], c[..., 1], c[..., 2]
        return ((z < 0).all(axis=1) | (z > self.range_max).all(axis=1) | (x > z * tan_x).all(axis=1)
                | (-x > z * tan_x).all(axis=1) | (y > z * tan_y).all(axis=1) | (-y > z * tan_y).all(axis=1))

    def _out_of_view(self, camera: str) -> np.ndarray:
        """Geoms of the persons whose bounding sphere lies wholly outside the camera's view or beyond its range
        (where a depth camera measures nothing): drawing costs per geom under Mesa, wherever the geom lands, so
        these are hidden while the camera draws."""
        s = self.scene
        size = s.person_scale[:s.alive]
        centre = np.column_stack([s.person_xy[:s.alive], body.HEIGHT / 2 * size])
        origin, rot = camera_pose(s, camera)
        c = (centre - origin) @ rot
        k = self.intrinsics
        tan_x, tan_y = k.width / 2 / k.f, k.height / 2 / k.f
        r = (body.HEIGHT / 2 + body.LEG_LENGTH * np.sin(body.SWING_AMPLITUDE)) * size  # a sphere round each person
        outside = ((c[:, 2] < -r) | (c[:, 2] - r > self.range_max)
                   | (np.abs(c[:, 0]) - r * np.hypot(1, tan_x) > c[:, 2] * tan_x)
                   | (np.abs(c[:, 1]) - r * np.hypot(1, tan_y) > c[:, 2] * tan_y))
        return s.person_geoms(np.flatnonzero(outside))

    def render(self, camera: str, depth: bool = True, segmentation: bool = True, rgb: bool = False) -> dict:
        self.context.make_current()
        if self.version != self.scene.version:
            self._remake()
        hidden = np.concatenate([self._out_of_view(camera) if self.people else np.zeros(0, np.int64),
                                 self._walls[self._frustum(camera, self._wall_corners)]])
        alpha = self.scene.model.geom_rgba[hidden, 3].copy()
        self.scene.model.geom_rgba[hidden, 3] = 0.0
        try:
            return self._render(camera, depth, segmentation, rgb)
        finally:
            self.scene.model.geom_rgba[hidden, 3] = alpha

    def _render(self, camera: str, depth: bool, segmentation: bool, rgb: bool) -> dict:
        if self.fixed:
            if segmentation:
                raise ValueError("a fixed camera's renderer gives depth and colour, not segmentation")
            out = self._over_static(camera, rgb)
            return out if depth else {"rgb": out["rgb"]}
        out = {}
        if rgb:
            if self.colour is None:
                raise ValueError("this renderer was made without colour")
            self._draw(self.colour, camera)
            image = np.empty((*self.shape, 3), np.uint8)
            mujoco.mjr_readPixels(image, self._depth if depth and not segmentation else None, self.rect, self.mjr)
            out["rgb"] = image[::-1].copy()
        if segmentation or (depth and not rgb):
            self._draw(self.ids, camera)
            mujoco.mjr_readPixels(self._seg if segmentation else None, self._depth if depth else None, self.rect,
                                  self.mjr)
        if depth:
            out["depth"] = self._z(self._depth[::-1])
        if segmentation:
            code = self._seg[::-1].astype(np.int64)
            segid = code[..., 0] + (code[..., 1] << 8) + (code[..., 2] << 16)  # 0: background, k + 1: geom k
            n = self.ids.ngeom
            # the scene's geoms' (segid, object type, object id), read in one pass: each attribute read through the
            # bindings costs about 0.1 us, and comparing with MuJoCo's enum 1 us (176 us a frame before, 48 now)
            found = np.array([(g.segid, int(g.objtype), g.objid) for g in self.ids.geoms[:n]], np.int64).reshape(-1, 3)
            drawn = (found[:, 0] >= 0) & (found[:, 1] == OBJ_GEOM)
            lookup = np.full(n + 1, -1, np.int64)
            lookup[found[drawn, 0] + 1] = found[drawn, 2]
            out["geom"] = lookup[np.minimum(segid, n)]
        return out

    def _z(self, b: np.ndarray) -> np.ndarray:
        """z-depth in metres of OpenGL depth buffer values b in [0, 1], which are 1/z mapped from [1/near, 1/far]:
        z = near far / (far - b (far - near)); inf where nothing was drawn (b = 1)."""
        near, far = self._clip
        return _gl_depth(np.atleast_2d(b), near * far, far, far - near).reshape(b.shape)

    def _over_static(self, camera: str, rgb: bool) -> dict:
        """A fixed camera's depth and colour: the world without the robot as drawn once, and the robot drawn over
        it."""
        scene, groups = self.colour if rgb else self.ids, self.option.geomgroup
        if (camera, rgb) not in self._static:
            groups[ROBOT_GROUP] = 0
            self._draw(scene, camera)
            groups[ROBOT_GROUP] = 1
            image = np.zeros((*self.shape, 3), np.uint8)
            mujoco.mjr_readPixels(image if rgb else None, self._depth, self.rect, self.mjr)
            buffer = self._depth[::-1].copy()  # GL's rows run bottom-up
            self._static[camera, rgb] = image[::-1].copy(), buffer, self._z(buffer)
        static_image, static_buffer, static_z = self._static[camera, rgb]
        out = {"depth": static_z.copy(), "rgb": static_image.copy() if rgb else None}
        box = robot_box(self.scene, camera, self.intrinsics)
        if box is not None:
            u0, v0, u1, v1 = box
            groups[STATIC_GROUP] = 0
            self._draw(scene, camera)
            groups[STATIC_GROUP] = 1
            image = np.zeros((v1 - v0, u1 - u0, 3), np.uint8)
            buffer = np.empty((v1 - v0, u1 - u0), np.float32)
            mujoco.mjr_readPixels(image if rgb else None, buffer,
                                  mujoco.MjrRect(u0, self.shape[0] - v1, u1 - u0, v1 - v0), self.mjr)
            image, buffer = image[::-1], buffer[::-1]
            # GL's depth test passes a pixel as near as the one drawn (MuJoCo's LEQUAL), and the robot came after the
            # walls and floor, so it wins their ties
            nearer = (buffer < 1.0) & (buffer <= static_buffer[v0:v1, u0:u1])
            out["depth"][v0:v1, u0:u1][nearer] = self._z(buffer[nearer])
            if rgb:
                out["rgb"][v0:v1, u0:u1][nearer] = image[nearer]
        return out


@kernel
def _gl_depth(b, near_far, far, far_minus_near):
    """``GLRenderer._z`` on the rows of b [r, c] (float32), in float64 as written there, rounded to float32."""
    out = np.empty(b.shape, np.float32)
    for i in range(b.shape[0]):
        for j in range(b.shape[1]):
            x = np.float64(b[i, j])
            out[i, j] = np.float32(near_far / (far - x * far_minus_near)) if x < 1.0 else np.inf
    return out


def geom_box_corners(m: mujoco.MjModel, d: mujoco.MjData, geoms: np.ndarray) -> np.ndarray:
    """The corners [n, 8, 3] in the world of the bounding boxes of ``geoms`` (MuJoCo's ``geom_aabb``, in each geom's
    frame; a box geom's is the box)."""
    aabb = m.geom_aabb[geoms]  # centre and half sizes
    local = aabb[:, None, :3] + bodycast.UNIT_BOX[None] * aabb[:, None, 3:]
    return d.geom_xpos[geoms][:, None] + np.einsum("nij,nkj->nki", d.geom_xmat[geoms].reshape(-1, 3, 3), local)


def robot_box(scene: Scene, camera: str, intrinsics: Intrinsics) -> tuple[int, int, int, int] | None:
    """The pixels [u0, u1) x [v0, v1) the robot can cover in ``camera``: round the projections of its geoms'
    bounding boxes, a pixel wider each side (the whole image when part of a box lies behind the camera); None where
    it lies outside the view."""
    m, d = scene.model, scene.data
    geoms = np.flatnonzero(m.geom_bodyid == scene.robot_body)
    corners = geom_box_corners(m, d, geoms)
    origin, rot = camera_pose(scene, camera)
    c = ((corners - origin) @ rot).reshape(-1, 3)
    k = intrinsics
    if (c[:, 2] <= NEAR_CLIP).all():
        return None
    if (c[:, 2] <= NEAR_CLIP).any():
        return 0, 0, k.width, k.height
    uv = k.project(c)
    u0, v0 = np.maximum(np.floor(uv.min(axis=0)).astype(int) - 1, 0)
    u1, v1 = np.minimum(np.ceil(uv.max(axis=0)).astype(int) + 1, [k.width, k.height])
    return (int(u0), int(v0), int(u1), int(v1)) if u0 < u1 and v0 < v1 else None


class RaycastRenderer:
    """The fallback without OpenGL: one ray per pixel from the camera, flat colours shaded by the surface angle.

    ``fixed=True``, for a camera that never moves and sees no people, casts the world that never moves once and
    after that only the rays of the pixels the robot can cover, against the robot, as ``GLRenderer`` draws it."""

    backend = "raycast"

    def __init__(self, scene: Scene, intrinsics: Intrinsics, exclude_body: int = -1, people: bool = True,
                 fixed: bool = False):
        self.scene = scene
        self.intrinsics = intrinsics
        self.exclude_body = exclude_body
        self.groups = np.ones(6, np.uint8)  # MuJoCo's include mask over geom groups
        self.groups[TORSO_GROUP:LEG_GROUP + 1] = people
        if fixed and people:
            raise ValueError("a fixed camera's renderer draws no people (they would stay as cast first)")
        self.fixed = fixed
        self._static = {}  # a fixed camera's casts without the robot (geom, distance, normal), by camera
        self._version = scene.version  # the model the casts were made in
        dirs = intrinsics.pixel_directions().reshape(-1, 3)
        self.z_per_metre = 1.0 / np.linalg.norm(dirs, axis=1)  # z-depth per metre along a pixel's ray
        self.unit = dirs * self.z_per_metre[:, None]
        self.shape = (intrinsics.height, intrinsics.width)

    def _cast(self, origin: np.ndarray, vec: np.ndarray, groups: np.ndarray):
        """Geom, distance (-1: no hit) and normal [n, 3] of each ray."""
        n = len(vec)
        geom, dist, normal = np.zeros(n, np.int32), np.zeros(n), np.zeros(3 * n)
        self.scene.cast(origin, vec, groups, self.exclude_body, 1e4, geom, dist, normal)
        return geom, dist, normal.reshape(-1, 3)

    def _over_static(self, camera: str, origin: np.ndarray, vec: np.ndarray):
        """A fixed camera's casts: the world without the robot as cast once, the robot's where it is nearer."""
        if self._version != self.scene.version:  # a model made anew numbers its geoms anew
            self._static, self._version = {}, self.scene.version
        if camera not in self._static:
            self._static[camera] = self._cast(origin, vec, np.where(np.arange(6) == ROBOT_GROUP, 0, self.groups))
        geom, dist, normal = (a.copy() for a in self._static[camera])
        box = robot_box(self.scene, camera, self.intrinsics)
        if box is not None:
            u0, v0, u1, v1 = box
            rows = (np.arange(v0, v1)[:, None] * self.shape[1] + np.arange(u0, u1)).ravel()
            robot = np.zeros(6, np.uint8)
            robot[ROBOT_GROUP] = 1
            g, r, nr = self._cast(origin, vec[rows], robot)
            # a tie goes to the geom first in the model, as in one cast
            nearer = (r >= 0) & ((r < dist[rows]) | (dist[rows] < 0))
            geom[rows[nearer]], dist[rows[nearer]], normal[rows[nearer]] = g[nearer], r[nearer], nr[nearer]
        return geom, dist, normal

    def render(self, camera: str, depth: bool = True, segmentation: bool = True, rgb: bool = False) -> dict:
        m = self.scene.model
        origin, rot = camera_pose(self.scene, camera)
        vec = self.unit @ rot.T
        geom, dist, normal = (self._over_static(camera, origin, vec) if self.fixed
                              else self._cast(origin, vec, self.groups))
        hit = dist >= 0
        out = {}
        if depth:
            out["depth"] = np.where(hit, dist * self.z_per_metre, np.inf).reshape(self.shape).astype(np.float32)
        if segmentation:
            out["geom"] = np.where(hit, geom, -1).reshape(self.shape)
        if rgb:
            colour = shade(m.geom_rgba[np.maximum(geom, 0), :3], normal, vec)
            out["rgb"] = np.where(hit[:, None], colour, 0).astype(np.uint8).reshape(*self.shape, 3)
        return out


@kernel
def _light(normal, view, p):
    """The light at a surface of unit normal ``normal[p]`` seen along ``view[p]`` (any length) from a light at the
    eye: 0.35 of the colour edge-on, all of it facing the eye."""
    nx, ny, nz, vx, vy, vz = normal[p, 0], normal[p, 1], normal[p, 2], view[p, 0], view[p, 1], view[p, 2]
    facing = abs(nx * vx + ny * vy + nz * vz) / max(np.sqrt(vx * vx + vy * vy + vz * vz), 1e-12)
    return 0.35 + 0.65 * facing


@kernel
def shade(colour: np.ndarray, normal: np.ndarray, view: np.ndarray) -> np.ndarray:
    """Flat colours [n, 3] in [0, 1] lit by a light at the eye (bright where the surface faces the ray ``view``),
    as 8-bit RGB."""
    out = np.empty((len(colour), 3), np.uint8)
    for p in range(len(colour)):
        light = _light(normal, view, p)
        for c in range(3):
            out[p, c] = np.uint8(255 * min(max(colour[p, c] * light, 0.0), 1.0))
    return out


@kernel
def _shade_people(rgb, pixel, owner, part, palette, normal, view):
    """``shade`` of each person's pixel (at ``pixel`` of the flattened image ``rgb`` [h w, 3], written there in
    turn) in the colour of its part from the owner's ``palette`` [n, 4, 3], looked up here rather than gathered."""
    for h in range(len(pixel)):
        light = _light(normal, view, h)
        for c in range(3):
            rgb[pixel[h], c] = np.uint8(255 * min(max(palette[owner[h], part[h], c] * light, 0.0), 1.0))


def make_renderer(scene: Scene, intrinsics: Intrinsics, exclude_body: int = -1, rgb: bool = False,
                  people: bool = True, range_max: float = np.inf, fixed: bool = False):
    """MuJoCo's GL renderer where a context can be made, else ray casting."""
    if os.environ.get("MUJOCO_GL", "") not in ("disable", "disabled", "off", "false", "0"):
        try:
            return GLRenderer(scene, intrinsics, rgb, people, range_max, fixed)
        except Exception:  # no usable GL context: fall back, and the backend name says so
            pass
    return RaycastRenderer(scene, intrinsics, exclude_body, people, fixed)


def kinect_noise(depth: np.ndarray, rng: np.random.Generator, camera: DepthCamera) -> np.ndarray:
    """The depth error of a structured-light camera after Khoshelham & Elberink 2012 (Sensors 12(2) 1437-1454):
    Gaussian with sigma ``noise_sigma`` z^2, then the depth quantized through the disparity, measured in steps of
    1 / ``disparity_subpixel`` pixel by an IR camera of focal length ``ir_focal_px`` on a baseline ``ir_baseline``
    (the camera's scenario keys; the Kinect's by default). One standard normal draw per pixel, seen or not."""
    draws = rng.standard_normal(depth.shape)
    if depth.dtype != np.float32:
        raise ValueError(f"depth must be float32 (as rendered), not {depth.dtype}")
    fb = camera.ir_focal_px * camera.ir_baseline * camera.disparity_subpixel
    return _kinect(depth.ravel(), draws.ravel(), np.float32(camera.noise_sigma), fb).reshape(depth.shape)


@kernel
def _kinect(depth, draws, sigma, fb):
    """``kinect_noise`` on the float32 depths (inf: nothing seen) and their draws: sigma z^2 in float32 (as numpy
    takes a float32 array times a Python float), the noisy depth and its quantization in float64, rounding half to
    even; inf where nothing was seen."""
    out = np.empty(len(depth), np.float32)
    for i in range(len(depth)):
        z = depth[i]
        if np.isfinite(z):
            noisy = np.float64(z) + draws[i] * np.float64(sigma * z * z)
            out[i] = np.float32(fb / np.round(fb / noisy))
        else:
            out[i] = np.inf
    return out


def measured(z: np.ndarray, rays: np.ndarray, range_min: float, range_max: float) -> tuple[np.ndarray, np.ndarray]:
    """The depth camera's float32 z-depths [h, w] with NaN outside [range_min, range_max] (compared in float32, as
    numpy compares a float32 array with a Python float), and the valid pixels' points [n, 3]: their rays [h, w, 3]
    (z = 1) scaled by the depth, row by row."""
    if z.dtype != np.float32 or rays.shape != (*z.shape, 3):
        raise ValueError(f"z must be float32 [h, w] and rays [h, w, 3], not {z.dtype} {z.shape} and {rays.shape}")
    depth, points = _measured(z.ravel(), np.ascontiguousarray(rays, np.float64).reshape(-1, 3), np.float32(range_min),
                              np.float32(range_max))
    return depth.reshape(z.shape), points


@kernel
def _measured(z, rays, range_min, range_max):
    """``measured`` on the flattened image."""
    depth = np.empty(len(z), np.float32)
    valid = 0
    for i in range(len(z)):
        if z[i] >= range_min and z[i] <= range_max:
            depth[i] = z[i]
            valid += 1
        else:
            depth[i] = np.nan
    points = np.empty((valid, 3))
    k = 0
    for i in range(len(z)):
        if depth[i] == depth[i]:
            scale = np.float64(depth[i])
            points[k, 0], points[k, 1], points[k, 2] = rays[i, 0] * scale, rays[i, 1] * scale, rays[i, 2] * scale
            k += 1
    return depth, points


class CameraSensor(Periodic):
    """What the two cameras share as ``Sensor``s (sensors/base.py): where the robot believes they are, and who has
    the middle of their body in the image."""

    name: str
    scene: Scene
    intrinsics: Intrinsics
    range_max = np.inf  # m: the depth camera's range; a wall camera's reaches as far as it sees

    def pose_in_odom(self, world) -> np.ndarray:
        """The optical frame in odom (a 4x4 transform), placed through the robot's localisation in the map (the true
        world_T_odom, as the route driver steers by): for a camera on the robot, its mount on the odometry pose."""
        origin, rot = camera_pose(self.scene, self.name)
        odom_T_world = inverse(world.robot.world_T_odom)
        odom_R_world = rotation(odom_T_world, 3)
        pose = np.eye(4)
        pose[:3, :3] = odom_R_world @ rot
        pose[:3, 3] = odom_R_world @ origin + [*odom_T_world[:2], 0.0]
        return pose

    def shown(self, world, frame: DepthFrame | CameraFrame) -> tuple[np.ndarray, np.ndarray]:
        """Each person's visible share, and whether the middle of their body (1 m up) is in the image within the
        camera's range."""
        agents = world.agents()
        n = len(agents.id)
        origin, rot = camera_pose(self.scene, self.name)
        cam = (np.column_stack([agents.position, np.full(n, 1.0)]) - origin) @ rot
        ahead = (cam[:, 2] > 0.05) & (cam[:, 2] <= self.range_max)
        size = self.intrinsics
        uv = size.project(np.where(ahead[:, None], cam, [0.0, 0.0, 1.0]))
        in_view = ahead & (uv >= 0).all(axis=1) & (uv[:, 0] < size.width) & (uv[:, 1] < size.height)
        return on_persons(agents.id, frame.ids, frame.visible_fraction), in_view


def on_persons(agent_ids: np.ndarray, ids: np.ndarray, values: np.ndarray, missing=0.0) -> np.ndarray:
    """``values`` of persons ``ids`` laid out over ``agent_ids`` (sorted); ``missing`` for those not among them."""
    out = np.full(len(agent_ids), missing, np.result_type(missing, np.asarray(values)))
    rows = np.searchsorted(agent_ids, ids)
    keep = rows < len(agent_ids)  # and, below, the person found there (nobody is found among no one)
    keep[keep] = agent_ids[rows[keep]] == ids[keep]
    out[rows[keep]] = np.asarray(values)[keep]
    return out


@dataclass(kw_only=True, eq=False)
class DepthCamera(CameraSensor):
    """An RGB-D camera on the robot: z-depth with Kinect noise, a point cloud, segmentation, optional colour. Made as
    ``DepthCamera(scene=..., rng=..., **params)``; the scenario format fills the values of a ``preset`` in."""

    name: str = param(REQUIRED, "the camera's optical frame name", kind="str")
    preset: str | None = param(None, "a camera model whose values fill the keys not given", kind="str")
    position: list = param([0.45, 0.0, 1.45], "m, in base_link (SPENCER: RGB-D cameras at head height, front and "
                                              "rear)", kind="point3")
    yaw: float = param(0.0, "rad, viewing direction in base_link (pi: looking backwards)")
    pitch: float = param(0.0, "rad, tilt down (positive) or up", min=-1.57, max=1.57)
    width: int = param(160, "pixels", min=8, max=4096)
    height: int = param(120, "pixels", min=8, max=4096)
    fovy_deg: float = param(43.0, "deg, vertical field of view (Kinect: 43)", min=1.0, max=170.0)
    range_min: float = param(0.5, "m, nearer depths read NaN (Kinect: 0.5)", min=0.0)
    range_max: float = param(8.0, "m, farther depths read NaN (Kinect: ~8)", min=0.0, exclusive_min=True)
    rate: float = param(15.0, "Hz, at most 1 / dt", min=0.0, exclusive_min=True)
    noise: str = param("kinect", "kinect: Gaussian depth noise, then depth quantized through the disparity (the keys "
                                 "below)", choices=("kinect", "none"))
    noise_sigma: float = param(1.425e-3, "1/m, the noise's sigma per z^2 (Khoshelham & Elberink 2012: 1.425e-3)",
                               min=0.0)
    ir_focal_px: float = param(580.0, "px, focal length of the IR camera the disparity is measured in (Kinect: 580)",
                               min=0.0, exclusive_min=True)
    ir_baseline: float = param(0.075, "m, IR projector to IR camera (Kinect: 0.075)", min=0.0, exclusive_min=True)
    disparity_subpixel: int = param(8, "disparity steps per pixel (Kinect: 8, a 1/8-pixel step)", min=1)
    rgb: bool = param(False, "render a colour image too (a second pass)")
    scene: Scene
    rng: np.random.Generator

    def __post_init__(self):
        self.intrinsics = Intrinsics(self.width, self.height, self.fovy_deg)
        self.period = 1.0 / self.rate
        # beyond its range a depth camera measures nothing, so nothing there need be drawn, unless it takes colour
        self.renderer = make_renderer(self.scene, self.intrinsics, self.scene.robot_body, self.rgb,
                                      range_max=np.inf if self.rgb else self.range_max)
        self._rays = self.intrinsics.pixel_directions()

    @property
    def backend(self) -> str:
        return self.renderer.backend

    def capture(self, world, stamp: float) -> DepthFrame:
        """The image of ``world`` now, its pose in odom and its ground truth (``visibility``) filled in."""
        self.scene.follow(world)
        image = self.render(stamp)
        image.pose = self.pose_in_odom(world)
        return self.visibility(image)

    def render(self, stamp: float) -> DepthFrame:
        """Render the scene as it was last synced."""
        out = self.renderer.render(self.name, depth=True, segmentation=True, rgb=self.rgb)
        z = out["depth"]
        if self.noise == "kinect":
            z = kinect_noise(z, self.rng, self)
        z, points = measured(z, self._rays, self.range_min, self.range_max)
        # person ids where the camera measured something: beyond its range it sees no one (and the GL renderer
        # does not even draw people there)
        person = np.where(np.isnan(z), -1, self.scene.person_of_geom(out["geom"]))
        return DepthFrame(stamp, self.name, z, points, person, out.get("rgb"),
                          camera_matrix=self.intrinsics.camera_matrix)

    def visibility(self, frame: DepthFrame) -> DepthFrame:
        """``frame`` with its ground truth filled in: the persons the image shows, their visible and unoccluded boxes
        and the share of each that shows (the scene as at the capture)."""
        frame.ids, frame.boxes, frame.full_boxes, frame.visible_fraction = person_boxes(
            self.scene, self.name, self.intrinsics, frame.person_id)
        return frame


@dataclass(kw_only=True, eq=False)
class WallCamera(CameraSensor):
    """A fixed camera: RGB and segmentation, and for every person in view the visible box and visible fraction. Made
    as ``WallCamera(scene=..., **params)``.

    The renderer draws the world without the people (walls, obstacles, the robot; the walls once, as the camera is
    fixed); the people are then ray-cast exactly (sensors/bodycast.py) on the pixels their boxes cover and drawn in
    where they are nearer than the world. That casting gives every person's unoccluded silhouette as well, and costs
    a fraction of drawing them under Mesa.
    """

    name: str = param(REQUIRED, "the camera's frame name", kind="str")
    position: list = param(REQUIRED, "m, in the world", kind="point3")
    yaw: float = param(0.0, "rad, viewing direction in the world")
    pitch: float = param(0.5, "rad, tilt down (positive)", min=-1.57, max=1.57)
    width: int = param(320, "pixels (seed 001: flea2 cameras, up to 640 x 480)", min=8, max=4096)
    height: int = param(240, "pixels", min=8, max=4096)
    fovy_deg: float = param(45.0, "deg, vertical field of view", min=1.0, max=170.0)
    rate: float = param(10.0, "Hz, at most 1 / dt", min=0.0, exclusive_min=True)
    rgb: bool = param(True, "render a colour image (the segmentation and boxes come without it)")
    scene: Scene

    def __post_init__(self):
        self.intrinsics = Intrinsics(self.width, self.height, self.fovy_deg)
        self.period = 1.0 / self.rate
        self.renderer = make_renderer(self.scene, self.intrinsics, rgb=self.rgb, people=False, fixed=True)

    @property
    def backend(self) -> str:
        return self.renderer.backend

    @property
    def camera_matrix(self) -> np.ndarray:
        return self.intrinsics.camera_matrix

    def world_pose(self) -> np.ndarray:
        """The optical frame in the world, a 4x4 transform."""
        origin, rot = camera_pose(self.scene, self.name)
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = rot, origin
        return pose

    def ground_homography(self) -> np.ndarray:
        """The 3x3 calibration that maps floor points (x, y, 1) in the world to image points (u, v, 1) up to scale
        (``pipeline.camera_geometry``)."""
        return floor_homography(self.camera_matrix, self.world_pose())

    def image_to_ground(self, uv: np.ndarray) -> np.ndarray:
        """Floor points [n, 2] in the world seen at image points ``uv`` [n, 2] (NaN above the horizon)."""
        return image_to_floor(self.camera_matrix, self.world_pose(), uv)

    def capture(self, world, stamp: float) -> CameraFrame:
        """The image of ``world`` now, with its pose in odom and the robot's odometry position (for a detector that
        tells the robot from people)."""
        self.scene.follow(world)
        image = self.render(stamp)
        image.pose = self.pose_in_odom(world)
        image.robot_position = world.robot.odom_pose[:2].copy()
        return image

    def render(self, stamp: float) -> CameraFrame:
        """Render the scene as it was last synced."""
        s, k = self.scene, self.intrinsics
        world = self.renderer.render(self.name, depth=True, segmentation=False, rgb=self.rgb)
        slots = np.arange(s.alive)
        owner, u, v, z, part, weight = person_pixels(s, self.name, k, slots)
        pixel = v * k.width + u
        shows = _in_front(world["depth"].ravel(), pixel, z, weight == 1.0)
        seg = np.full(k.width * k.height, -1, np.int64)
        seg[pixel[shows]] = s.slot_person_id[slots[owner[shows]]]
        rgb = world.get("rgb")
        if rgb is not None:
            origin, rot = camera_pose(s, self.name)
            view = k.rays(u[shows], v[shows]) @ rot.T
            sl, pt = slots[owner[shows]], part[shows]
            surface = bodycast.normals(s, sl, pt, origin + z[shows, None] * view)
            palette = bodycast.colours(s.slot_person_id[slots])  # [n, 4, 3]: each person's parts' colours
            _shade_people(rgb.reshape(-1, 3), pixel[shows], owner[shows], pt, palette, surface, view)
        # per person: the pixels that show against all of the silhouette's
        full = np.bincount(owner, weights=weight, minlength=len(slots))
        seen = np.bincount(owner[shows], minlength=len(slots))
        ids = np.flatnonzero(seen)
        remap = np.full(len(slots), -1)
        remap[ids] = np.arange(len(ids))
        order = np.argsort(s.slot_person_id[slots[ids]])  # by person id, as the segmentation's unique ids come
        boxes = _boxes_of(remap[owner[shows]], u[shows], v[shows], len(ids))[order]
        keep = remap[owner] >= 0
        full_boxes = _boxes_of(remap[owner[keep]], u[keep], v[keep], len(ids))[order]
        fraction = np.minimum(seen[ids] / np.maximum(full[ids], 1), 1.0)[order]
        return CameraFrame(stamp, self.name, rgb, seg.reshape(k.height, k.width), s.slot_person_id[slots[ids]][order],
                           boxes, full_boxes, fraction, self.camera_matrix)


@kernel
def _in_front(world_depth, pixel, z, inside):
    """Which silhouette pixels (at ``pixel`` of the image, z-depth ``z``, in the image where ``inside``) show: those
    nearer than the world there and as near as the nearest person's there, in their order."""
    nearest = np.full(len(world_depth), np.inf, np.float32)
    for h in range(len(z)):
        if inside[h] and z[h] < world_depth[pixel[h]] and z[h] < nearest[pixel[h]]:
            nearest[pixel[h]] = z[h]
    count = 0
    for h in range(len(z)):
        count += inside[h] and z[h] < world_depth[pixel[h]] and z[h] == nearest[pixel[h]]
    shows = np.empty(count, np.int64)
    count = 0
    for h in range(len(z)):
        if inside[h] and z[h] < world_depth[pixel[h]] and z[h] == nearest[pixel[h]]:
            shows[count] = h
            count += 1
    return shows


def person_pixels(scene: Scene, camera: str, intrinsics: Intrinsics, slots: np.ndarray):
    """Every pixel of each person's silhouette as it would show with nobody and nothing in front and no image
    border: each part of the body ray-cast on the pixels of its projected bounding box, the nearest part kept
    (``bodycast.nearest_parts``).

    Returns the hits as ``owner`` (index into ``slots``), ``u``, ``v``, z-depth, body part, and the weight each
    stands for: pixels inside the image are all cast; beyond its border (within one image size, which bounds the
    work for someone right in front of the lens) every other row and column, each counting four. The hits come
    by owner, then row by row.
    """
    if set(scene.parts) != set(PARTS):
        raise ValueError(f"people's silhouettes are cast in a scene with every body part {PARTS}, "
                         f"not {sorted(scene.parts)}")
    k = intrinsics
    origin, rot = camera_pose(scene, camera)
    slots = np.asarray(slots, np.int64)
    corners = bodycast.part_box_corners(scene, slots)
    cam = (corners - origin) @ rot
    cx, cy = k.centre
    f = k.f
    part_lo, part_hi, cast = _part_boxes(cam, f, cx, cy, k.width, k.height)
    return bodycast.nearest_parts(origin, rot, f, cx, cy, k.width, k.height, part_lo, part_hi, cast,
                                  *bodycast.bodies(scene, slots), not body.HIP_INSIDE_TORSO)


@kernel
def _part_boxes(cam, f, cx, cy, width, height):
    """The pixel boxes [lo, hi) [n, 4, 2] of the projections of each person's part boxes, whose corners [n, 32, 3]
    in the optical frame are ``cam``, clipped to one image size beyond the border; and which persons to cast: those
    wholly in front of the camera whose box meets the image (a person partly behind it gets the boxes of corners
    at (1, 1, 1), never cast)."""
    n = len(cam)
    part_lo, part_hi = np.empty((n, 4, 2), np.int64), np.empty((n, 4, 2), np.int64)
    cast = np.empty(n, np.bool_)
    reach_lo, reach_hi = (-width, -height), (2 * width, 2 * height)
    for i in range(n):
        in_front = True
        for c in range(32):
            in_front = in_front and cam[i, c, 2] > 1e-3
        for part in range(4):
            lo, hi = [np.inf, np.inf], [-np.inf, -np.inf]
            for c in range(8 * part, 8 * part + 8):
                x, y, z = (cam[i, c, 0], cam[i, c, 1], cam[i, c, 2]) if in_front else (1.0, 1.0, 1.0)
                u, v = cx + f * x / z, cy + f * y / z
                lo[0], lo[1], hi[0], hi[1] = min(lo[0], u), min(lo[1], v), max(hi[0], u), max(hi[1], v)
            for a in range(2):
                part_lo[i, part, a] = np.int64(min(max(np.floor(lo[a]), reach_lo[a]), reach_hi[a]))
                part_hi[i, part, a] = np.int64(min(max(np.ceil(hi[a]), reach_lo[a]), reach_hi[a]))
        meets = True
        for a in range(2):
            top, bottom = part_hi[i, 0, a], part_lo[i, 0, a]
            for part in range(1, 4):
                top, bottom = max(top, part_hi[i, part, a]), min(bottom, part_lo[i, part, a])
            meets = meets and top > 0 and bottom < (width, height)[a]
        cast[i] = in_front and meets
    return part_lo, part_hi, cast


def person_boxes(scene: Scene, camera: str, intrinsics: Intrinsics, seg: np.ndarray):
    """For every person a segmentation image shows: id, box around the visible pixels, box around the person as it
    would show with nobody and nothing in front and no image border (so it may reach outside the image), and the
    share of those pixels that show."""
    seg = np.asarray(seg, np.int64)
    if seg.ndim != 2:
        raise ValueError(f"seg must be an image [h, w] of person ids, not of shape {seg.shape}")
    ids, boxes, counts = _segments(seg)
    full_owner, fu, fv, _, _, weight = person_pixels(scene, camera, intrinsics, scene.slots_of(ids))
    full = np.bincount(full_owner, weights=weight, minlength=len(ids))
    return ids, boxes, _boxes_of(full_owner, fu, fv, len(ids)), np.minimum(counts / np.maximum(full, 1), 1.0)


@kernel
def _segments(seg):
    """The ids >= 0 a segmentation image [h, w] shows (sorted), the box round each one's pixels and their count."""
    height, width = seg.shape
    shown = 0
    for v in range(height):
        for u in range(width):
            shown += seg[v, u] >= 0
    values, us, vs = np.empty(shown, np.int64), np.empty(shown, np.int64), np.empty(shown, np.int64)
    k = 0
    for v in range(height):
        for u in range(width):
            if seg[v, u] >= 0:
                values[k], us[k], vs[k] = seg[v, u], u, v
                k += 1
    ordered = np.sort(values)
    distinct = 0
    for k in range(shown):
        distinct += k == 0 or ordered[k] != ordered[k - 1]
    ids = np.empty(distinct, np.int64)
    distinct = 0
    for k in range(shown):
        if k == 0 or ordered[k] != ordered[k - 1]:
            ids[distinct] = ordered[k]
            distinct += 1
    owner = np.searchsorted(ids, values)
    counts = np.zeros(distinct, np.int64)
    for k in range(shown):
        counts[owner[k]] += 1
    return ids, _boxes_of(owner, us, vs, distinct), counts


@kernel
def _boxes_of(owner, u, v, n):
    """(u0, v0, u1, v1) around each owner's pixels (zeros for an owner without any): one pass over the pixels, in
    place of numpy's sort and reductions (nine calls on arrays of a few thousand)."""
    boxes = np.zeros((n, 4))
    seen = np.zeros(n, np.bool_)
    for k in range(len(owner)):
        i = owner[k]
        if not seen[i]:
            seen[i] = True
            boxes[i, 0], boxes[i, 1], boxes[i, 2], boxes[i, 3] = u[k], v[k], u[k] + 1, v[k] + 1
        else:
            boxes[i, 0], boxes[i, 1] = min(boxes[i, 0], u[k]), min(boxes[i, 1], v[k])
            boxes[i, 2], boxes[i, 3] = max(boxes[i, 2], u[k] + 1), max(boxes[i, 3], v[k] + 1)
    return boxes
