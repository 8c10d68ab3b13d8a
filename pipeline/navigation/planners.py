"""Local planners behind one interface, so that a navigation policy can be swapped and compared in the loop:
``Planner(**params).command(stamp, pose, velocity, obstacles, tracks, goal) -> (v, omega)``.

Every planner sees what a real robot has, all in ``odom``: its odometry pose, the (v, omega) it executed last, the
laser returns as points, the people tracks, and the goal. Each is made from keyword parameters: the robot's
``radius`` (m), ``max_speed`` (m/s) and ``max_angular_speed`` (rad/s), required, its ``max_acceleration`` (m/s^2),
and the planner's own, which it declares on its class with their defaults, ranges and sources (pipeline/params.py
``param``; the scenario's ``robot.planner`` section holds these). ``PLANNERS`` names them:

* ``zone``: Nearness Diagram over the laser points and the security zones of the tracked persons (seed 001 Sec. 7);
* ``nd``: Nearness Diagram over the laser points alone (persons are obstacles like any other);
* ``straight``: turn to the goal and drive, stopping for a laser return ahead (the route driver's safety stop);
* ``social_force``: the robot as a social-force agent (Helbing & Molnar 1995), attracted by the goal and repelled
  by the tracked persons and the laser returns.

Every planner stops within ``goal_tolerance`` of the goal and brakes on the way in (v <= sqrt(2 a s) over the
remaining distance s), so that the robot's acceleration limit does not carry it past the goal; and it brakes the same
way for the nearest laser return in its path (the robot's width ahead, less ``stop_margin``), so that it can always
stop before what it sees ahead: at 1 m/s and 0.5 m/s^2 the robot needs 1 m to stop, more than ND's low-safety speed
law (speed in proportion to the nearest obstacle's distance within ds) allows for a person walking at it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.frames import inverse, transform_points, unrotate
from pipeline.params import Slot, param
from pipeline.types import TrackedPersons

from .nd import NDResult, NearnessDiagram, drive, nearest_per_sector
from .zones import SecurityZones


@dataclass(kw_only=True, eq=False)
class Planner:
    """A local planner: ``command`` gives the (v, omega) for the next tick, ``reset`` starts it over."""

    # the robot's, given by build_planner from the scenario's robot section (not keys of robot.planner)
    radius: float  # m
    max_speed: float  # m/s
    max_angular_speed: float  # rad/s
    max_acceleration: float  # m/s^2, the braking on the way to the goal
    # well inside the follower's band (1-2 m behind the person), so that the follower, not the planner, decides where
    # the robot stops
    goal_tolerance: float = param(0.1, "m, the planner stops this near its goal (well inside the follower's band; an "
                                       "assumption)", min=0.0)
    # a few laser range errors
    stop_margin: float = param(0.05, "m, every planner brakes to stop this short of the nearest laser return in its "
                                     "path (an assumption)", min=0.0)

    def reset(self) -> None:
        """Start over (the planners here keep nothing between calls)."""

    def command(self, stamp: float, pose: np.ndarray, velocity: np.ndarray, obstacles: np.ndarray,
                tracks: TrackedPersons, goal: np.ndarray) -> tuple[float, float]:
        """(v, omega) towards ``goal`` [2]: ``pose`` (3,) the odometry pose, ``velocity`` (v, omega) executed last
        (part of the interface; none of the planners here needs it), ``obstacles`` [m, 2] laser returns (NaN rows
        ignored), ``tracks`` and ``goal`` in odom."""
        base = inverse(np.asarray(pose, float))
        pts = np.asarray(obstacles, float).reshape(-1, 2)
        pts = transform_points(base, pts[np.isfinite(pts).all(axis=1)])
        g = transform_points(base, np.asarray(goal, float).reshape(1, 2))[0]
        remaining = float(np.hypot(g[0], g[1])) - self.goal_tolerance
        if remaining <= 0:
            return 0.0, 0.0
        persons = transform_points(base, tracks.position)
        person_velocity = unrotate(pose, tracks.velocity)  # into base_link
        v, omega = self._command(pts, persons, person_velocity, g)
        ahead = (pts[:, 0] > 0) & (np.abs(pts[:, 1]) < self.radius)
        room = remaining
        if ahead.any():
            room = min(room, float(pts[ahead, 0].min()) - self.radius - self.stop_margin)
        return min(float(v), float(np.sqrt(2.0 * self.max_acceleration * max(room, 0.0)))), float(omega)

    def _command(self, points, persons, person_velocity, goal) -> tuple[float, float]:
        """The planner's own law, everything in base_link."""
        raise NotImplementedError


def _sectors(p: dict):
    if p["sectors"] % 4:
        return "sectors", f"{p['sectors']}; expected a multiple of 4 (the nearness diagram's quadrants)"


@dataclass(kw_only=True, eq=False)
class NDPlanner(Planner):
    """Nearness Diagram (pipeline/navigation/nd.py) over the laser returns; ``last`` keeps its latest result."""

    security_distance: float = param(0.5, "m, ds: obstacles nearer the robot's edge are dangerous (Player's nd "
                                          "driver, avoid_dist)", min=0.0, exclusive_min=True)
    sectors: int = param(180, "sectors of the nearness diagram, a multiple of 4 (Minguez's SECTORES)", min=8)
    wide_fraction: float = param(0.25, "a region wider than this share of the sectors is wide (Minguez & Montano "
                                       "2004)", min=0.0, exclusive_min=True, max=1.0)

    CHECKS = (_sectors,)

    def __post_init__(self) -> None:
        self.nd = NearnessDiagram(self.radius, self.max_speed, self.max_angular_speed, self.security_distance,
                                  self.sectors, self.wide_fraction)
        self.last: NDResult | None = None
        self._turning = 0.0  # the way the robot turns on the spot (+1 left, -1 right, 0 it does not)

    def reset(self) -> None:
        self.last, self._turning = None, 0.0

    def _command(self, points, persons, person_velocity, goal):
        """ND's command, turning on the spot the way it already turns while the direction stays out of reach
        ahead: ND's direction behind the robot (or square to it) flips from one side to the other as people move
        round it, and a robot turning left, then right, then left at each flip faces nowhere for seconds."""
        obstacles, security = self._obstacles(points, persons, person_velocity)
        self.last = self.nd.solve(obstacles, goal, security)
        v, omega = self.last.v, self.last.omega
        if np.isfinite(self.last.direction) and abs(self.last.direction) >= np.pi / 2 - 1e-9:
            if self._turning and np.sign(omega) == -self._turning:
                omega = -omega
            self._turning = float(np.sign(omega))
        else:
            self._turning = 0.0
        return v, omega

    def _obstacles(self, points, persons, person_velocity) -> tuple[np.ndarray, np.ndarray | None]:
        """The points ND avoids and each one's security distance (None: ND's own for all)."""
        return points, None


@dataclass(kw_only=True, eq=False)
class ZonePlanner(NDPlanner):
    """ND over the laser returns plus each tracked person's security zone, seen as a scan of virtual returns from
    ``zone_rays`` rays around the robot (seed 001 Sec. 7: ND with persons as "obstacles with special zone needs").

    A zone the robot is already in cannot be kept out of: if the robot stands in a person's sector (the person walks
    towards it), that zone keeps its disc only; if it is in the disc, the zone is dropped and the laser alone keeps
    the robot off the person.

    Two additions to seed 001's planner, each measured on the bundled ``passers_by`` (README, navigation):

    * the zones' virtual returns get their own security distance, ``zone_security_distance`` (0.2 m), in place of
      ND's 0.5 m for physical obstacles: a zone is already a margin round the person, and ND's margin on top of it
      kept the robot in low safety, crawling and turning, whenever anyone was within 1.5 m;
    * the robot yields to passers-by about to cross its course: a walking person whose path crosses the robot's
      heading line ahead of it within ``yield_time`` (2 s), or, walking slowly, within their sector's reach R plus
      the robot's radius, has the right of way, and the robot's speed is limited so that it reaches the crossing no
      sooner than the person's zone disc (r, plus the robot's radius) has cleared it. Seed 001's sector reaches
      R = 1.5 m ahead of a person, about 1.1 s at walking speed, while this robot takes (2 (r + radius)) /
      max_speed, about 3 s at 0.6 m/s, to cross a person's path: ND alone steers round the sector's tip, across the
      person's path in front of them. ``yield_time`` 0 turns yielding off (person_following does: a following robot
      that gives way to everyone crossing between it and its user loses her).

    The base class (``NDPlanner``) also keeps turning on the spot the way it turns while ND's direction lies out of
    reach ahead, and ND itself (nd.py) counts only obstacles ahead of the robot's axle as dangerous.
    """

    zone_radius: float = param(0.5, "m, r: the disc round each tracked person (seed 001 Fig. 11)", min=0.0,
                               exclusive_min=True)
    zone_reach: float = param(1.5, "m, R: the sector ahead of a walking person (seed 001 Fig. 11)", min=0.0,
                              exclusive_min=True)
    zone_opening_deg: float = param(30.0, "deg, omega: the sector's full opening (seed 001 Fig. 11; "
                                          "pipeline/navigation/zones.py says why full)", min=0.0, exclusive_min=True,
                                    max=180.0)
    standing_speed: float = param(0.25, "m/s, slower tracks get the disc alone (above the tracker's speed for a "
                                        "person standing still; pipeline/navigation/zones.py)", min=0.0)
    # two rays per ND sector, so each sector sees the zone's nearest boundary within 1 deg
    zone_rays: int = param(360, "rays that read the zones as a scan (two per ND sector)", min=8)
    # a zone is a margin kept round a person already (seed 001), so ND's own 0.5 m (for physical obstacles) on top of
    # it doubles the margin; 0.2 m, the gap at which people pass the robot in the crowd model (its robot_range), keeps
    # the robot moving among passers-by (passers_by, seeds 1-20, 2026-11-30: 20 reach the goal with 0.2 m, 17 with
    # 0.3 m, 18 with 0.5 m)
    zone_security_distance: float = param(0.2, "m, ND's security distance for the zones (a zone is a margin already; "
                                                "pipeline/navigation/planners.py says why 0.2)", min=0.0,
                                          exclusive_min=True)
    # 2 s, about the reach of seed 001's sector (1.1 s at 1.34 m/s) and a second more; measured on passers_by (seeds
    # 1-20, 2026-11-30): goal reached in 20 runs with 0.45 crossings in front of a passer-by a run with 2 s; 18 and
    # 0.30 with 3 s; 20 and 0.65 without
    yield_time: float = param(2.0, "s, give way to a passer-by crossing the robot's course ahead within this time "
                                   "(0: never; an addition to seed 001, pipeline/navigation/planners.py)", min=0.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        self.zones = SecurityZones(self.zone_radius, self.zone_reach, np.radians(self.zone_opening_deg),
                                   self.standing_speed)
        n = self.zone_rays
        self.angles = -np.pi + (np.arange(n) + 0.5) * (2 * np.pi / n)
        self.directions = np.stack([np.cos(self.angles), np.sin(self.angles)], axis=1)

    def _obstacles(self, points, persons, person_velocity):
        heading = np.arctan2(person_velocity[:, 1], person_velocity[:, 0])
        walking = np.hypot(person_velocity[:, 0], person_velocity[:, 1]) >= self.zones.standing_speed
        robot = np.zeros((1, 2))
        in_zone = self.zones.inside_each(robot, persons, heading, walking)[0]
        keep = np.hypot(persons[:, 0], persons[:, 1]) > self.zones.r
        walking = walking & ~in_zone
        ranges = self.zones.zone_ranges(robot[0], self.angles, persons[keep], heading[keep], walking[keep])
        hit = np.isfinite(ranges)
        security = np.r_[np.full(len(points), self.security_distance),
                         np.full(int(hit.sum()), self.zone_security_distance)]
        return np.concatenate([points, ranges[hit, None] * self.directions[hit]]), security

    def _command(self, points, persons, person_velocity, goal):
        v, omega = super()._command(points, persons, person_velocity, goal)
        return min(v, self._yield_speed(persons, person_velocity)), omega

    def _yield_speed(self, persons: np.ndarray, person_velocity: np.ndarray) -> float:
        """The highest speed along the robot's heading (base_link x) at which it reaches the course crossing of
        every passer-by due there within ``yield_time`` no sooner than their zone disc has cleared it (inf: no
        one to yield to). A person at (x, y) walking at (vx, vy) crosses the line y = 0 at t = -y / vy, at
        x_c = x + t vx; their disc, grown by the robot's radius, w = r + radius, covers the crossing from
        t - w / |vy| until t + w / |vy|, and the robot's front must not reach x_c - w before then."""
        if self.yield_time <= 0 or not len(persons):
            return np.inf
        vx, vy = person_velocity[:, 0], person_velocity[:, 1]
        crossing = (np.hypot(vx, vy) >= self.zones.standing_speed) & (np.abs(vy) > 1e-6)
        t = -persons[:, 1] / np.where(crossing, vy, 1.0)
        w = self.zones.r + self.radius
        half = w / np.maximum(np.abs(vy), 1e-6)
        clear = t + half
        at = persons[:, 0] + t * vx
        # due within yield_time, or a slow walker's zone (its sector's reach R plus the robot's radius) at the
        # course already
        reach = self.zones.R + self.radius
        due = crossing & ((t <= self.yield_time) | (t * np.hypot(vx, vy) <= reach)) & (clear > 0) & (at > -w)
        if not due.any():
            return np.inf
        return float((np.maximum(at[due] - w, 0.0) / clear[due]).min())


@dataclass(kw_only=True, eq=False)
class StraightPlanner(Planner):
    """Turn to the goal and drive; stop while a laser return lies in the robot's path nearer than
    ``safety_distance`` (crowdsim's route driver and its safety stop, as a planner)."""

    safety_distance: float = param(0.6, "m, stop for a laser return this near ahead (robot.safety_distance)",
                                   min=0.0)
    heading_gain: float = param(2.0, "1/s, omega = gain x heading error (the route driver's)", min=0.0)
    drive_cone_deg: float = param(60.0, "deg, drive only with the goal this near the heading (the route driver's)",
                                  min=0.0, max=180.0)
    corridor_margin: float = param(0.1, "m, the path checked is the robot's width plus this each side", min=0.0)

    def _command(self, points, persons, person_velocity, goal):
        err = float(np.arctan2(goal[1], goal[0]))
        omega = float(np.clip(self.heading_gain * err, -self.max_angular_speed, self.max_angular_speed))
        v = self.max_speed * np.cos(err) if abs(err) < np.radians(self.drive_cone_deg) else 0.0
        ahead = (points[:, 0] > 0) & (np.abs(points[:, 1]) < self.radius + self.corridor_margin)
        if ahead.any() and points[ahead, 0].min() - self.radius < self.safety_distance:
            v = 0.0
        return v, omega


@dataclass(kw_only=True, eq=False)
class SocialForcePlanner(Planner):
    """The robot as a social-force agent (Helbing & Molnar 1995, as robot navigation: Ferrer, Garrell & Sanfeliu,
    IROS 2013): a goal attraction (v0 e - v)/tau, repulsions -grad V0 exp(-b/sigma) from each tracked person and
    -grad U0 exp(-b/R) from the laser returns, b measured from the robot's edge (the robot keeps the clearance a
    pedestrian keeps with its centre). Persons out of the robot's view (``fov_deg`` about the goal direction) weigh
    ``out_of_view_weight``.

    The command is the velocity at which the forces balance, v = v0 e + tau sum(f) (dv/dt = 0 in HM 1995 Eq. 1), at
    most ``max_speed``, driven with ND's differential-drive law; the robot's acceleration limits do the relaxation.
    Laser returns count once per direction (the nearest in each of ``obstacle_sectors`` sectors), so that a wall
    weighs as much near as far whatever the beam density, and those within ``person_radius`` of a track are that
    person's legs, already counted as the person.
    """

    relaxation_time: float = param(0.5, "s, tau (Helbing & Molnar 1995)", min=0.0)
    person_strength: float = param(2.1, "m^2/s^2, V0 of the pedestrian potential (HM 1995)", min=0.0)
    person_range: float = param(0.3, "m, sigma of that potential (HM 1995)", min=0.0, exclusive_min=True)
    obstacle_strength: float = param(10.0, "m^2/s^2, U0 of the wall potential (HM 1995)", min=0.0)
    obstacle_range: float = param(0.2, "m, R of the wall potential (HM 1995)", min=0.0, exclusive_min=True)
    fov_deg: float = param(200.0, "deg, 2 phi, the field of view (HM 1995)", min=0.0, max=360.0)
    out_of_view_weight: float = param(0.5, "c, weight of what is out of view (HM 1995)", min=0.0, max=1.0)
    # 10 deg each: the walls' extent, not the beams', counts
    obstacle_sectors: int = param(36, "laser returns count once per sector (an assumption)", min=1)
    # body radius 0.25 m (scenarios/format.py, adult) plus ~0.15 m of track position error
    person_radius: float = param(0.4, "m, laser returns this near a track are that person's (body 0.25 m plus track "
                                      "error; an assumption)", min=0.0)

    def _command(self, points, persons, person_velocity, goal):
        e = goal / np.hypot(goal[0], goal[1])
        dist = np.hypot(persons[:, 0], persons[:, 1])
        away = -persons / np.maximum(dist, 1e-9)[:, None]
        seen = (persons @ e) >= np.cos(np.radians(self.fov_deg) / 2) * dist
        weight = np.where(seen, 1.0, self.out_of_view_weight)
        push = weight * self.person_strength / self.person_range * np.exp(
            -np.maximum(dist - self.radius, 0.0) / self.person_range)
        force = push @ away
        if len(persons):  # squared point-person distances [m, k] as |a|^2 + |b|^2 - 2 a.b: one matrix product
            d2 = (points ** 2).sum(axis=1)[:, None] + (persons ** 2).sum(axis=1)[None, :] - 2.0 * points @ persons.T
            points = points[d2.min(axis=1) > self.person_radius ** 2]
        d, nearest = nearest_per_sector(points, self.obstacle_sectors)
        seen = np.isfinite(d)
        push = self.obstacle_strength / self.obstacle_range * np.exp(
            -np.maximum(d[seen] - self.radius, 0.0) / self.obstacle_range)
        force = force - push @ (nearest[seen] / d[seen, None])
        want = self.max_speed * e + self.relaxation_time * force
        speed = min(float(np.hypot(want[0], want[1])), self.max_speed)
        return drive(speed, float(np.arctan2(want[1], want[0])), self.max_angular_speed)


PLANNERS: dict[str, type[Planner]] = {
    "zone": ZonePlanner,
    "nd": NDPlanner,
    "straight": StraightPlanner,
    "social_force": SocialForcePlanner,
}


# the planner of the goals and follow drivers (robot.planner): a built-in type, or a class of one's own made as
# Class(**keys), with command(stamp, pose, velocity, obstacles, tracks, goal) and reset()
PLANNER = Slot(PLANNERS, "zone", ("command", "reset"),
               "the local planner of the goals and follow drivers (zone: seed 001 Sec. 7); a built-in type gets the "
               "robot's radius, speed limits and max_acceleration besides its keys, a class of your own is made as "
               "Class(**keys) and needs command(stamp, pose, velocity, obstacles, tracks, goal) -> (v, omega) and "
               "reset() (pipeline/navigation/planners.py)", "planner")

ROBOT_KEYS = ("radius", "max_speed", "max_angular_speed", "max_acceleration")


def build_planner(spec: dict, robot, source: str = "<scenario>") -> Planner:
    """The planner a validated ``robot.planner`` section names (``type`` and its keys): a built-in type, given the
    robot's radius, speed limits and acceleration (``robot``: the robot's body, or the scenario's ``robot`` section)
    besides its keys, or
    a class of one's own, made as ``Class(**keys)`` like the pipeline's parts (pipeline/assemble.py: what its
    constructor raises, and a command that is no (v, omega), are one error naming ``source``'s key)."""
    # here, not at the top: assemble imports the scenario format, which imports this module for the planners' keys
    from pipeline.assemble import check_outputs, make_user_part

    params = {key: value for key, value in spec.items() if key != "type"}
    if spec["type"] in PLANNERS:
        return PLANNERS[spec["type"]](**{key: getattr(robot, key) for key in ROBOT_KEYS}, **params)
    return check_outputs(make_user_part(spec["type"], params, source, "robot.planner"), "planner", source,
                         "robot.planner")
