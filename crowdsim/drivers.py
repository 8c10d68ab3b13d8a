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

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from pipeline.frames import compose, inverse, transform_points, wrap_angle
from pipeline.navigation.follow import PersonFollower
from pipeline.navigation.planners import PLANNER, build_planner
from pipeline.params import REQUIRED, given, param
from pipeline.types import LaserScan, TagReading
from scenarios.schema import Field, ListOf
from scenarios.typed import plain

if TYPE_CHECKING:
    from pipeline.software import Perception


@dataclass
class Decision:
    """What a navigation driver decided at a cycle: the goal driven to (world; None once the last is reached, and
    when following) and, following, the follower's track of the target (-1: none) and the tag reading it had."""

    goal: np.ndarray | None = None
    target_track: int = -1
    tag: TagReading | None = None


# the latest scan of each laser with the laser's mount in base_link
Scans = list[tuple[LaserScan, np.ndarray]]


@dataclass(kw_only=True, eq=False)
class Driver:
    """A driver that holds still; each kind below overrides what it does. Its declared parameters are keys of the
    scenario's ``robot`` section, which ``of`` makes it from; ``body`` gives the robot's radius and limits (a
    ``Robot``, or that section)."""

    body: Any
    source: str = "<scenario>"  # the scenario file, which the planner's errors name

    name = "none"
    finished = False  # the last goal reached: the run ends

    @classmethod
    def of(cls, robot: Mapping, source: str = "<scenario>") -> Driver:
        return cls(body=robot, source=source, **given(cls, robot))

    def reset(self) -> None:
        pass

    def command(self, world, scans: Scans) -> tuple[float, float]:
        return 0.0, 0.0

    def cycle(self, world, scans: Scans, perception: Perception, tag: TagReading | None) -> Decision:
        return Decision()


@dataclass(kw_only=True, eq=False)
class Repeating(Driver):
    """A driver that may start over at its end."""

    loop: bool = param(True, "drive the route, or the script, again from its start after its end")


@dataclass(kw_only=True, eq=False)
class RouteDriver(Repeating):
    """Round the robot's route, steering on the true pose (a robot localised against its map); it stops when a
    laser return in its path (a corridor as wide as the robot) is nearer than the safety distance."""

    route: list | None = param(None, "m, waypoints the robot drives through", kind="points")
    safety_distance: float = param(0.6, "m, stop when a laser return is this close in front", min=0.0)

    name = "route"

    def __post_init__(self):
        self.waypoints = np.asarray(self.route, float) if self.route else np.zeros((0, 2))

    def reset(self) -> None:
        self.target = 0

    def command(self, world, scans: Scans) -> tuple[float, float]:
        return self.steer(world.robot.pose, front_clearance(scans, self.body.radius))

    def steer(self, pose: np.ndarray, front_clearance: float) -> tuple[float, float]:
        """(v, omega) from ``pose`` towards the next route point; none when something is nearer than the safety
        distance."""
        if len(self.waypoints) == 0 or self.target >= len(self.waypoints):
            return 0.0, 0.0
        goal = self.waypoints[self.target]
        if np.linalg.norm(goal - pose[:2]) < 0.5:
            self.target += 1
            if self.target >= len(self.waypoints):
                if not self.loop:
                    return 0.0, 0.0
                self.target = 0
            goal = self.waypoints[self.target]
        d = goal - pose[:2]
        err = float(wrap_angle(np.arctan2(d[1], d[0]) - pose[2]))
        omega = 2.0 * err
        v = self.body.max_speed * max(0.0, np.cos(err)) if abs(err) < np.pi / 3 else 0.0
        if front_clearance < self.safety_distance:
            v = 0.0
        return v, omega


@dataclass(kw_only=True, eq=False)
class ScriptDriver(Repeating):
    """The rows of ``script`` ([duration, v, omega], held in turn) by the time the robot has been driven, from the
    first again with ``loop``; after the last, standing."""

    script: list | None = param(None, "s, m/s, rad/s: [duration, v, omega] rows the script driver holds in turn (seed "
                                      "003's KTP: the robot still, translating, rotating or driving an arc), within "
                                      "the speed and acceleration limits; after the last, 0 unless `loop`",
                                kind=ListOf(Field(ListOf(Field("float"), min_items=3)), min_items=1))

    name = "script"

    def __post_init__(self):
        self.rows = np.asarray(self.script, float)

    def command(self, world, scans: Scans) -> tuple[float, float]:
        return self.at(world.robot.clock)

    def at(self, clock: float) -> tuple[float, float]:
        ends = np.cumsum(self.rows[:, 0])
        t = clock % ends[-1] if self.loop else clock
        k = int(np.searchsorted(ends, t, side="right"))
        return (0.0, 0.0) if k >= len(self.rows) else (float(self.rows[k, 1]), float(self.rows[k, 2]))


@dataclass(kw_only=True, eq=False)
class PlannerDriver(Driver):
    """A planner's command, made at each tracking cycle and held until the next."""

    planner: Mapping | None = param(None, PLANNER.doc, parts=PLANNER)

    def __post_init__(self):
        self.local_planner = build_planner(plain(self.planner) if self.planner is not None else {"type": "zone"},
                                           self.body, self.source)

    def reset(self) -> None:
        self._command = (0.0, 0.0)

    def command(self, world, scans: Scans) -> tuple[float, float]:
        return self._command

    def _hold(self, command) -> None:
        self._command = (float(command[0]), float(command[1]))


@dataclass(kw_only=True, eq=False)
class GoalsDriver(PlannerDriver):
    """To each of ``goals`` in turn (reached within ``goal_radius`` of the robot's centre), by the planner."""

    goals: list | None = param(None, "m, world: the goals the goals driver visits in order",
                               kind=ListOf(Field("point"), min_items=1))
    goal_radius: float = param(0.3, "m, a goal is reached with the robot's centre this near (CrowdNav: the robot "
                                    "radius, 0.3 m)", min=0.0, exclusive_min=True)

    name = "goals"

    def __post_init__(self):
        super().__post_init__()
        self.waypoints = np.asarray(self.goals or np.zeros((0, 2)), float).reshape(-1, 2)

    def reset(self) -> None:
        super().reset()
        self.local_planner.reset()
        self.goal_index = 0
        self.finished = False

    def cycle(self, world, scans: Scans, perception: Perception, tag: TagReading | None) -> Decision:
        robot = world.robot
        while (self.goal_index < len(self.waypoints)
               and np.hypot(*(self.waypoints[self.goal_index] - robot.pose[:2])) <= self.goal_radius):
            self.goal_index += 1
        if self.goal_index >= len(self.waypoints):
            self.finished = True
            self._hold((0.0, 0.0))
            return Decision()
        goal = self.waypoints[self.goal_index]
        in_odom = transform_points(inverse(robot.world_T_odom), goal[None])[0]
        self._hold(self.local_planner.command(world.t, robot.odom_pose.copy(), robot.velocity.copy(),
                                              obstacles(scans, robot.odom_pose), perception.tracks, in_odom))
        return Decision(goal=goal.copy())


@dataclass(frozen=True, kw_only=True)
class FollowTarget:
    """The person the robot follows, who wears the tag: they join the crowd when recording starts."""

    start: tuple = param(REQUIRED, "m, world: where the target appears when recording starts (after the warm-up)",
                         kind="point")
    route: str = param(REQUIRED, "the route (a name under `routes`) the target walks; with sink: false, round and "
                                 "round", kind="str")
    speed: float = param(REQUIRED, "m/s, the target's desired speed; below robot.max_speed, or the robot could not "
                                   "keep up", kind="float", min=0.0, exclusive_min=True)
    agent_type: str = param("adult", "the target's agent type (its size)")


@dataclass(frozen=True, kw_only=True)
class Following:
    """Whom the follow driver follows, and how near."""

    band: tuple = param([1.0, 2.0], "m, [near, far]: the robot keeps the target's centre this far away "
                                    "(pipeline/navigation/follow.py)", kind="point")
    target: FollowTarget | None = param(None, "the person the robot follows, who wears the tag (required)",
                                        kind=FollowTarget)


@dataclass(kw_only=True, eq=False)
class FollowDriver(PlannerDriver):
    """Behind the tagged person, within ``follow.band``, by the planner (pipeline/navigation/follow.py)."""

    follow: Following | None = param(None, "the follow driver's target and band (required with driver: follow)",
                                     kind=Following)

    name = "follow"

    def __post_init__(self):
        super().__post_init__()
        self.follower = PersonFollower(self.local_planner, tuple(self.follow.band))

    def reset(self) -> None:
        super().reset()
        self.follower.reset()

    def cycle(self, world, scans: Scans, perception: Perception, tag: TagReading | None) -> Decision:
        robot = world.robot
        self._hold(self.follower.command(world.t, robot.odom_pose.copy(), robot.velocity.copy(),
                                         obstacles(scans, robot.odom_pose), perception.tracks, tag))
        return Decision(target_track=int(self.follower.target_track), tag=tag)


DRIVERS: dict[str, type[Driver]] = {d.name: d for d in (RouteDriver, GoalsDriver, FollowDriver, ScriptDriver)}


def make_driver(robot: Mapping, source: str) -> Driver:
    """The driver ``robot.driver`` names, made from the validated ``robot`` section of the scenario ``source``."""
    return DRIVERS[robot.driver].of(robot, source)


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
