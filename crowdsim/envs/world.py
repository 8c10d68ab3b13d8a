"""Many small worlds stepped as one: the environments' crowds and robots on arrays over every world at once.

A gym step is a few simulation ticks, and one world of 10-20 people is too small for numpy to pay off. Here E worlds
of N people each live in [E, N] arrays. The robots of all worlds move through all the ticks of a step in one call of
the robot's own drive kernel (``crowdsim.robot.drive``), and the persons in one compiled call (``_people_ticks``)
made of the scenario crowd's own force kernels (``crowdsim.crowd.forces``: Moussaid et al. 2009 between every two
persons, Helbing, Farkas & Vicsek 2000 from the room's walls, the robot's disc, Helbing & Molnar's field of view)
with the crowd's parameters. One environment is the same code with E = 1, so a batched world is the single
environment's world, bit for bit: each world is stepped on its own, in the same order.

What the scenario crowd has and these worlds do not: sources, sinks, queues, groups, walls other than the room's
four, and the pymunk contact solver. People walk routes round and round (``layouts``); overlapping bodies are
pushed apart half the overlap each per tick, out of the robot's disc and into the room.
"""

from __future__ import annotations

import math

import numpy as np

from crowdsim.crowd import forces
from pipeline.compiled import kernel
from scenarios.wall_grid import WallGrid
from crowdsim.crowd.behaviours import AgentTypes
from crowdsim.robot import drive
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
        self.crowd_p = p = scenario.crowd
        self._forces = (p.relaxation_time, p.max_speed_factor, p.interaction_range, p.moussaid_strength,
                        p.moussaid_lambda, p.moussaid_gamma, p.moussaid_n, p.moussaid_n_prime, p.fov_deg,
                        p.out_of_view_weight, p.wall_strength, p.wall_range, p.wall_interaction_range,
                        p.robot_strength, p.robot_range)  # _people_ticks's parameters, in its order
        self.robot_p = scenario.robot
        self.robot_radius = self.robot_p.radius
        self._acceleration = np.array([self.robot_p.max_acceleration, self.robot_p.max_angular_acceleration])
        self._top = np.array([self.robot_p.max_speed, self.robot_p.max_angular_speed])
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
        self._room = WallGrid.of(room_walls(self.size))

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
        if lay.size != self.size:
            self.size, self._room = lay.size, WallGrid.of(room_walls(lay.size))
        self.z[k] = lay.start[:, 0] + 1j * lay.start[:, 1]
        self.v[k], self.walked[k] = 0.0, 0.0
        v0 = self.types.desired_speeds(np.full(self.N, self.kind), rng)
        self.v0[k] = v0 if lay.speed is None else np.where(np.isnan(lay.speed), v0, lay.speed)
        self.route[k], self.route_length[k], self.place[k] = lay.route[..., 0] + 1j * lay.route[..., 1], \
            lay.route_length, 0
        self.goal_z[k] = self.route[k, :, 0]
        self.robot_pose[k], self.robot_velocity[k], self.goal[k], self.t[k] = lay.robot_start, 0.0, lay.robot_goal, 0.0
        return lay

    def tick(self, command: np.ndarray, noise: np.ndarray) -> tuple[np.ndarray, dict]:
        """Advance every world len(noise) steps dt with ``command`` [E, 2] (v, omega) held: the robots within their
        limits, the persons by their forces (``noise`` [ticks, E, N] the random force, complex). Returns each tick's
        smallest gap between each world's robot disc and a person or a wall, before contacts push anyone apart
        [ticks, E] (negative: a collision), and, for each world that collided in these ticks, its state (time,
        robot pose, person positions and velocities) at the first of them."""
        dt, ticks = self.dt, len(noise)
        # the robots first: nothing a person does moves them
        velocity, poses = drive(command, self.robot_velocity, self.robot_pose, self._acceleration, self._top, dt, ticks)
        self.robot_velocity, self.robot_pose = velocity[-1], poses[-1]
        stamps = np.empty((ticks, self.E))
        for t in range(ticks):
            self.t += dt
            stamps[t] = self.t
        people = np.ascontiguousarray(noise).view(float).reshape(noise.shape + (2,))
        gaps, hit_pos, hit_vel = _people_ticks(
            _pairs(self.z), _pairs(self.v), self.v0, _pairs(self.goal_z), self.radius, self.walked,
            _pairs(self.route), self.route_length, self.place, poses, self.robot_radius, self.robot_visible, people,
            dt, self.size[0], self.size[1], *self._forces, *self._room.arrays())
        hit = {}
        for k in np.flatnonzero((gaps < 0).any(axis=0)):
            t = int(np.argmax(gaps[:, k] < 0))
            hit[k] = (float(stamps[t, k]), poses[t, k].copy(), hit_pos[k].view(complex)[:, 0].copy(),
                      hit_vel[k].view(complex)[:, 0].copy())
        return gaps, hit

def _pairs(z: np.ndarray) -> np.ndarray:
    """A contiguous complex array [...] as its (real, imaginary) pairs [..., 2], without a copy."""
    return z.view(float).reshape(z.shape + (2,))


@kernel
def _people_ticks(pos, vel, v0, goal, radius, walked, route, route_length, place, robot, robot_radius, robot_visible,
                  noise, dt, width, height, tau, max_speed_factor, interaction_range, strength, lam, gamma, n, n_prime,
                  fov_deg, out_of_view, wall_strength, wall_range, wall_reach, robot_strength, robot_range, walls,
                  origin, cell, columns, rows, start, members):
    """``Worlds.tick``'s persons, world by world and tick by tick, in place: the scenario crowd's forces
    (``forces``: every pair, the room's walls, the robot's disc when visible), the random force ``noise``, the
    crowd's speed limits, then contacts (half an overlap each, everyone inside the room). Returns the gaps
    [ticks, E] and the positions and velocities at each world's first collision [E, N, 2]."""
    ticks, worlds, people = noise.shape[0], pos.shape[0], pos.shape[1]
    gaps = np.empty((ticks, worlds))
    hit_pos, hit_vel = np.zeros((worlds, people, 2)), np.zeros((worlds, people, 2))
    walking = np.ones(people, np.bool_)
    order = np.arange(people)  # each person's pair forces summed in the persons' order
    for k in range(worlds):
        z, v, r = pos[k], vel[k], radius[k]
        for t in range(ticks):
            rx, ry = robot[t, k, 0], robot[t, k, 1]
            gap = min(min(rx, width - rx), min(ry, height - ry)) - robot_radius
            e = np.empty((people, 2))
            for i in range(people):
                gx, gy = goal[k, i, 0] - z[i, 0], goal[k, i, 1] - z[i, 1]
                norm = max(math.sqrt(gx * gx + gy * gy), 1e-9)
                e[i, 0], e[i, 1] = gx / norm, gy / norm
            acc = forces.moussaid2009(z, v, order, interaction_range, strength, lam, gamma, n, n_prime, walking, e,
                                      fov_deg, out_of_view)
            acc += forces.grid_wall_force(z, r, e, wall_strength, wall_range, wall_reach, fov_deg, out_of_view, walls,
                                          origin, cell, columns, rows, start, members)
            if robot_visible:
                acc += forces.obstacle_disc_force(z, e, rx, ry, robot_radius, robot_strength, robot_range, fov_deg,
                                                  out_of_view)
            moved = np.empty((people, 2))
            for i in range(people):
                ax = (v0[k, i] * e[i, 0] - v[i, 0]) / tau + acc[i, 0] + noise[t, k, i, 0]
                ay = (v0[k, i] * e[i, 1] - v[i, 1]) / tau + acc[i, 1] + noise[t, k, i, 1]
                nx, ny = v[i, 0] + ax * dt, v[i, 1] + ay * dt
                back = min(nx * e[i, 0] + ny * e[i, 1], 0.0)  # pressure stops a walker; it does not walk them back
                nx, ny = nx - back * e[i, 0], ny - back * e[i, 1]
                scale = min(1.0, max_speed_factor * v0[k, i] / max(math.sqrt(nx * nx + ny * ny), 1e-9))
                moved[i, 0], moved[i, 1] = z[i, 0] + scale * nx * dt, z[i, 1] + scale * ny * dt
                gap = min(gap, math.sqrt((moved[i, 0] - rx) ** 2 + (moved[i, 1] - ry) ** 2) - r[i] - robot_radius)
            _contacts(moved, r, width, height)
            for i in range(people):
                v[i, 0], v[i, 1] = (moved[i, 0] - z[i, 0]) / dt, (moved[i, 1] - z[i, 1]) / dt
                z[i, 0], z[i, 1] = moved[i, 0], moved[i, 1]
                walked[k, i] += math.sqrt(v[i, 0] ** 2 + v[i, 1] ** 2) * dt
                if math.sqrt((goal[k, i, 0] - z[i, 0]) ** 2 + (goal[k, i, 1] - z[i, 1]) ** 2) < ARRIVED:
                    place[k, i] = (place[k, i] + 1) % route_length[k, i]
                    goal[k, i, 0], goal[k, i, 1] = route[k, i, place[k, i], 0], route[k, i, place[k, i], 1]
            gaps[t, k] = gap
            if gap < 0 and (t == 0 or gaps[:t, k].min() >= 0):
                hit_pos[k], hit_vel[k] = z, v
    return gaps, hit_pos, hit_vel


@kernel
def _contacts(z, radius, width, height):
    """Overlapping persons apart (half the overlap each), everyone inside the room. Nobody is pushed off the
    robot: an overlap with it is a collision, left for the episode to see (and, when the robot is visible, for
    the person's repulsion from it to undo)."""
    push = np.zeros_like(z)
    for i in range(len(z)):
        for j in range(len(z)):
            if i != j:
                dx, dy = z[j, 0] - z[i, 0], z[j, 1] - z[i, 1]
                d = math.sqrt(dx * dx + dy * dy)
                overlap = radius[i] + radius[j] - d
                if overlap > 0:
                    push[i, 0] -= 0.5 * overlap / d * dx
                    push[i, 1] -= 0.5 * overlap / d * dy
    for i in range(len(z)):
        z[i, 0] = min(max(z[i, 0] + push[i, 0], radius[i]), width - radius[i])
        z[i, 1] = min(max(z[i, 1] + push[i, 1], radius[i]), height - radius[i])
