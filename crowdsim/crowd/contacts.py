"""Body contacts resolved by pymunk (Chipmunk2D): discs for people, static segments for walls, a kinematic disc for
the robot.

The social forces decide where everyone wants to go; each step the bodies' positions and velocities go into the
pymunk space in one batched call, Chipmunk moves them and resolves the contacts, and the positions come back in
another. Nothing loops over agents per step in Python: populations change only when people enter or leave.
"""

from __future__ import annotations

import numpy as np
import pymunk
import pymunk.batch as batch

from pipeline.compiled import kernel
from scenarios.wall_grid import WallGrid, away_from_wall, near_walls

PERSON_MASS = 80.0  # kg; one mass for all: only ratios matter to the contact solver
ITERATIONS = 40  # Chipmunk solver iterations per substep
COLLISION_SLOP = 0.002  # m of overlap Chipmunk tolerates before it pushes back
CORRECTION_PER_STEP = 0.5  # share of an overlap Chipmunk removes per 0.04 s (its default: about 0.2)
HASH_CELL = 1.0  # m, two body diameters: Chipmunk steps about 15% faster than with 0.5 m at 5000 agents
# bodies the spatial hash is sized for when made: its table has four cells per body of the crowd's capacity, up to
# this many; a larger capacity (crowd.max_agents) gets its table grown, doubling, as bodies come. Chipmunk clears the
# whole table every step, so a table sized for max_agents 1e7 cost 70 ms a step and 0.8 GB with 20 persons present
# (1e8: 6.4 GB; 1e9 overflowed pymunk's int); up to this many the table is what it always was, so runs are unchanged
HASH_BODIES = 10_000
SUBSTEPS = 2  # Chipmunk steps per simulation step (dense crowds: fewer overlaps than 1)
WALL_PASSES = 4  # push-out passes; two walls of a corner may each need one
FIELDS = batch.BodyFields.POSITION | batch.BodyFields.VELOCITY


class ContactSolver:
    def __init__(self, walls: np.ndarray, robot_radius: float = 0.0, capacity: int = 1000):
        self.space = pymunk.Space()
        # a spatial hash of body-sized cells: Chipmunk's default tree rebuilds slowly for thousands of bodies
        self.capacity = max(capacity, 100)
        self._hash_bodies = min(self.capacity, HASH_BODIES)  # the bodies the table is sized for
        self.space.use_spatial_hash(HASH_CELL, 4 * self._hash_bodies)
        self.space.iterations = ITERATIONS
        self.space.collision_slop = COLLISION_SLOP
        # Chipmunk's bias is the share of an overlap left after one second
        self.space.collision_bias = (1.0 - CORRECTION_PER_STEP) ** (1.0 / 0.04)
        for a, b in walls:
            seg = pymunk.Segment(self.space.static_body, tuple(a), tuple(b), 0.0)
            seg.friction = 0.0
            self.space.add(seg)
        self.robot = None
        if robot_radius > 0:
            self.robot = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            disc = pymunk.Circle(self.robot, robot_radius)
            disc.friction = 0.0
            self.space.add(self.robot, disc)
        self.bodies: list[pymunk.Body] = []  # in the crowd's agent order
        self._perm = np.zeros(0, np.int64)  # space order -> agent index (-1: the robot or the static body)
        self._out = batch.Buffer()
        self._in = batch.Buffer()

    def add(self, radii: np.ndarray) -> None:
        """Bodies for new agents, appended in the crowd's order."""
        for r in radii:
            body = pymunk.Body(PERSON_MASS, float("inf"))  # infinite moment: discs do not spin
            disc = pymunk.Circle(body, float(r))
            disc.friction = 0.0
            self.space.add(body, disc)
            self.bodies.append(body)
        if len(self.bodies) > self._hash_bodies and self._hash_bodies < self.capacity:
            # a bigger table (Chipmunk moves every shape over, the walls too), at most the capacity's
            self._hash_bodies = min(self.capacity, max(len(self.bodies), 2 * self._hash_bodies))
            self.space.use_spatial_hash(HASH_CELL, 4 * self._hash_bodies)
        self._reorder()

    def keep(self, mask: np.ndarray) -> None:
        """Remove the bodies of the agents where ``mask`` is False."""
        for body, k in zip(self.bodies, mask):
            if not k:
                self.space.remove(body, *body.shapes)
        self.bodies = [b for b, k in zip(self.bodies, mask) if k]
        self._reorder()

    def _reorder(self) -> None:
        self._out.clear()
        batch.get_space_bodies(self.space, batch.BodyFields.BODY_ID, self._out)
        space_ids = np.frombuffer(self._out.int_buf(), dtype=np.int64)
        ours = np.array([b.id for b in self.bodies], dtype=np.int64)
        order = np.argsort(ours)
        where = np.searchsorted(ours[order], space_ids).clip(0, max(len(ours) - 1, 0))
        found = (ours[order][where] == space_ids) if len(ours) else np.zeros(len(space_ids), bool)
        self._perm = np.where(found, order[where] if len(ours) else -1, -1)

    def step(self, pos: np.ndarray, vel: np.ndarray, dt: float, robot_pose: np.ndarray | None = None,
             robot_velocity: np.ndarray | None = None) -> np.ndarray:
        """Move the bodies from ``pos`` at ``vel`` for ``dt`` with contacts resolved; return the new positions."""
        if self.robot is not None and robot_pose is not None:
            self.robot.position = (float(robot_pose[0]), float(robot_pose[1]))
            v = np.zeros(2) if robot_velocity is None else robot_velocity
            self.robot.velocity = (float(v[0]), float(v[1]))
        self._out.clear()
        batch.get_space_bodies(self.space, FIELDS, self._out)
        state = np.frombuffer(self._out.float_buf(), dtype=np.float64).reshape(-1, 4).copy()
        _to_space(state, pos, vel, self._perm)
        self._in.set_float_buf(state.ravel())
        batch.set_space_bodies(self.space, FIELDS, self._in)
        for _ in range(SUBSTEPS):
            self.space.step(dt / SUBSTEPS)
        self._out.clear()
        batch.get_space_bodies(self.space, batch.BodyFields.POSITION, self._out)
        return _from_space(np.frombuffer(self._out.float_buf(), dtype=np.float64).reshape(-1, 2), self._perm,
                           len(pos))


@kernel
def _to_space(state, pos, vel, perm):
    """The persons' positions and velocities into the rows [x, y, vx, vy] of ``state`` (space order) that are
    theirs (``perm``: space row -> person, -1 for the robot's and other bodies', left as they are)."""
    for row in range(len(perm)):
        if perm[row] >= 0:
            state[row, 0], state[row, 1] = pos[perm[row], 0], pos[perm[row], 1]
            state[row, 2], state[row, 3] = vel[perm[row], 0], vel[perm[row], 1]


@kernel
def _from_space(moved, perm, persons):
    """The positions [persons, 2] of the persons from the rows of ``moved`` (space order) that are theirs."""
    out = np.empty((persons, 2))
    for row in range(len(perm)):
        if perm[row] >= 0:
            out[perm[row], 0], out[perm[row], 1] = moved[row, 0], moved[row, 1]
    return out


def push_out_of_walls(pos: np.ndarray, radius: np.ndarray, grid: WallGrid) -> None:
    """Move every body (``pos`` [n, 2], in place) that overlaps a wall of ``grid`` out along the wall's normal, the
    deepest overlap first (summing pushes from the two walls of a corner would over-correct); a few passes settle
    corners."""
    _push_out(pos, radius, WALL_PASSES, *grid.arrays())


@kernel
def _push_out(pos, radius, passes, walls, origin, cell, columns, rows, start, members):
    seen, near = np.full(len(walls), -1, np.int64), np.empty(len(walls), np.int64)
    for i in range(len(pos)):
        for attempt in range(passes):
            count = near_walls(pos[i, 0], pos[i, 1], radius[i], walls, origin, cell, columns, rows, start, members,
                               seen, i * passes + attempt, near)
            deepest, wall, out_x, out_y, out_d = 0.0, -1, 0.0, 0.0, 0.0
            for k in range(count):  # the deepest overlap, the lowest-numbered wall of equally deep ones
                wx, wy, dist = away_from_wall(pos[i, 0], pos[i, 1], walls, near[k])
                depth = radius[i] - dist
                if depth > deepest or (depth == deepest and depth > 0 and near[k] < wall):
                    deepest, wall, out_x, out_y, out_d = depth, near[k], wx, wy, dist
            if wall < 0:
                break
            scale = deepest / max(out_d, 1e-12)
            pos[i, 0] += scale * out_x
            pos[i, 1] += scale * out_y
