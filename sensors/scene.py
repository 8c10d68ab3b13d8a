"""The MuJoCo scene: static walls and obstacles, the robot and a pool of person bodies moved as mocap bodies.

No contact physics runs: bodies are placed every tick and MuJoCo is used for ray casting (and later rendering).
A person is three mocap bodies (torso with head, left leg, right leg; see sensors/body.py). Slots beyond the number
alive are parked below the floor and made transparent, which ray casting skips.
"""

from __future__ import annotations

import mujoco
import numpy as np

from . import body

WALL_HEIGHT = 2.5  # m
WALL_THICKNESS = 0.1  # m
PERSON_HIP_RADIUS = body.TORSO_RADIUS  # m, what the lasers at 0.70 m see
ROBOT_HEIGHT = 1.6  # m
PARKED_Z = -50.0
GEOMS_PER_PERSON = 4  # torso, head, left leg, right leg (in this order)
BODIES_PER_PERSON = 3  # torso (with the head), left leg, right leg
# MuJoCo geom groups, so that a ray cast skips the parts a ray at its height cannot meet: a 70 cm laser tests the
# torsos only, a 38 cm laser the legs only (a renderer must turn all groups on: MuJoCo shows 0-2 by default)
STATIC_GROUP, TORSO_GROUP, HEAD_GROUP, LEG_GROUP = 0, 1, 2, 3


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


def _person_xml(k: int) -> str:
    torso_half = (body.TORSO_TOP - body.TORSO_BOTTOM) / 2
    leg = (f'<geom type="capsule" fromto="0 0 0 0 0 {-body.LEG_LENGTH:.4f}" size="{body.LEG_RADIUS}" '
           f'group="{LEG_GROUP}" rgba=".2 .2 .3 1"/>')
    return (f'<body name="person{k}" mocap="true" pos="0 0 {PARKED_Z}">'
            f'<geom type="cylinder" size="{body.TORSO_RADIUS} {torso_half:.4f}" '
            f'pos="0 0 {body.TORSO_BOTTOM + torso_half:.4f}" group="{TORSO_GROUP}" rgba=".8 .5 .3 1"/>'
            f'<geom type="sphere" size="{body.HEAD_RADIUS}" pos="0 0 {body.HEAD_CENTRE}" group="{HEAD_GROUP}" '
            f'rgba=".85 .68 .55 1"/></body>'
            f'<body name="person{k}_left_leg" mocap="true" pos="0 0 {PARKED_Z}">{leg}</body>'
            f'<body name="person{k}_right_leg" mocap="true" pos="0 0 {PARKED_Z}">{leg}</body>')


class Scene:
    """MuJoCo model and data of one scenario, with ``sync`` to place the people and the robot."""

    def __init__(self, walls: np.ndarray, robot_radius: float, capacity: int):
        self.capacity = capacity
        persons = "\n".join(_person_xml(k) for k in range(capacity))
        xml = f"""<mujoco model="crowdsim">
  <option timestep="0.04"/>
  <worldbody>
    {_segment_boxes(walls)}
    <body name="robot" mocap="true" pos="0 0 0">
      <geom type="cylinder" size="{robot_radius} {ROBOT_HEIGHT / 2}" pos="0 0 {ROBOT_HEIGHT / 2}" rgba=".2 .3 .8 1"/>
    </body>
    {persons}
  </worldbody>
</mujoco>"""
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        self.robot_body = self.model.body("robot").id
        self.first_person_geom = self.model.body("person0").geomadr[0] if capacity else self.model.ngeom
        self.robot_mocap = self.model.body_mocapid[self.robot_body]
        self.person_mocap = self.model.body_mocapid[self.model.body("person0").id] if capacity else 0
        self.slot_person_id = np.full(capacity, -1, np.int64)
        self._person_geoms = slice(self.first_person_geom, self.first_person_geom + GEOMS_PER_PERSON * capacity)
        self._person_bodies = slice(self.person_mocap, self.person_mocap + BODIES_PER_PERSON * capacity)
        self.data.mocap_pos[self._person_bodies, 2] = PARKED_Z

    def sync(self, robot_pose: np.ndarray, person_ids: np.ndarray, person_xy: np.ndarray,
             person_velocity: np.ndarray | None = None, person_walked: np.ndarray | None = None) -> None:
        """Place the robot and the persons (slot k holds the k-th person given); park the unused slots.

        With velocities and distances walked the legs swing at each person's gait phase, facing the walking
        direction; without them everyone stands with legs straight.
        """
        n = len(person_ids)
        if n > self.capacity:
            raise ValueError(f"{n} persons alive but the scene holds {self.capacity} (crowd.max_agents)")
        m, d = self.model, self.data
        d.mocap_pos[self.robot_mocap] = (robot_pose[0], robot_pose[1], 0.0)
        d.mocap_quat[self.robot_mocap] = (np.cos(robot_pose[2] / 2), 0.0, 0.0, np.sin(robot_pose[2] / 2))
        xy = np.asarray(person_xy, float).reshape(-1, 2)
        vel = np.zeros((n, 2)) if person_velocity is None else np.asarray(person_velocity, float)
        walked = np.zeros(n) if person_walked is None else np.asarray(person_walked, float)
        speed = np.linalg.norm(vel, axis=1)
        heading = np.arctan2(vel[:, 1], vel[:, 0])
        hips, leg_quat = body.leg_poses(xy, heading, body.leg_swing(walked, speed))
        pos = d.mocap_pos[self._person_bodies].reshape(self.capacity, BODIES_PER_PERSON, 3)
        quat = d.mocap_quat[self._person_bodies].reshape(self.capacity, BODIES_PER_PERSON, 4)
        pos[:n, 0, :2], pos[:n, 0, 2] = xy, 0.0
        quat[:n, 0] = np.stack([np.cos(heading / 2), np.zeros(n), np.zeros(n), np.sin(heading / 2)], 1)
        pos[:n, 1:], quat[:n, 1:] = hips, leg_quat
        pos[n:] = (0.0, 0.0, PARKED_Z)
        d.mocap_pos[self._person_bodies] = pos.reshape(-1, 3)
        d.mocap_quat[self._person_bodies] = quat.reshape(-1, 4)
        # clothing colours; MuJoCo's ray casting skips geoms with alpha 0, so parked slots cost nothing per beam
        top, trousers = body.clothing(person_ids)
        rgba = m.geom_rgba[self._person_geoms].reshape(self.capacity, GEOMS_PER_PERSON, 4)
        rgba[:n, 0, :3], rgba[:n, 1, :3] = top, body.SKIN
        rgba[:n, 2, :3], rgba[:n, 3, :3] = trousers, trousers
        rgba[:n, :, 3], rgba[n:, :, 3] = 1.0, 0.0
        m.geom_rgba[self._person_geoms] = rgba.reshape(-1, 4)
        self.slot_person_id[:n] = person_ids
        self.slot_person_id[n:] = -1
        mujoco.mj_kinematics(m, d)

    @staticmethod
    def groups_at(height: float) -> np.ndarray:
        """The geom groups (MuJoCo's include mask) a horizontal ray at ``height`` above the floor can meet."""
        mask = np.zeros(6, np.uint8)
        mask[STATIC_GROUP] = 1
        mask[TORSO_GROUP] = body.TORSO_BOTTOM <= height <= body.TORSO_TOP
        mask[HEAD_GROUP] = abs(height - body.HEAD_CENTRE) <= body.HEAD_RADIUS
        mask[LEG_GROUP] = body.legs_show_at(height)
        return mask

    def person_of_geom(self, geom_id: np.ndarray) -> np.ndarray:
        """Ground-truth person id for each hit geom id (-1 for walls, the robot or no hit)."""
        slot = (np.asarray(geom_id) - self.first_person_geom) // GEOMS_PER_PERSON
        valid = (geom_id >= self.first_person_geom) & (slot < self.capacity)
        return np.where(valid, self.slot_person_id[np.clip(slot, 0, max(self.capacity - 1, 0))], -1)
