"""Many small worlds stepped as one: the environments' crowds and robots on arrays over every world at once.

A gym step is a few simulation ticks, and one world of 10-20 people is too small for numpy to pay off: a tick of
the scenario crowd (``crowdsim.crowd.Crowd``) costs about 1 ms at 20 people, nearly all of it per-call overhead.
Here E worlds of N people each live in [E, N] arrays and every tick is one set of array calls over all of them,
with the crowd's force model and parameters (Moussaid et al. 2009 between persons, ``forces.moussaid2009_dense``;
Helbing, Farkas & Vicsek 2000 from the walls; the robot's disc; Helbing & Molnar's field of view) between the persons
of each world. One environment is the same code with E = 1, so a batched world is the single environment's world,
bit for bit: every sum runs over one person's own world, in the same order.

What the scenario crowd has and these worlds do not: sources, sinks, queues, groups, walls other than the room's
four, and the pymunk contact solver. People walk routes round and round (``layouts``); overlapping bodies are
pushed apart half the overlap each per tick, out of the robot's disc and into the room.
"""

from __future__ import annotations

import numpy as np

from crowdsim.crowd import forces
from crowdsim.crowd.behaviours import AgentTypes
from crowdsim.robot import arc, limited
from pipeline.frames import compose
from scenarios.typed import Scenario

from ..errors import Error
from .layouts import LAYOUTS, Layout, room_walls

ARRIVED = 0.5  # m: a person this near their current route place heads for the next


class Worlds:
    """E worlds of one layout with N persons each: person arrays are [E, N], positions and velocities as complex
    numbers x + iy (one array call per vector operation: at these sizes the calls are the cost); robot arrays
    [E, ...]."""

    def __init__(self, n_worlds: int, people: int, layout: str, scenario: Scenario, robot_visible: bool = True):
        if layout not in LAYOUTS:
            raise Error(f"scenario: expected one of {sorted(LAYOUTS)}, got {layout!r}")
        if people < 0:
            raise Error(f"people: expected a count >= 0, got {people}")
        self.E, self.N = n_worlds, people
        self.layout = LAYOUTS[layout]
        self.crowd_p = scenario.crowd
        self.robot_p = scenario.robot
        self.robot_radius = self.robot_p.radius
        self.robot_visible = robot_visible
        self.dt = scenario.dt
        self.types = AgentTypes(self.crowd_p.agent_types)
        self.kind = self.types.names.index("adult") if "adult" in self.types.names else 0
        shape = (n_worlds, people)
        self.z, self.v, self.goal_z = (np.zeros(shape, complex) for _ in range(3))  # goal_z: the place headed for
        self.v0 = np.zeros(shape)
        self.radius = np.full(shape, self.types.radius[self.kind])
        self.walked = np.zeros(shape)
        self.route = np.zeros(shape + (1,), complex)
        self.route_length = np.ones(shape, np.int64)
        self.place = np.zeros(shape, np.int64)  # index of the route place each is heading for
        self.robot_pose = np.zeros((n_worlds, 3))
        self.robot_velocity = np.zeros((n_worlds, 2))
        self.goal = np.zeros((n_worlds, 2))
        self.t = np.zeros(n_worlds)
        self.size = (0.0, 0.0)
        self._wall_gap, self._facing = np.zeros((4,) + shape), np.zeros((4,) + shape)
        self._contact_distance = np.zeros((n_worlds, people, people))  # two radii, -inf on the diagonal

    # by component, as views (writing to them writes the state)
    x = property(lambda self: self.z.real)
    y = property(lambda self: self.z.imag)
    vx = property(lambda self: self.v.real)
    vy = property(lambda self: self.v.imag)
    gx = property(lambda self: self.goal_z.real)
    gy = property(lambda self: self.goal_z.imag)

    @property
    def walls(self) -> np.ndarray:
        return room_walls(self.size)

    @property
    def position(self) -> np.ndarray:
        """[E, N, 2], a view of the state (``position[k]`` costs nothing for the other worlds)."""
        return _pairs(self.z)

    @property
    def velocity(self) -> np.ndarray:
        """[E, N, 2], a view of the state."""
        return _pairs(self.v)

    def reset(self, k: int, rng: np.random.Generator) -> Layout:
        """Start world k over from a new layout drawn with ``rng``."""
        lay = self.layout(self.N, rng)
        width = lay.route.shape[1]
        if width != self.route.shape[2]:  # the layout's route width, known once the first is drawn
            self.route = np.zeros((self.E, self.N, width), complex)
        self.size = lay.size
        self.z[k] = lay.start[:, 0] + 1j * lay.start[:, 1]
        self.v[k], self.walked[k] = 0.0, 0.0
        v0 = self.types.desired_speeds(np.full(self.N, self.kind), rng)
        self.v0[k] = v0 if lay.speed is None else np.where(np.isnan(lay.speed), v0, lay.speed)
        self.route[k], self.route_length[k], self.place[k] = lay.route[..., 0] + 1j * lay.route[..., 1], \
            lay.route_length, 0
        self.goal_z[k] = self.route[k, :, 0]
        reach = self.radius[k, :, None] + self.radius[k, None, :]
        np.fill_diagonal(reach, -np.inf)  # no one overlaps themselves
        self._contact_distance[k] = reach
        self.robot_pose[k], self.robot_velocity[k], self.goal[k], self.t[k] = lay.robot_start, 0.0, lay.robot_goal, 0.0
        return lay

    def tick(self, command: np.ndarray, noise: np.ndarray) -> np.ndarray:
        """Advance every world one step dt: the persons by their forces (``noise`` [E, N] the random force, complex),
        the robots by ``command`` [E, 2] (v, omega) within their limits. Returns each world's smallest gap between
        the robot's disc and a person's or a wall, before contacts push anyone apart [E] (negative: a collision)."""
        p, dt = self.crowd_p, self.dt
        self.robot_velocity = limited(command, self.robot_velocity, self.robot_p, dt)
        self.robot_pose = compose(self.robot_pose, arc(self.robot_velocity[:, 0], self.robot_velocity[:, 1], dt))
        self.t += dt
        gap = self.robot_wall_gap()
        if self.N == 0:
            return gap
        z, v, v0 = self.z, self.v, self.v0
        e = self.goal_z - z
        e /= np.maximum(np.abs(e), 1e-9)
        acc = (v0 * e - v) / p.relaxation_time
        acc += forces.moussaid2009_dense(z, v, e, p.moussaid_strength, p.moussaid_lambda, p.moussaid_gamma,
                                         p.moussaid_n, p.moussaid_n_prime, p.fov_deg,
                                         p.out_of_view_weight)
        acc += self._wall_force(e)
        robot = (self.robot_pose[:, 0] + 1j * self.robot_pose[:, 1])[:, None]
        if self.robot_visible:
            acc += self._robot_force(e, robot)
        acc += noise
        nv = v + acc * dt
        back = np.minimum((nv * e.conjugate()).real, 0.0)  # pressure stops a walker; it does not walk them backwards
        nv -= back * e
        nv *= np.minimum(1.0, p.max_speed_factor * v0 / np.maximum(np.abs(nv), 1e-9))
        nz = z + nv * dt
        gap = np.minimum(gap, (np.abs(nz - robot) - self.radius - self.robot_radius).min(axis=1))
        nz = self._contacts(nz)
        self.v = (nz - z) / dt
        self.z = nz
        self.walked += np.abs(self.v) * dt
        arrived = np.abs(self.goal_z - nz) < ARRIVED
        if arrived.any():
            self.place[arrived] = (self.place[arrived] + 1) % self.route_length[arrived]
            self.goal_z[arrived] = self.route[arrived, self.place[arrived]]
        return gap

    def _in_view(self, e, f) -> np.ndarray:
        """``forces.in_view_weight`` on complex vectors."""
        p = self.crowd_p
        seen = -(e.conjugate() * f).real >= np.abs(f) * np.cos(np.radians(p.fov_deg) / 2)
        return np.where(seen, 1.0, p.out_of_view_weight)

    def _robot_force(self, e, robot) -> np.ndarray:
        """``forces.obstacle_disc_force`` from each world's robot (at ``robot`` [E, 1]) on its persons."""
        p = self.crowd_p
        away = self.z - robot
        dist = np.maximum(np.abs(away), 1e-9)
        f = away * (p.robot_strength / p.robot_range * np.exp(
            -np.maximum(dist - self.robot_radius, 0.0) / p.robot_range) / dist)
        return f * self._in_view(e, f)

    def _wall_force(self, e) -> np.ndarray:
        """``forces.wall_force`` from the room's four walls, whose normals are the axes: the gap to each wall is a
        coordinate, and a wall is in view when the walker faces it within the field of view."""
        p = self.crowd_p
        w, h = self.size
        x, y = self.z.real, self.z.imag
        dist, facing = self._wall_gap, self._facing  # to the left, right, bottom and top walls
        dist[0], dist[2] = x, y
        np.subtract(w, x, out=dist[1])
        np.subtract(h, y, out=dist[3])
        facing[0], facing[2] = e.real, e.imag
        np.negative(facing[0], out=facing[1])
        np.negative(facing[2], out=facing[3])
        facing = facing <= -np.cos(np.radians(p.fov_deg) / 2)  # the force (away from the wall) against e
        mag = np.exp((self.radius - dist) / p.wall_range)
        mag *= np.where(facing, p.wall_strength, p.wall_strength * p.out_of_view_weight)
        mag *= dist < p.wall_interaction_range
        return (mag[0] - mag[1]) + 1j * (mag[2] - mag[3])

    def _contacts(self, z) -> np.ndarray:
        """Overlapping persons apart (half the overlap each), everyone inside the room. Nobody is pushed off the
        robot: an overlap with it is a collision, left for the episode to see (and, when the robot is visible, for
        the person's repulsion from it to undo)."""
        dz = z[:, None, :] - z[:, :, None]
        d = np.abs(dz)
        push = self._contact_distance - d
        overlap = push > 0
        if overlap.any():
            push = np.divide(push, d, out=np.zeros_like(push), where=overlap)
            z = z - 0.5 * (push * dz).sum(axis=2)
        w, h = self.size
        r = self.radius
        return np.minimum(np.maximum(z.real, r), w - r) + 1j * np.minimum(np.maximum(z.imag, r), h - r)

    def robot_wall_gap(self) -> np.ndarray:
        """Distance from each robot's disc to the nearest wall of the room [E]."""
        w, h = self.size
        x, y = self.robot_pose[:, 0], self.robot_pose[:, 1]
        return np.minimum(np.minimum(x, w - x), np.minimum(y, h - y)) - self.robot_radius


def _pairs(z: np.ndarray) -> np.ndarray:
    """A contiguous complex array [...] as its (real, imaginary) pairs [..., 2], without a copy."""
    return z.view(float).reshape(z.shape + (2,))
