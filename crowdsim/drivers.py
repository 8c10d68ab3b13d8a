"""Where the robot's command comes from (``robot.driver``): a route, a script, a planner to goals, a planner
following a person. A caller's own (v, omega) (a gym environment, a planner of one's own through
``Simulation.step(command)``) replaces the driver's for that tick.

Each tick the loop asks the driver for the tick's command (``command``); at each tracking cycle it gives the driver
what the robot's software made (``cycle``): the navigation drivers plan then, and hold the command until the next.
A driver sees what the robot has: its odometry pose and last executed (v, omega), the latest laser returns, the
tracks in odom, the goal brought into odom through the robot's localisation in the map (the true world_T_odom, as
the route driver steers by), and for following the tag reading.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.frames import compose, inverse, transform_points, wrap_angle
from pipeline.navigation.follow import PersonFollower
from pipeline.navigation.planners import build_planner
from pipeline.software import Perception
from pipeline.types import LaserScan, TagReading
from scenarios.typed import Section, plain


@dataclass
class Decision:
    """What a navigation driver decided at a cycle: the goal driven to (world; None once the last is reached, and
    when following) and, following, the follower's track of the target (-1: none) and the tag reading it had."""

    goal: np.ndarray | None = None
    target_track: int = -1
    tag: TagReading | None = None


# the latest scan of each laser with the laser's mount in base_link
Scans = list[tuple[LaserScan, np.ndarray]]


class Driver:
    """A driver that holds still; each kind below overrides what it does."""

    name = "none"
    finished = False  # the last goal reached: the run ends

    def reset(self) -> None:
        pass

    def command(self, world, scans: Scans) -> tuple[float, float]:
        return 0.0, 0.0

    def cycle(self, world, scans: Scans, perception: Perception, tag: TagReading | None) -> Decision:
        return Decision()


class RouteDriver(Driver):
    """Round the robot's route, steering on the true pose (a robot localised against its map); it stops when a
    laser return in its path (a corridor as wide as the robot) is nearer than the safety distance."""

    name = "route"

    def __init__(self, robot: Section, source: str = "<scenario>"):
        self.p = robot
        self.route = np.asarray(robot.route, float) if robot.route else np.zeros((0, 2))

    def reset(self) -> None:
        self.target = 0

    def command(self, world, scans: Scans) -> tuple[float, float]:
        return self.steer(world.robot.pose, front_clearance(scans, self.p.radius))

    def steer(self, pose: np.ndarray, front_clearance: float) -> tuple[float, float]:
        """(v, omega) from ``pose`` towards the next route point; none when something is nearer than the safety
        distance."""
        if len(self.route) == 0 or self.target >= len(self.route):
            return 0.0, 0.0
        goal = self.route[self.target]
        if np.linalg.norm(goal - pose[:2]) < 0.5:
            self.target += 1
            if self.target >= len(self.route):
                if not self.p.loop:
                    return 0.0, 0.0
                self.target = 0
            goal = self.route[self.target]
        d = goal - pose[:2]
        err = float(wrap_angle(np.arctan2(d[1], d[0]) - pose[2]))
        omega = 2.0 * err
        v = self.p.max_speed * max(0.0, np.cos(err)) if abs(err) < np.pi / 3 else 0.0
        if front_clearance < self.p.safety_distance:
            v = 0.0
        return v, omega


class ScriptDriver(Driver):
    """The rows of ``script`` ([duration, v, omega], held in turn) by the time the robot has been driven, from the
    first again with ``loop``; after the last, standing."""

    name = "script"

    def __init__(self, robot: Section, source: str = "<scenario>"):
        self.rows = np.asarray(robot.script, float)
        self.loop = robot.loop

    def command(self, world, scans: Scans) -> tuple[float, float]:
        return self.at(world.robot.clock)

    def at(self, clock: float) -> tuple[float, float]:
        ends = np.cumsum(self.rows[:, 0])
        t = clock % ends[-1] if self.loop else clock
        k = int(np.searchsorted(ends, t, side="right"))
        return (0.0, 0.0) if k >= len(self.rows) else (float(self.rows[k, 1]), float(self.rows[k, 2]))


class PlannerDriver(Driver):
    """A planner's command, made at each tracking cycle and held until the next."""

    def reset(self) -> None:
        self._command = (0.0, 0.0)

    def command(self, world, scans: Scans) -> tuple[float, float]:
        return self._command

    def _hold(self, command) -> None:
        self._command = (float(command[0]), float(command[1]))


class GoalsDriver(PlannerDriver):
    """To each of ``robot.goals`` in turn (reached within ``goal_radius`` of the robot's centre), by the planner."""

    name = "goals"

    def __init__(self, robot: Section, source: str):
        self.planner = build_planner(plain(robot.planner), plain(robot), source)
        self.goals = np.asarray(robot.goals or np.zeros((0, 2)), float).reshape(-1, 2)
        self.radius = robot.goal_radius

    def reset(self) -> None:
        super().reset()
        self.planner.reset()
        self.goal_index = 0
        self.finished = False

    def cycle(self, world, scans: Scans, perception: Perception, tag: TagReading | None) -> Decision:
        robot = world.robot
        while (self.goal_index < len(self.goals)
               and np.hypot(*(self.goals[self.goal_index] - robot.pose[:2])) <= self.radius):
            self.goal_index += 1
        if self.goal_index >= len(self.goals):
            self.finished = True
            self._hold((0.0, 0.0))
            return Decision()
        goal = self.goals[self.goal_index]
        in_odom = transform_points(inverse(robot.world_T_odom), goal[None])[0]
        self._hold(self.planner.command(world.t, robot.odom_pose.copy(), robot.velocity.copy(),
                                        obstacles(scans, robot.odom_pose), perception.tracks, in_odom))
        return Decision(goal=goal.copy())


class FollowDriver(PlannerDriver):
    """Behind the tagged person, within ``robot.follow.band``, by the planner (pipeline/navigation/follow.py)."""

    name = "follow"

    def __init__(self, robot: Section, source: str):
        self.planner = build_planner(plain(robot.planner), plain(robot), source)
        self.follower = PersonFollower(self.planner, tuple(robot.follow.band))

    def reset(self) -> None:
        super().reset()
        self.follower.reset()

    def cycle(self, world, scans: Scans, perception: Perception, tag: TagReading | None) -> Decision:
        robot = world.robot
        self._hold(self.follower.command(world.t, robot.odom_pose.copy(), robot.velocity.copy(),
                                         obstacles(scans, robot.odom_pose), perception.tracks, tag))
        return Decision(target_track=int(self.follower.target_track), tag=tag)


DRIVERS: dict[str, type[Driver]] = {d.name: d for d in (RouteDriver, ScriptDriver, GoalsDriver, FollowDriver)}


def make_driver(robot: Section, source: str) -> Driver:
    """The driver ``robot.driver`` names, made from the validated ``robot`` section of the scenario ``source``."""
    return DRIVERS[robot.driver](robot, source)


def front_clearance(scans: Scans, radius: float) -> float:
    """Distance to the nearest laser return in the robot's path (a corridor as wide as the robot)."""
    best = np.inf
    for scan, mount in scans:
        pts = transform_points(mount, scan.points())
        ahead = (pts[:, 0] > 0) & (np.abs(pts[:, 1]) < radius + 0.1)
        if ahead.any():
            best = min(best, float(pts[ahead, 0].min()) - radius)
    return best


def obstacles(scans: Scans, odom_pose: np.ndarray) -> np.ndarray:
    """The latest laser returns in odom [n, 2]."""
    points = [transform_points(compose(odom_pose, mount), scan.points()) for scan, mount in scans]
    return np.concatenate(points) if points else np.zeros((0, 2))
