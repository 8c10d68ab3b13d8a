"""The pedestrian crowd: its persons as arrays, moved by vectorized social forces (crowdsim.crowd.forces) and body
contacts (crowdsim.crowd.contacts), with what they do (sources, routes, queues, attractions, sinks, escapes) in
crowdsim.crowd.behaviours.

The forces are compiled kernels over persons, over neighbour pairs (every pair in a small crowd, a k-d tree's in a
large one, so a step costs O(N log N), not O(N^2)) and over the walls of a grid near each person. Social forces
steer; pymunk then moves the bodies and resolves their contacts (the force model alone does not keep bodies apart),
and a last geometric pass keeps every body out of the walls.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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

    # -- forces -------------------------------------------------------------------------------------------------

    def desired_direction(self, holding: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors towards the current goals (or along the wall for walkers escaping one, see
        ``behaviours.Escapes``) and the desired speeds (standing people slow to their spot; people waiting at a
        waypoint want to stand wherever they stopped, so a group gathering there stands round it, not on its
        centre). ``holding``: ``self.holding``, made once a step."""
        to_goal = self.goal - self.pos
        dist = np.linalg.norm(to_goal, axis=1)
        e = to_goal / np.maximum(dist, 1e-9)[:, None]
        speed = np.where(holding, self.v0 * np.clip(dist / ARRIVAL_RADIUS, 0.0, 1.0), self.v0)
        speed[self.waiting] = 0.0
        self.escapes.steer(self, e)
        return e, speed

    def acceleration(self, e: np.ndarray, speed: np.ndarray, holding: np.ndarray, robot_pos: np.ndarray | None,
                     robot_radius: float) -> np.ndarray:
        """The sum of every force term on every agent, walking in directions ``e`` at desired ``speed``."""
        p = self.p
        acc = forces.desired_force(e, speed, self.vel, p.relaxation_time)
        acc += forces.pair_forces(p, self.pos, self.vel, e, ~holding)
        acc += forces.wall_force(self.pos, self.radius, e, self.wall_grid, p.wall_strength, p.wall_range,
                                 p.wall_interaction_range, p.fov_deg, p.out_of_view_weight
                                 ) * self.escapes.repelled_by_walls(self)[:, None]
        walking_groups = np.where(holding, -1, self.group)
        acc += forces.group_forces(self.pos, self.vel, e, self.radius, walking_groups, p.group_gaze,
                                   p.group_coherence, p.group_repulsion)
        if robot_pos is not None:
            acc += forces.obstacle_disc_force(self.pos, e, robot_pos[0], robot_pos[1], robot_radius,
                                              p.robot_strength, p.robot_range, p.fov_deg, p.out_of_view_weight)
        if p.random_force > 0:
            acc += self.rng.normal(0.0, p.random_force, acc.shape)
        return acc

    # -- stepping -----------------------------------------------------------------------------------------------

    def step(self, dt: float, robot_pos: np.ndarray | None = None, robot_radius: float = 0.0) -> None:
        """Emit, move everyone ``dt`` with the robot's disc at ``robot_pos`` as an obstacle, then let the behaviours
        act on where they now are."""
        self.sources.update(self)
        if len(self.pos):
            holding = self.holding  # nobody starts or stops holding a spot before the behaviours act
            e, speed = self.desired_direction(holding)
            vel = self.vel + self.acceleration(e, speed, holding, robot_pos, robot_radius) * dt
            # The field-of-view weighting makes the forces from those ahead outweigh those from behind, so in a
            # jam the net force points backwards and a whole crowd would walk backwards. Pressure from ahead
            # stops a walker; it does not make them walk backwards (contacts still push bodies physically).
            along = np.einsum("ij,ij->i", vel, e)
            back = ~holding & (along < 0)
            vel[back] -= along[back, None] * e[back]
            vmax = self.p.max_speed_factor * self.v0
            s = np.linalg.norm(vel, axis=1)
            vel *= np.minimum(1.0, vmax / np.maximum(s, 1e-9))[:, None]
            before = self.pos.copy()
            robot_vel = None
            if robot_pos is not None and self._robot_pos is not None:
                robot_vel = (robot_pos - self._robot_pos) / dt
            parked = np.array([1e6, 1e6])  # no robot in this simulation: its disc waits far away
            self.pos = self.contacts.step(self.pos, vel, dt, parked if robot_pos is None else robot_pos, robot_vel)
            # Chipmunk tolerates a little overlap; walls get none
            push_out_of_walls(self.pos, self.radius, self.wall_grid)
            # pushes from a dense crowd can carry a body across a thin wall within one step: such a body stays put
            crossed = self.wall_grid.crossed(before, self.pos)
            self.pos[crossed] = before[crossed]
            self.vel = (self.pos - before) / dt
            self.walked += np.linalg.norm(self.vel, axis=1) * dt
            self.escapes.update(self, dt)
        self._robot_pos = None if robot_pos is None else np.array(robot_pos, float)
        self.t += dt
        self.attractions.update(self, dt)
        self.routes.update(self, served=self.queues.update(self))

    def states(self) -> AgentStates:
        return AgentStates(self.t, self.id.copy(), self.pos.copy(), self.vel.copy(), self.goal.copy(),
                           self.group.copy(), self.walked.copy(), self.radius.copy(), self.kind.copy())
