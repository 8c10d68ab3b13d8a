"""The MuJoCo scene: static walls and obstacles, the robot and a pool of person bodies moved as mocap bodies.

No contact physics runs: bodies are placed every tick and MuJoCo is used for ray casting and rendering.
A person is a torso body (with the head) and two leg bodies (see sensors/body.py). The scene holds only the parts
its sensors can see (two 70 cm lasers see torsos only): MuJoCo's ray casting tests every geom of the model, so parts
nobody sees would only cost time. Slots beyond the number alive are parked below the floor and made transparent.
Rays are cast in a copy of the model whose persons are gathered by place into bodies of a few each (``Scene.cast``),
since MuJoCo's ray loop tests each body's bounding sphere before its geoms.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from pipeline.compiled import kernel
from pipeline.frames import optical_rotation

from . import body

WALL_HEIGHT = 2.5  # m
WALL_THICKNESS = 0.1  # m
PERSON_HIP_RADIUS = body.TORSO_RADIUS  # m, what the lasers at 0.70 m see
# the robot's outline, after the SPENCER platform (seed 000): a round base as wide as the footprint up to above the
# lasers, a narrower upper body, and a head at about 1.6 m carrying the RGB-D cameras
ROBOT_BASE_HEIGHT = 0.95  # m
ROBOT_BODY_HALF = (0.18, 0.28)  # m, half depth and half width of the upper body
ROBOT_HEAD_BOTTOM = 1.45  # m
ROBOT_HEAD_HALF = (0.14, 0.2)  # m, half depth and half width of the head
ROBOT_HEIGHT = 1.7  # m, top of the head
PARKED_Z = -50.0
# person slots the model starts with; it is made anew with twice as many when more persons are alive (up to the
# crowd's max_agents, or as many as are alive): MuJoCo's ray casts loop over every geom, so 400 parked slots cost an
# airport scan about 0.6 ms. Memory and the model's making follow the persons present, not max_agents
INITIAL_CAPACITY = 32
PARTS = ("torso", "head", "legs")
# persons per body of the cast model (``Scene.cast``): at 15 and 40 s of the airport (93 and 150 alive), an airport
# scan cost 213 us with every person in one body, 167 us with 8 a body, 172-194 with 4, 6, 12 or 24
TILE = 8
# MuJoCo geom groups, so that a ray cast skips the parts a ray at its height cannot meet, and a fixed camera draws
# the world that never moves apart from the robot (a renderer must turn all groups on: MuJoCo shows groups 0-2 by
# default)
STATIC_GROUP, TORSO_GROUP, HEAD_GROUP, LEG_GROUP, ROBOT_GROUP = 0, 1, 2, 3, 4


def parts_at(height: float) -> set[str]:
    """The body parts a horizontal ray at ``height`` above the floor can meet."""
    return {part for part, seen in (("torso", body.torso_at(height)), ("head", body.head_at(height)),
                                    ("legs", body.legs_show_at(height))) if seen}


def _segment_boxes(segs: np.ndarray) -> str:
    xml = []
    for (a, b) in segs:
        mid, d = (a + b) / 2, b - a
        half = np.linalg.norm(d) / 2
        if half < 1e-6:
            continue
        yaw = np.degrees(np.arctan2(d[1], d[0]))
        xml.append(f'<geom type="box" size="{half + WALL_THICKNESS / 2:.6f} {WALL_THICKNESS / 2} {WALL_HEIGHT / 2}" '
                   f'pos="{mid[0]:.6f} {mid[1]:.6f} {WALL_HEIGHT / 2}" euler="0 0 {yaw:.6f}" rgba=".6 .6 .65 1"/>')
    return "\n".join(xml)


def camera_xml(cam: dict) -> str:
    """A MuJoCo camera at ``position`` [x, y, z] looking along ``yaw`` and down by ``pitch`` (rad), in its parent's
    frame. MuJoCo's camera looks along its -z with y up: x = right, y = right x forward."""
    optical = optical_rotation(cam["yaw"], cam["pitch"])  # columns: right, down, forward
    right, up = optical[:, 0], -optical[:, 1]
    axes = " ".join(f"{v:.9f}" for v in (*right, *up))
    pos = " ".join(f"{v:.6f}" for v in cam["position"])
    return f'<camera name="{cam["name"]}" pos="{pos}" xyaxes="{axes}" fovy="{cam["fovy_deg"]}"/>'


def _person_geoms(k: int, parts: set[str]) -> tuple[str, str, str]:
    """The k-th person's geoms: those of the torso body (torso, head and neck), the left leg and the right leg."""
    torso_half = (body.TORSO_TOP - body.TORSO_BOTTOM) / 2
    trunk = ""
    if "torso" in parts:
        trunk += (f'<geom name="person{k}_torso" type="cylinder" size="{body.TORSO_RADIUS} {torso_half:.4f}" '
                  f'pos="0 0 {body.TORSO_BOTTOM + torso_half:.4f}" group="{TORSO_GROUP}" rgba=".8 .5 .3 1"/>')
    if "head" in parts:
        neck_half = (body.HEAD_CENTRE - body.TORSO_TOP) / 2
        trunk += (f'<geom name="person{k}_head" type="sphere" size="{body.HEAD_RADIUS}" pos="0 0 {body.HEAD_CENTRE}" '
                  f'group="{HEAD_GROUP}" rgba=".85 .68 .55 1"/>'
                  f'<geom name="person{k}_neck" type="cylinder" size="{body.NECK_RADIUS} {neck_half:.4f}" '
                  f'pos="0 0 {body.TORSO_TOP + neck_half:.4f}" group="{HEAD_GROUP}" rgba=".85 .68 .55 1"/>')
    legs = [f'<geom name="person{k}_{side}_leg" type="capsule" fromto="0 0 0 0 0 {-body.LEG_LENGTH:.4f}" '
            f'size="{body.LEG_RADIUS}" group="{LEG_GROUP}" rgba=".2 .2 .3 1"/>' if "legs" in parts else ""
            for side in ("left", "right")]
    return trunk, legs[0], legs[1]


def _person_xml(k: int, parts: set[str]) -> str:
    """The k-th person as mocap bodies: the torso (with the head) and, with legs, one body per leg."""
    trunk, left, right = _person_geoms(k, parts)
    xml = f'<body name="person{k}" mocap="true" pos="0 0 {PARKED_Z}">{trunk}</body>'
    for side, leg in (("left", left), ("right", right)):
        if leg:
            xml += f'<body name="person{k}_{side}_leg" mocap="true" pos="0 0 {PARKED_Z}">{leg}</body>'
    return xml


def _tiles_xml(capacity: int, parts: set[str]) -> str:
    """The cast model's persons: ``_tile_count`` bodies of TILE person slots each."""
    return "".join(f'<body name="tile{b}" mocap="true">' + "".join(
        "".join(_person_geoms(c, parts)) for c in range(b * TILE, (b + 1) * TILE)) + "</body>"
        for b in range(_tile_count(capacity)))


def _tile_count(capacity: int) -> int:
    """Bodies enough for ``capacity`` persons cut into tiles (``_tiles``): each band of them leaves at most one tile
    part-filled, and there are at most sqrt(capacity / TILE) + 1 bands."""
    full = math.ceil(capacity / TILE)
    return full + math.ceil(math.sqrt(full)) + 1


@kernel
def _tiles(xy, tile):
    """The cast slot of each person at ``xy`` [n, 2], so that each body of the cast model (slots
    b TILE ... (b + 1) TILE - 1) holds persons near each other: the persons cut by x into about sqrt(n / TILE) bands
    of equal counts, each band by y into tiles of TILE (its last one part-filled). Returns the slots [n] and the
    number of bodies used."""
    n = len(xy)
    bands = max(1, int(round(math.sqrt(math.ceil(n / tile)))))
    by_x = np.argsort(xy[:, 0], kind="mergesort")
    slot = np.empty(n, np.int64)
    body = 0
    for band in range(bands):
        lo, hi = band * n // bands, (band + 1) * n // bands
        members = by_x[lo:hi]
        by_y = members[np.argsort(xy[members, 1], kind="mergesort")]
        for k in range(len(by_y)):
            slot[by_y[k]] = (body + k // tile) * tile + k % tile
        body += (len(by_y) + tile - 1) // tile
    return slot, body


@kernel
def _fill_tiles(slot, bodies, scene_geoms, cast_geoms, xpos, xmat, size, rbound, aabb, rgba, cast_xpos, cast_xmat,
                cast_size, cast_rbound, cast_aabb, cast_rgba, tile_xipos, bvh_aabb, tile_bvh, scene_geom):
    """The persons' geoms copied into their cast slots ``slot`` (the scene's arrays first, the cast model's
    second), the unused slots' geoms transparent (MuJoCo's ray casting skips them), each used body's bounding box
    (MuJoCo's ``bvh_aabb`` row: centre relative to the body's xipos, half sizes) round its geoms, an unused body's
    far away and of no size (every ray misses it), and ``scene_geom`` mapping each cast geom to the scene's."""
    cast_rgba[cast_geoms.ravel(), 3] = 0.0
    lo, hi = np.full((len(tile_bvh), 3), np.inf), np.full((len(tile_bvh), 3), -np.inf)
    for k in range(len(slot)):
        b = slot[k] // TILE
        for p in range(scene_geoms.shape[1]):
            g, c = scene_geoms[k, p], cast_geoms[slot[k], p]
            cast_xpos[c], cast_xmat[c], cast_size[c], cast_aabb[c], cast_rgba[c] = xpos[g], xmat[g], size[g], aabb[g], \
                rgba[g]
            cast_rbound[c] = rbound[g]
            scene_geom[c] = g
            for a in range(3):
                lo[b, a] = min(lo[b, a], xpos[g, a] - rbound[g])
                hi[b, a] = max(hi[b, a], xpos[g, a] + rbound[g])
    for b in range(len(tile_bvh)):
        row = tile_bvh[b]
        for a in range(3):
            if b < bodies and lo[b, a] <= hi[b, a]:
                bvh_aabb[row, a] = (lo[b, a] + hi[b, a]) / 2 - tile_xipos[b, a]
                bvh_aabb[row, 3 + a] = (hi[b, a] - lo[b, a]) / 2
            else:
                bvh_aabb[row, a], bvh_aabb[row, 3 + a] = 1e9, 0.0


class Scene:
    """MuJoCo model and data of one scenario, with ``sync`` to place the people and the robot.

    ``parts``: the body parts to build (all of PARTS by default); ``parts_at`` says which a laser needs.
    ``robot_cameras`` ride on the robot (poses in base_link), ``wall_cameras`` stand in the world: dicts with
    ``name``, ``position``, ``yaw``, ``pitch``, ``fovy_deg``, ``width`` and ``height``.
    """

    def __init__(self, walls: np.ndarray, robot_radius: float, capacity: int, parts=PARTS,
                 robot_cameras: tuple = (), wall_cameras: tuple = (), initial_capacity: int = INITIAL_CAPACITY):
        unknown = set(parts) - set(PARTS)
        if unknown:
            raise ValueError(f"unknown body parts {sorted(unknown)}; expected some of {PARTS}")
        self.max_capacity = capacity
        self.parts = set(parts)
        self._layout = (np.asarray(walls, float), robot_radius, tuple(robot_cameras), tuple(wall_cameras))
        self.version = 0  # counts the builds: whoever holds something made from the model remakes it on a change
        self._synced_to = None  # (world, tick) of the last follow
        self._build(min(capacity, initial_capacity))

    def _build(self, capacity: int) -> None:
        """Make the model with ``capacity`` person slots, all parked."""
        walls, robot_radius, robot_cameras, wall_cameras = self._layout
        self.capacity = capacity
        self.version += 1
        cameras = [*robot_cameras, *wall_cameras]
        # a floor as big as the map plus a margin (an infinite plane costs a third of a camera image under Mesa)
        corners = np.asarray(walls, float).reshape(-1, 2) if len(walls) else np.zeros((1, 2))
        floor_centre = (corners.min(axis=0) + corners.max(axis=0)) / 2
        floor_half = (corners.max(axis=0) - corners.min(axis=0)) / 2 + 20.0
        width = max([c["width"] for c in cameras] + [640])
        height = max([c["height"] for c in cameras] + [480])
        # the floor (for cameras; horizontal laser rays never meet it) and a light from above; offscreen buffers as
        # big as the biggest camera, no multisampling, a coarse tessellation (16 sides: a cylinder's outline within
        # 2% of its width)
        self._xml = f"""<mujoco model="crowdsim">
  <option timestep="0.04"/>
  <visual>
    <global offwidth="{width}" offheight="{height}"/>
    <quality offsamples="0" numslices="16" numstacks="4" numquads="1"/>
  </visual>
  <worldbody>
    <light directional="true" pos="0 0 10" dir="0.2 0.3 -1" castshadow="false"/>
    <geom name="floor" type="plane" pos="{floor_centre[0]:.3f} {floor_centre[1]:.3f} 0"
          size="{floor_half[0]:.3f} {floor_half[1]:.3f} 1" rgba=".75 .75 .72 1"/>
    {_segment_boxes(walls)}
    {"".join(camera_xml(c) for c in wall_cameras)}
    <body name="robot" mocap="true" pos="0 0 0">
      <geom type="cylinder" size="{robot_radius} {ROBOT_BASE_HEIGHT / 2}" pos="0 0 {ROBOT_BASE_HEIGHT / 2}"
            group="{ROBOT_GROUP}" rgba=".85 .85 .88 1"/>
      <geom type="box" size="{ROBOT_BODY_HALF[0]} {ROBOT_BODY_HALF[1]} {(ROBOT_HEAD_BOTTOM - ROBOT_BASE_HEIGHT) / 2}"
            pos="0 0 {(ROBOT_HEAD_BOTTOM + ROBOT_BASE_HEIGHT) / 2}" group="{ROBOT_GROUP}" rgba=".2 .3 .8 1"/>
      <geom type="box" size="{ROBOT_HEAD_HALF[0]} {ROBOT_HEAD_HALF[1]} {(ROBOT_HEIGHT - ROBOT_HEAD_BOTTOM) / 2}"
            pos="0 0 {(ROBOT_HEIGHT + ROBOT_HEAD_BOTTOM) / 2}" group="{ROBOT_GROUP}" rgba=".85 .85 .88 1"/>
      {"".join(camera_xml(c) for c in robot_cameras)}
    </body>
    {{persons}}
  </worldbody>
</mujoco>"""
        m = self.model = mujoco.MjModel.from_xml_string(
            self._xml.replace("{persons}", "\n".join(_person_xml(k, self.parts) for k in range(capacity))))
        self._cast_model, self._cast_synced = None, False  # made at the first cast
        self.data = mujoco.MjData(m)
        self.robot_body = m.body("robot").id
        self.robot_mocap = m.body_mocapid[self.robot_body]

        def mocap(name):
            return np.array([m.body_mocapid[m.body(name.format(k)).id] for k in range(capacity)], np.int64)

        def geoms(name):
            return np.array([m.geom(name.format(k)).id for k in range(capacity)], np.int64)

        self._torso_mocap = mocap("person{}")
        self._leg_mocap = (np.stack([mocap("person{}_left_leg"), mocap("person{}_right_leg")], 1)
                           if "legs" in self.parts else np.zeros((capacity, 0), np.int64))
        self._geom = {"torso": geoms("person{}_torso")} if "torso" in self.parts else {}
        if "head" in self.parts:
            self._geom["head"] = np.stack([geoms("person{}_head"), geoms("person{}_neck")], 1)
        if "legs" in self.parts:
            self._geom["legs"] = np.stack([geoms("person{}_left_leg"), geoms("person{}_right_leg")], 1)
        # the names of a person's geoms, in the order of _all_person_geoms's columns
        self._part_names = [name for part, names in (("torso", ("torso",)), ("head", ("head", "neck")),
                                                     ("legs", ("left_leg", "right_leg"))) if part in self.parts
                            for name in names]
        self._all_person_geoms = np.concatenate([g.reshape(capacity, -1 if capacity else 1)
                                                 for g in self._geom.values()], 1).astype(np.int64) \
            if self._geom else np.zeros((capacity, 0), np.int64)
        self._geom_slot = np.full(m.ngeom + 1, -1, np.int64)  # the extra entry maps geom id -1 (no hit)
        self._geom_slot[self._all_person_geoms] = np.arange(capacity)[:, None]
        # the adult body's geom sizes, positions and bounds, which every person's own scale multiplies
        g = self._all_person_geoms
        self._base = [m.geom_size[g].copy(), m.geom_pos[g].copy(), m.geom_rbound[g].copy(), m.geom_aabb[g].copy()]
        self.person_scale = np.ones(capacity)
        self.slot_person_id = np.full(capacity, -1, np.int64)
        self.alive = 0
        self.person_xy = np.zeros((capacity, 2))
        self.hips = np.zeros((capacity, 2, 3))  # hip joints and leg ends for the cameras' silhouettes (with legs)
        self.feet = np.zeros((capacity, 2, 3))
        self.data.mocap_pos[self._torso_mocap, 2] = PARKED_Z
        self.data.mocap_pos[self._leg_mocap.ravel(), 2] = PARKED_Z
        m.geom_rgba[self._all_person_geoms.ravel(), 3] = 0.0

    def follow(self, world) -> None:
        """Synced to ``world`` (sensors/base.py) at its current tick, once however many sensors capture then."""
        if self._synced_to == (world, world.ticks):
            return
        agents = world.agents()
        self.sync(world.robot.pose, agents.id, agents.position, agents.velocity, agents.walked,
                  body.body_scale(agents.id, agents.radius))
        self._synced_to = (world, world.ticks)

    def sync(self, robot_pose: np.ndarray, person_ids: np.ndarray, person_xy: np.ndarray,
             person_velocity: np.ndarray | None = None, person_walked: np.ndarray | None = None,
             person_scale: np.ndarray | None = None) -> None:
        """Place the robot and the persons (slot k holds the k-th person given); park the unused slots.

        With velocities and distances walked the legs swing at each person's gait phase, facing the walking
        direction; without them everyone stands with legs straight. ``person_scale`` sizes each body
        (``body.body_scale``; the adult body without it).
        """
        n = len(person_ids)
        if n > self.capacity:  # a bigger model; each slot of it costs every ray cast a little, parked or not
            # doubling up to max_capacity, and never fewer than alive: the follow driver's target joins even a
            # crowd that its sources have filled to crowd.max_agents
            self._build(max(n, min(self.max_capacity, 2 * self.capacity)))
        m, d = self.model, self.data
        d.mocap_pos[self.robot_mocap] = (robot_pose[0], robot_pose[1], 0.0)
        d.mocap_quat[self.robot_mocap] = (np.cos(robot_pose[2] / 2), 0.0, 0.0, np.sin(robot_pose[2] / 2))
        xy = np.asarray(person_xy, float).reshape(-1, 2)
        vel = np.zeros((n, 2)) if person_velocity is None else np.asarray(person_velocity, float)
        heading = np.arctan2(vel[:, 1], vel[:, 0])
        torso, parked = self._torso_mocap[:n], self._torso_mocap[n:]
        d.mocap_pos[torso, :2], d.mocap_pos[torso, 2] = xy, 0.0
        d.mocap_quat[torso, 0], d.mocap_quat[torso, 3] = np.cos(heading / 2), np.sin(heading / 2)  # x, y stay 0
        d.mocap_pos[parked] = (0.0, 0.0, PARKED_Z)
        walked = np.zeros(n) if person_walked is None else np.asarray(person_walked, float)
        scale = np.ones(n) if person_scale is None else np.asarray(person_scale, float)
        if n and (scale.min() < body.MIN_SCALE - 1e-9 or scale.max() > body.MAX_SCALE + 1e-9):
            raise ValueError(f"body scales must lie in [{body.MIN_SCALE}, {body.MAX_SCALE}]")
        self.alive = n
        self.person_xy[:n], self.person_scale[:n] = xy, scale
        if "legs" in self.parts:  # the legs' poses, and the hips and feet the cameras' silhouettes are cast from
            swing = body.leg_swing(walked, np.linalg.norm(vel, axis=1), scale)
            hips, leg_quat = body.leg_poses(xy, heading, swing, scale)
            self.hips[:n], self.feet[:n] = hips, body.feet(hips, heading, swing, scale)
            legs = self._leg_mocap[:n]
            d.mocap_pos[legs], d.mocap_quat[legs] = hips, leg_quat
            d.mocap_pos[self._leg_mocap[n:].ravel()] = (0.0, 0.0, PARKED_Z)
        # each body at its own size: MuJoCo reads geom sizes and positions each draw and ray cast, and culls rays
        # by the bounding radii and boxes, which scale with them
        g, k = self._all_person_geoms[:n], scale[:, None, None]
        m.geom_size[g] = self._base[0][:n] * k
        m.geom_pos[g] = self._base[1][:n] * k
        m.geom_rbound[g] = self._base[2][:n] * scale[:, None]
        m.geom_aabb[g] = self._base[3][:n] * k
        # clothing colours, written where a slot's person changed; MuJoCo's ray casting skips geoms with alpha 0, so
        # parked slots cost less per beam
        new = np.flatnonzero(self.slot_person_id[:n] != person_ids)
        if len(new):
            top, trousers = body.clothing(np.asarray(person_ids)[new])
            for part, colour in (("torso", top), ("head", body.SKIN), ("legs", trousers)):
                if part in self._geom:
                    g = self._geom[part][new]
                    m.geom_rgba[g, :3] = colour[:, None] if g.ndim == 2 and colour.ndim == 2 else colour
        m.geom_rgba[self._all_person_geoms[:n].ravel(), 3] = 1.0
        m.geom_rgba[self._all_person_geoms[n:].ravel(), 3] = 0.0
        self.slot_person_id[:n] = person_ids
        self.slot_person_id[n:] = -1
        mujoco.mj_kinematics(m, d)
        if m.ncam:
            mujoco.mj_camlight(m, d)  # camera poses, which mj_kinematics leaves alone
        self._cast_synced = False

    def cast(self, origin: np.ndarray, directions: np.ndarray, groups: np.ndarray, exclude_body: int, cutoff: float,
             geom: np.ndarray, dist: np.ndarray, normal: np.ndarray | None = None) -> None:
        """MuJoCo's ``mj_multiRay`` from ``origin`` along ``directions`` [n, 3] in the scene as last synced: into
        ``geom`` (int32, the scene's geom ids; -1: no hit), ``dist`` (-1: no hit) and ``normal`` [3 n] where given.

        Why not the scene's own model: MuJoCo's ray loop tests every ray against every body's bounding sphere, then
        against each geom of the bodies it meets, and a person is one to three bodies. The cast is made in a copy
        of the model (``_make_cast_model``) whose persons are gathered by place into bodies of TILE (``_tiles``),
        each body's box round its persons: a ray skips the bodies it misses, and every body's geoms with them. In
        the airport at 15 s (170 bodies) a scan cost 430-460 us in the scene's model, 220-230 us with all persons
        in one body, 185 us in tiles (and 18 us a sync for the copy, made once for all the lasers of a tick). The persons' geom poses, sizes, bounds and colours are copied in from the scene, so
        MuJoCo tests each geom against the ray with the same numbers; walls and the robot keep their geom ids, and
        a person's hit is told by the scene's id. (The scene model's body spheres are those MuJoCo compiled for
        the adult body: a person scaled by ``sync`` can poke out of them, and rays in 3D then missed them there.
        tests/test_laser.py checks these hits against ``mj_ray``, which tests every geom.)"""
        if self._cast_model is None:
            self._make_cast_model()
        cm, cd = self._cast_model, self._cast_data
        if not self._cast_synced:
            self._sync_cast()
        mujoco.mj_multiRay(cm, cd, origin, directions.reshape(-1), groups, 1, exclude_body, geom, dist, normal,
                           len(dist), cutoff)
        geom[:] = self._scene_geom[geom]

    def _sync_cast(self) -> None:
        """The cast model's copy of the scene as last synced: the walls' and robot's poses, the persons in tiles."""
        m, d, cm, cd = self.model, self.data, self._cast_model, self._cast_data
        first = self._first_person_geom
        cd.geom_xpos[:first], cd.geom_xmat[:first] = d.geom_xpos[:first], d.geom_xmat[:first]
        cd.xipos[self.robot_body] = d.xipos[self.robot_body]
        n = self.alive
        slot, bodies = _tiles(self.person_xy[:n], TILE)
        _fill_tiles(slot, bodies, self._all_person_geoms[:n], self._cast_geoms, d.geom_xpos, d.geom_xmat, m.geom_size,
                    m.geom_rbound, m.geom_aabb, m.geom_rgba, cd.geom_xpos, cd.geom_xmat, cm.geom_size, cm.geom_rbound,
                    cm.geom_aabb, cm.geom_rgba, self._tile_xipos, cm.bvh_aabb, self._tile_bvh, self._scene_geom)
        self._cast_synced = True

    def _make_cast_model(self) -> None:
        """The model ``cast`` uses: this one with the persons' geoms in ``_tile_count`` bodies of TILE slots; the
        walls' and the robot's geoms keep their ids."""
        m = self.model
        cm = self._cast_model = mujoco.MjModel.from_xml_string(
            self._xml.replace("{persons}", _tiles_xml(self.capacity, self.parts)))
        self._cast_data = mujoco.MjData(cm)
        mujoco.mj_kinematics(cm, self._cast_data)
        self._first_person_geom = first = int(self._all_person_geoms.min()) if self._all_person_geoms.size else m.ngeom
        if cm.body("robot").id != self.robot_body or any(cm.geom(i).name != m.geom(i).name for i in range(first)):
            raise AssertionError("the cast model's walls or robot differ from the scene's")
        self._tile_bodies = np.array([cm.body(f"tile{b}").id for b in range(_tile_count(self.capacity))], np.int64)
        self._tile_bvh = cm.body_bvhadr[self._tile_bodies].astype(np.int64)
        self._tile_xipos = self._cast_data.xipos[self._tile_bodies]  # mocap bodies that never move
        slots = len(self._tile_bodies) * TILE
        self._cast_geoms = np.array([[cm.geom(f"person{c}_{part}").id for part in self._part_names]
                                     for c in range(slots)], np.int64).reshape(slots, -1)
        # the scene's geom id of each cast geom (the extra last entry maps -1, no hit, to -1)
        self._scene_geom = np.append(np.arange(cm.ngeom, dtype=np.int32), np.int32(-1))
        self._cast_synced = False

    def slots_of(self, person_ids: np.ndarray) -> np.ndarray:
        """The slots that hold these persons (each must be alive)."""
        alive = self.slot_person_id[:self.alive]
        order = np.argsort(alive)
        return order[np.searchsorted(alive, np.asarray(person_ids), sorter=order)]

    def person_geoms(self, slots: np.ndarray) -> np.ndarray:
        """The geom ids of the persons in ``slots``."""
        return self._all_person_geoms[np.asarray(slots, np.int64)].ravel()

    @staticmethod
    def groups_at(height: float) -> np.ndarray:
        """The geom groups (MuJoCo's include mask) a horizontal ray at ``height`` above the floor can meet."""
        parts = parts_at(height)
        mask = np.zeros(6, np.uint8)
        mask[STATIC_GROUP] = 1
        mask[TORSO_GROUP], mask[HEAD_GROUP], mask[LEG_GROUP] = ("torso" in parts), ("head" in parts), ("legs" in parts)
        return mask

    def person_of_geom(self, geom_id: np.ndarray) -> np.ndarray:
        """Ground-truth person id for each hit geom id (-1 for walls, the robot or no hit)."""
        slot = self._geom_slot[np.asarray(geom_id)]  # geom id -1 picks the extra last entry, -1
        return np.where(slot >= 0, self.slot_person_id[np.maximum(slot, 0)], -1)
