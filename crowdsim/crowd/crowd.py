"""The pedestrian crowd: its persons as arrays, moved by vectorized social forces (crowdsim.crowd.forces) and body
contacts (crowdsim.crowd.contacts), with what they do (sources, routes, queues, attractions, sinks, escapes) in
crowdsim.crowd.behaviours.

The forces are compiled kernels over persons, over neighbour pairs (every pair in a small crowd, a k-d tree's in a
large one, so a step costs O(N log N), not O(N^2)) and over the walls of a grid near each person. Social forces
steer; pymunk then moves the bodies and resolves their contacts (the force model alone does not keep bodies apart),
and a last geometric pass keeps every body out of the walls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.compiled import kernel
from scenarios.geometry import wall_segments
from scenarios.typed import Scenario
from scenarios.wall_grid import WallGrid

from . import forces
from .behaviours import (AgentTypes, Attractions, Escapes, GroupIds, PerAgent, Queues, Routes, Sources, place_clusters,
                         place_standing)
from .contacts import ContactSolver, push_out_of_walls

ARRIVAL_RADIUS = 0.3  # m: standing people slow down within this distance of their spot, and return to it when pushed

# the per-agent arrays of the crowd itself (the behaviours add theirs), with the value a newcomer gets
COLUMNS = {
    "id": PerAgent(np.int64),
    "pos": PerAgent(float, shape=(2,)),
    "vel": PerAgent(float, 0.0, (2,)),
    "v0": PerAgent(float),  # desired speed
    "radius": PerAgent(float),
    "kind": PerAgent(np.int64),  # index into types.names
    "group": PerAgent(np.int64),  # -1 when alone
    "goal": PerAgent(float, shape=(2,)),
    "goal_radius": PerAgent(float),
    "walked": PerAgent(float, 0.0),  # m walked so far (drives the gait phase)
}


@dataclass
class AgentStates:
    """Ground truth of every person alive at ``stamp`` (world frame)."""

    stamp: float
    id: np.ndarray  # [n] int64
    position: np.ndarray  # [n, 2]
    velocity: np.ndarray  # [n, 2]
    goal: np.ndarray  # [n, 2]
    group_id: np.ndarray  # [n] int64, -1 when alone
    walked: np.ndarray  # [n] metres walked so far (drives the gait phase)
    radius: np.ndarray  # [n]
    kind: np.ndarray  # [n] int64, the agent type: index into the scenario's crowd.agent_types (in their order)


class Crowd:
    """The persons of one scenario; ``step(dt)`` advances them, ``states()`` reports the ground truth.

    Each per-agent array (``COLUMNS`` and the behaviours' ``columns``) is an attribute, in agent order (ids
    ascending); ``add`` and ``keep`` change them all together, and the contact solver's bodies with them.
    """

    def __init__(self, scenario: Scenario, rng: np.random.Generator):
        self.p = scenario.crowd
        self.rng = rng
        self.t = 0.0
        self.walls = wall_segments(scenario)
        self.wall_grid = WallGrid.of(self.walls)
        self.contacts = ContactSolver(self.walls, scenario.robot.radius, self.p.max_agents)
        self._robot_pos: np.ndarray | None = None
        self._next_id = 1
        self.types = AgentTypes(self.p.agent_types)
        self.groups = GroupIds()
        self.routes = Routes(scenario)
        self.queues = Queues(scenario)
        self.attractions = Attractions(scenario)
        self.escapes = Escapes(self.p.stuck_time)
        p = self.p
        self._parameters = (p.relaxation_time, p.max_speed_factor, p.interaction_range, p.moussaid_strength,
                            p.moussaid_lambda, p.moussaid_gamma, p.moussaid_n, p.moussaid_n_prime, p.agent_strength,
                            p.agent_range, p.step_time, p.fov_deg, p.out_of_view_weight, p.wall_strength, p.wall_range,
                            p.wall_interaction_range, p.group_gaze, p.group_coherence, p.group_repulsion,
                            p.robot_strength, p.robot_range)  # _velocity's, in its order
        self.sources = Sources(scenario.sources, self.types, self.routes, rng)
        self.columns = dict(COLUMNS)
        for behaviour in (self.routes, self.queues, self.attractions, self.escapes):
            self.columns.update(behaviour.columns)
        for name, column in self.columns.items():
            setattr(self, name, np.zeros((0,) + column.shape, column.dtype))
        place_standing(self, scenario.standing)
        place_clusters(self, scenario.clusters)

    # -- population ---------------------------------------------------------------------------------------------

    def add(self, pos: np.ndarray, v0: np.ndarray, kind: np.ndarray, group: int | np.ndarray, route: int | np.ndarray,
            goal: np.ndarray, goal_radius: np.ndarray) -> np.ndarray:
        """Append persons at ``pos`` [n, 2] (``group`` and ``route`` per person or one for all); their other arrays
        start at the columns' fill values. Returns their ids."""
        n = len(pos)
        radius = self.types.radius[kind]
        self.contacts.add(radius)
        given = {"id": np.arange(self._next_id, self._next_id + n), "pos": pos, "v0": v0, "radius": radius,
                 "kind": kind, "group": group, "route": route, "goal": goal, "goal_radius": goal_radius}
        self._next_id += n
        for name, column in self.columns.items():
            new = np.broadcast_to(np.asarray(given.get(name, column.fill), column.dtype), (n,) + column.shape)
            setattr(self, name, np.concatenate([getattr(self, name), new]))
        return given["id"]

    def keep(self, mask: np.ndarray) -> None:
        """Remove the persons where ``mask`` is False."""
        self.contacts.keep(mask)
        for name in self.columns:
            setattr(self, name, getattr(self, name)[mask])

    def add_walkers(self, positions: np.ndarray, route: str, desired_speed: float | None = None,
                    group: bool = False, agent_type: str = "adult") -> np.ndarray:
        """Place persons at ``positions`` [n, 2] on the named route (for tests, benchmarks and scripted scenes);
        returns their ids. Without ``desired_speed`` each draws their own from the agent type's distribution."""
        n = len(positions)
        kind = np.full(n, self.types.names.index(agent_type))
        v0 = (np.full(n, float(desired_speed)) if desired_speed is not None
              else self.types.desired_speeds(kind, self.rng))
        return self.add(np.asarray(positions, float), v0, kind, self.groups.new(n) if group else -1,
                        **self.routes.start(self.routes.names.index(route), n))

    @property
    def waiting(self) -> np.ndarray:
        """Persons standing at a waypoint for its ``wait`` (``behaviours.Routes``)."""
        return ~np.isnan(self.wait_end)

    @property
    def holding(self) -> np.ndarray:
        """Persons who hold a spot rather than walk: standing people, people in a queue, at an attraction or
        waiting at a waypoint."""
        return (self.route < 0) | (self.queued >= 0) | (self.visiting >= 0) | self.waiting

    # -- stepping -----------------------------------------------------------------------------------------------

    def step(self, dt: float, robot_pos: np.ndarray | None = None, robot_radius: float = 0.0) -> None:
        """Emit, move everyone ``dt`` with the robot's disc at ``robot_pos`` as an obstacle, then let the behaviours
        act on where they now are."""
        self.sources.update(self)
        if len(self.pos):
            p = self.p
            holding = self.holding  # nobody starts or stops holding a spot before the behaviours act
            e, speed = _desired(self.goal, self.pos, self.v0, holding, self.waiting, ARRIVAL_RADIUS)
            self.escapes.steer(self, e)
            moussaid = p.interaction == "moussaid2009"
            order = forces.pair_order(self.pos) if moussaid else forces.NO_ORDER
            pairs = forces.NO_PAIRS if moussaid else forces.neighbour_pairs(self.pos, p.interaction_range)
            noise = self.rng.normal(0.0, p.random_force, self.pos.shape) if p.random_force > 0 else forces.NO_FORCE
            robot = (np.nan, np.nan) if robot_pos is None else (float(robot_pos[0]), float(robot_pos[1]))
            grouped, label, groups = forces.group_labels(np.where(holding, -1, self.group))  # walking members
            vel = _velocity(self.pos, self.vel, self.v0, e, speed, holding, self.radius, grouped, label, groups,
                            self.escapes.repelled_by_walls(self), noise, pairs, order, moussaid, *robot, robot_radius,
                            dt, *self._parameters, *self.wall_grid.arrays())
            before = self.pos.copy()
            robot_vel = None
            if robot_pos is not None and self._robot_pos is not None:
                robot_vel = (robot_pos - self._robot_pos) / dt
            parked = np.array([1e6, 1e6])  # no robot in this simulation: its disc waits far away
            self.pos = self.contacts.step(self.pos, vel, dt, parked if robot_pos is None else robot_pos, robot_vel)
            # Chipmunk tolerates a little overlap; walls get none
            push_out_of_walls(self.pos, self.radius, self.wall_grid)
            # pushes from a dense crowd can carry a body across a thin wall within one step: such a body stays put
            self.vel = _moved(self.pos, before, self.wall_grid.crossed(before, self.pos), self.walked, dt)
            self.escapes.update(self, dt, holding)
        self._robot_pos = None if robot_pos is None else np.array(robot_pos, float)
        self.t += dt
        self.attractions.update(self, dt)
        self.routes.update(self, served=self.queues.update(self))

    def states(self) -> AgentStates:
        return AgentStates(self.t, self.id.copy(), self.pos.copy(), self.vel.copy(), self.goal.copy(),
                           self.group.copy(), self.walked.copy(), self.radius.copy(), self.kind.copy())


@kernel
def _desired(goal, pos, v0, holding, waiting, arrival_radius):
    """Unit vectors towards the goals [n, 2] and the desired speeds [n]: standing people slow to their spot within
    ``arrival_radius``; people ``waiting`` at a waypoint want to stand wherever they stopped (a group gathering
    there stands round it, not on its centre)."""
    e, speed = np.empty((len(pos), 2)), np.empty(len(pos))
    for i in range(len(pos)):
        gx, gy = goal[i, 0] - pos[i, 0], goal[i, 1] - pos[i, 1]
        dist = math.sqrt(gx * gx + gy * gy)
        e[i, 0], e[i, 1] = gx / max(dist, 1e-9), gy / max(dist, 1e-9)
        speed[i] = 0.0 if waiting[i] else v0[i] * min(max(dist / arrival_radius, 0.0), 1.0) if holding[i] else v0[i]
    return e, speed


@kernel
def _velocity(pos, vel, v0, e, speed, holding, radius, grouped, label, groups, repelled, noise, pairs, order,
              moussaid, robot_x, robot_y, robot_radius, dt, tau, max_speed_factor, interaction_range, strength, lam,
              gamma, n, n_prime, agent_strength, agent_range, step_time, fov_deg, out_of_view, wall_strength,
              wall_range, wall_reach, gaze, coherence, repulsion, robot_strength, robot_range, walls, origin, cell,
              columns, rows, start, members):
    """Everyone's velocity after ``dt`` of every force term, walking in directions ``e`` at desired ``speed``: the
    relaxation towards the desired velocity (Helbing & Molnar 1995), the agent-agent force the crowd parameters
    choose (Moussaid 2009 summed in the ``order`` of ``forces.pair_order``; else Helbing & Molnar's ellipses over
    the k-d tree's ``pairs``), the walls' (but for those not ``repelled``), the groups' (Moussaid 2010, on the
    walking members ``grouped`` of ``groups`` groups numbered ``label``), the robot's disc (unless ``robot_x`` is
    NaN) and the random force ``noise``.
    Pressure from ahead stops a walker but does not make them walk backwards (in a jam the field of view makes the
    net force point backwards, and a whole crowd would walk backwards; contacts still push bodies physically);
    nobody exceeds ``max_speed_factor`` x their desired speed."""
    walking = ~holding
    acc = np.empty((len(pos), 2))
    for i in range(len(pos)):  # the relaxation: (v0 e - v) / tau
        acc[i, 0] = (speed[i] * e[i, 0] - vel[i, 0]) / tau
        acc[i, 1] = (speed[i] * e[i, 1] - vel[i, 1]) / tau
    if moussaid:
        acc += forces.moussaid2009(pos, vel, order, interaction_range, strength, lam, gamma, n, n_prime, walking, e,
                                   fov_deg, out_of_view)
    else:
        acc += forces.helbing_molnar1995(pos, vel, e, pairs, agent_strength, agent_range, step_time, fov_deg,
                                         out_of_view)
    wall = forces.grid_wall_force(pos, radius, e, wall_strength, wall_range, wall_reach, fov_deg, out_of_view, walls,
                                  origin, cell, columns, rows, start, members)
    for i in range(len(pos)):
        acc[i, 0] += wall[i, 0] * repelled[i]
        acc[i, 1] += wall[i, 1] * repelled[i]
    if len(grouped) >= 2:
        acc += forces.group_members_forces(pos, vel, e, radius, grouped, label, groups, gaze, coherence, repulsion,
                                           math.radians(forces.GROUP_VISION_DEG), forces.GROUP_MARGIN)
    if not math.isnan(robot_x):
        acc += forces.obstacle_disc_force(pos, e, robot_x, robot_y, robot_radius, robot_strength, robot_range,
                                          fov_deg, out_of_view)
    if len(noise):
        acc += noise
    out = np.empty((len(pos), 2))
    for i in range(len(pos)):
        vx, vy = vel[i, 0] + acc[i, 0] * dt, vel[i, 1] + acc[i, 1] * dt
        along = vx * e[i, 0] + vy * e[i, 1]
        if walking[i] and along < 0:
            vx, vy = vx - along * e[i, 0], vy - along * e[i, 1]
        cap = min(1.0, max_speed_factor * v0[i] / max(math.sqrt(vx * vx + vy * vy), 1e-9))
        out[i, 0], out[i, 1] = vx * cap, vy * cap
    return out


@kernel
def _moved(pos, before, crossed, walked, dt):
    """Put back those who ``crossed`` a wall (``pos`` in place), add the distance walked to ``walked``; returns the
    velocities [n, 2] of the moves from ``before``."""
    vel = np.empty((len(pos), 2))
    for i in range(len(pos)):
        if crossed[i]:
            pos[i, 0], pos[i, 1] = before[i, 0], before[i, 1]
        vel[i, 0], vel[i, 1] = (pos[i, 0] - before[i, 0]) / dt, (pos[i, 1] - before[i, 1]) / dt
        walked[i] += math.sqrt(vel[i, 0] * vel[i, 0] + vel[i, 1] * vel[i, 1]) * dt
    return vel
