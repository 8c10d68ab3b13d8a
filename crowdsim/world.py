"""The world a tick advances: the crowd, the robot's body, the walls and the clock.

It knows the truth (every person, the robot's true pose); the sensors capture it and the ground truth labels it,
while the robot's software sees only what the sensors make of it. It also keeps the navigation metrics' collision
test: whether the robot's disc overlaps a person's or a wall at a tick.
"""

from __future__ import annotations

import numpy as np

from scenarios.geometry import closest_on_segments
from scenarios.typed import Scenario, Section

from .crowd import AgentStates, Crowd
from .robot import Robot


class World:
    """``follow_target`` (the scenario's ``robot.follow.target``, or None) is the tagged person: they join the crowd
    at the first tick, when recording starts."""

    def __init__(self, scenario: Scenario, walls: np.ndarray, crowd_rng: np.random.Generator,
                 robot_rng: np.random.Generator, follow_target: Section | None = None):
        self.walls = walls
        self.dt = scenario.dt
        self.crowd = Crowd(scenario, crowd_rng)
        self.robot = Robot.of(scenario.robot, robot_rng)
        self.ticks = 0
        self._follow_target = follow_target
        self.tagged_id = -1  # the tagged person's crowd id, once placed
        self.collision_ticks = 0  # ticks the robot's disc overlapped a person's or a wall
        self.first_collision: float | None = None  # the stamp of the first
        self.collided = False  # at the last tick
        self._agents: AgentStates | None = None

    @property
    def t(self) -> float:
        return self.crowd.t

    def warm_up(self, duration: float) -> None:
        """Crowd-only simulation, the robot standing at its start."""
        for _ in range(int(round(duration / self.dt))):
            self.crowd.step(self.dt, self.robot.pose[:2], self.robot.radius)
        self._agents = None

    def step(self, v: float, omega: float) -> None:
        """One tick: the crowd (reacting to the robot where it stands), then the robot by (v, omega)."""
        if self._follow_target is not None:
            target, self._follow_target = self._follow_target, None
            self.tagged_id = int(self.crowd.add_walkers(np.array([target.start], float), target.route,
                                                        target.speed, agent_type=target.agent_type)[0])
        self.crowd.step(self.dt, self.robot.pose[:2], self.robot.radius)
        self.robot.step(v, omega, self.dt)
        self.ticks += 1
        self._agents = None
        self._check_collision()

    def agents(self) -> AgentStates:
        """Every person now (made once per tick)."""
        if self._agents is None:
            self._agents = self.crowd.states()
        return self._agents

    def tagged_position(self) -> np.ndarray | None:
        """Where the tagged person is (world), or None: none placed, or gone."""
        agents = self.agents()
        row = np.searchsorted(agents.id, self.tagged_id)
        return agents.position[row] if row < len(agents.id) and agents.id[row] == self.tagged_id else None

    def _check_collision(self) -> None:
        xy, radius = self.robot.pose[:2], self.robot.radius
        gap = np.inf
        if len(self.crowd.pos):
            gap = float((np.hypot(*(self.crowd.pos - xy).T) - self.crowd.radius).min()) - radius
        if len(self.walls):
            gap = min(gap, float(closest_on_segments(xy[None], self.walls)[1].min()) - radius)
        self.collided = gap < 0
        if self.collided:
            self.collision_ticks += 1
            if self.first_collision is None:
                self.first_collision = self.crowd.t
