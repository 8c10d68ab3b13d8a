"""The MuJoCo scene: static walls and obstacles, the robot and a pool of person bodies moved as mocap bodies.

No contact physics runs: bodies are placed every tick and MuJoCo is used for ray casting (and later rendering).
Person bodies beyond the number alive are parked below the floor and made transparent, which ray casting skips.
"""

from __future__ import annotations

import mujoco
import numpy as np

WALL_HEIGHT = 2.5  # m
WALL_THICKNESS = 0.1  # m
PERSON_HIP_RADIUS = 0.18  # m, radius of the body the lasers see at 0.70 m (adult hip width ~0.36 m)
PERSON_HEIGHT = 1.75  # m
ROBOT_HEIGHT = 1.6  # m
PARKED_Z = -50.0


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


class Scene:
    """MuJoCo model and data of one scenario, with ``sync`` to place the people and the robot."""

    def __init__(self, walls: np.ndarray, robot_radius: float, capacity: int):
        self.capacity = capacity
        persons = "\n".join(
            f'<body name="person{k}" mocap="true" pos="0 0 {PARKED_Z}"><geom type="cylinder" '
            f'size="{PERSON_HIP_RADIUS} {PERSON_HEIGHT / 2}" pos="0 0 {PERSON_HEIGHT / 2}" rgba=".8 .5 .3 1"/></body>'
            for k in range(capacity))
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
        self.data.mocap_pos[self.person_mocap:self.person_mocap + capacity, 2] = PARKED_Z

    def sync(self, robot_pose: np.ndarray, person_ids: np.ndarray, person_xy: np.ndarray) -> None:
        """Place the robot and the persons (slot k holds the k-th person given); park the unused slots."""
        n = len(person_ids)
        if n > self.capacity:
            raise ValueError(f"{n} persons alive but the scene holds {self.capacity} (crowd.max_agents)")
        d = self.data
        d.mocap_pos[self.robot_mocap] = (robot_pose[0], robot_pose[1], 0.0)
        d.mocap_quat[self.robot_mocap] = (np.cos(robot_pose[2] / 2), 0.0, 0.0, np.sin(robot_pose[2] / 2))
        slots = slice(self.person_mocap, self.person_mocap + self.capacity)
        pos = d.mocap_pos[slots]
        pos[:n, :2] = person_xy
        pos[:n, 2] = 0.0
        pos[n:] = (0.0, 0.0, PARKED_Z)
        # MuJoCo's ray casting skips geoms with alpha 0: parked slots then cost nothing per beam
        self.model.geom_rgba[self.first_person_geom:self.first_person_geom + self.capacity, 3] = 0.0
        self.model.geom_rgba[self.first_person_geom:self.first_person_geom + n, 3] = 1.0
        self.slot_person_id[:n] = person_ids
        self.slot_person_id[n:] = -1
        mujoco.mj_kinematics(self.model, d)

    def person_of_geom(self, geom_id: np.ndarray) -> np.ndarray:
        """Ground-truth person id for each hit geom id (-1 for walls, the robot or no hit)."""
        slot = geom_id - self.first_person_geom
        valid = (slot >= 0) & (slot < self.capacity)
        return np.where(valid, self.slot_person_id[np.clip(slot, 0, max(self.capacity - 1, 0))], -1)
