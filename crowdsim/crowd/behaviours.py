"""What people do, as against how they move (crowd.py, forces.py, contacts.py): they arrive (sources, clusters,
standing people and static groups; in groups, of agent types), follow routes of waypoints and queues, stop at
attractions, leave at sinks, and escape from walls that hold them.

A behaviour holds its part of the scenario as arrays and acts once a tick on the crowd's per-agent arrays,
vectorized over agents. The per-agent state it needs it declares in ``columns`` (name -> PerAgent); the crowd keeps
those arrays beside its own, in agent order, so that persons arriving or leaving change all of them at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pipeline.compiled import kernel
from scenarios.geometry import closest_on_segments, segments_cross
from scenarios.typed import Names, Scenario, Section

if TYPE_CHECKING:
    from .crowd import Crowd

ATTRACTION_RATE = 0.05  # 1/s per unit of PedSim's (unitless) attraction strength, while a walker is within reach
STANDING_RADIUS = 0.1  # m, the goal radius of a standing person's spot
RETRY_EMISSION = 0.2  # s: a source whose area is occupied tries again this much later
SLOW_SHARE = 0.2  # a walker slower than this share of its desired speed is held (``Escapes``)


@dataclass(frozen=True)
class PerAgent:
    """One per-agent array: its dtype, the value a newcomer gets (None: whoever adds persons gives it), and the shape
    of one agent's entry."""

    dtype: type
    fill: float | int | bool | None = None
    shape: tuple[int, ...] = ()


class AgentTypes:
    """The agent types (adults, children, elders, ...): each with its desired-speed distribution and body radius."""

    def __init__(self, types: Names):
        self.names = list(types)
        self.speed = np.array([[t.speed_mean, t.speed_std, t.speed_min, t.speed_max]
                               for t in types.values()]).reshape(-1, 4)
        self.radius = np.array([t.radius for t in types.values()])

    def desired_speeds(self, kind: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """One draw per agent from its type's clipped normal distribution."""
        mean, std, lo, hi = self.speed[kind].T
        return np.clip(rng.normal(mean, std), lo, hi)


class GroupIds:
    """Group ids: a new one for each group of two or more, -1 for a person alone."""

    def __init__(self):
        self._next = 1

    def new(self, size: int) -> int:
        if size < 2:
            return -1
        self._next += 1
        return self._next - 1

    def divide(self, count: int, size_weights: list[float], rng: np.random.Generator) -> np.ndarray:
        """Group ids for ``count`` persons, in order: sizes drawn from the weights until all have one, the last group
        cut to the persons left (as PedSim divides a cluster)."""
        w = np.asarray(size_weights, float)
        ids = []
        while len(ids) < count:
            size = min(1 + int(rng.choice(w.size, p=w / w.sum())), count - len(ids))
            ids += [self.new(size)] * size
        return np.array(ids, np.int64)


def at_slowest_pace(v0: np.ndarray, group: np.ndarray) -> np.ndarray:
    """Desired speeds with every group's members at its slowest member's (Moussaid et al. 2010: groups walk
    slower); persons alone (group -1) keep their own."""
    v0 = v0.copy()
    grouped = np.flatnonzero(group >= 0)
    groups, member_of = np.unique(group[grouped], return_inverse=True)
    slowest = np.full(len(groups), np.inf)
    np.minimum.at(slowest, member_of, v0[grouped])
    v0[grouped] = slowest[member_of]
    return v0


class Routes:
    """Routes of stages, each a waypoint (reached within its radius, then stood at for its ``wait``) or a queue
    (left when served), and each person's place on theirs: ``route`` (-1 for standing people, who hold their spot),
    ``stage``, and ``wait_end``, the time a person standing at their waypoint goes on (NaN while not waiting). At
    the end of a route a person leaves the simulation (a sink) or starts over."""

    columns = {"route": PerAgent(np.int64), "stage": PerAgent(np.int64, 0), "wait_end": PerAgent(float, np.nan)}

    def __init__(self, scenario: Scenario):
        self.names = list(scenario.routes)
        wps, queue_names = scenario.waypoints, list(scenario.queues)
        length = max((len(r.waypoints) for r in scenario.routes.values()), default=1)
        shape = (max(len(self.names), 1), length)
        self.goal = np.zeros(shape + (2,))
        self.radius = np.ones(shape)
        self.wait = np.zeros(shape)  # s stood at a waypoint once reached (a group gathering there)
        self.queue = np.full(shape, -1, np.int64)  # the queue a stage is, -1 for a waypoint
        self.length = np.zeros(shape[0], np.int64)
        self.sink = np.zeros(shape[0], bool)
        for k, route in enumerate(scenario.routes.values()):
            for i, stage in enumerate(route.waypoints):
                if stage in queue_names:
                    self.goal[k, i] = scenario.queues[stage].position
                    self.queue[k, i] = queue_names.index(stage)
                else:
                    self.goal[k, i] = wps[stage].position
                    self.radius[k, i] = wps[stage].radius
                    self.wait[k, i] = wps[stage].wait
            self.length[k] = len(route.waypoints)
            self.sink[k] = route.sink
        self.queued_stages = bool((self.queue >= 0).any())  # whether any route has a queue for a stage

    def start(self, route: int, n: int) -> dict:
        """The route-related arrays of ``n`` persons starting on ``route``, for ``Crowd.add``."""
        return {"route": route, "goal": np.repeat(self.goal[route, :1], n, 0),
                "goal_radius": np.full(n, self.radius[route, 0])}

    def stage_queue(self, crowd: Crowd) -> np.ndarray:
        """The queue each person's current stage is; -1 for a waypoint, and for standing people."""
        if not self.queued_stages:
            return np.full(len(crowd.route), -1)
        r = np.maximum(crowd.route, 0)
        return np.where(crowd.route >= 0, self.queue[r, np.minimum(crowd.stage, self.length[r] - 1)], -1)

    def head_for_stage(self, crowd: Crowd, who: np.ndarray) -> None:
        """Point ``who`` at their current stage."""
        crowd.goal[who] = self.goal[crowd.route[who], crowd.stage[who]]
        crowd.goal_radius[who] = self.radius[crowd.route[who], crowd.stage[who]]

    def update(self, crowd: Crowd, served: np.ndarray) -> None:
        """Stop whoever reached a waypoint with a wait; move on whoever reached one without, waited there long
        enough, or was ``served`` at their queue, to their next stage; remove those at the end of a route that ends
        in a sink."""
        r = np.maximum(crowd.route, 0)
        waited = crowd.wait_end <= crowd.t  # NaN, not waiting, compares False
        walking_to_waypoint = ~crowd.holding & (self.stage_queue(crowd) < 0)
        reached = _arrived(crowd.goal, crowd.pos, crowd.goal_radius, walking_to_waypoint)
        wait = self.wait[r, crowd.stage]
        stay = reached & (wait > 0)
        crowd.wait_end[stay] = crowd.t + wait[stay]
        reached = (reached & ~stay) | waited | served
        if not reached.any():
            return
        crowd.wait_end[waited] = np.nan
        crowd.stage[reached] += 1
        done = reached & (crowd.stage >= self.length[r])
        sink = done & self.sink[r]
        crowd.stage[done & ~sink] = 0
        self.head_for_stage(crowd, np.flatnonzero(reached & ~sink))
        if sink.any():
            crowd.keep(~sink)


class Queues:
    """PedSim's waiting queues: a person whose stage is a queue heads for the tail and joins it on arrival; people
    in line hold their slots, ``spacing`` apart from the service point along the queue's direction; the head is
    served for an exponential time and then walks on, and everyone behind moves up a slot (first come, first
    served). ``queued`` is the queue a person stands in, -1 for none."""

    columns = {"queued": PerAgent(np.int64, -1)}

    def __init__(self, scenario: Scenario):
        queues = scenario.queues.values()
        self.head = np.array([q.position for q in queues], float).reshape(-1, 2)
        angle = np.radians([q.direction_deg for q in queues])
        self.direction = np.stack([np.cos(angle), np.sin(angle)], 1).reshape(-1, 2)
        self.spacing = np.array([q.spacing for q in queues], float)
        self.service_time = np.array([q.service_time for q in queues], float)
        self.members: list[list[int]] = [[] for _ in queues]  # ids in line, head first
        self.service_end = np.full(len(queues), np.nan)

    def update(self, crowd: Crowd) -> np.ndarray:
        """Serve, line up and move up the people whose stage is a queue; return who finished being served."""
        served = np.zeros(len(crowd.id), bool)
        if not self.members:
            return served
        stage_queue = crowd.routes.stage_queue(crowd)
        for q, members in enumerate(self.members):
            head = self.head[q]
            step = self.spacing[q] * self.direction[q]
            if members:
                h = int(np.searchsorted(crowd.id, members[0]))
                if np.isnan(self.service_end[q]):
                    if np.linalg.norm(crowd.pos[h] - head) < 0.5:
                        self.service_end[q] = crowd.t + crowd.rng.exponential(self.service_time[q])
                elif crowd.t >= self.service_end[q]:
                    served[h] = True
                    crowd.queued[h] = -1
                    members.pop(0)
                    self.service_end[q] = np.nan
            arriving = np.flatnonzero((stage_queue == q) & (crowd.queued < 0) & ~served)
            if len(arriving):
                tail = head + len(members) * step
                dist = np.linalg.norm(crowd.pos[arriving] - tail, axis=1)
                order = np.argsort(dist, kind="stable")
                for a in arriving[order][dist[order] < 1.0]:  # the few at the tail this step, nearest first
                    members.append(int(crowd.id[a]))
                    crowd.queued[a] = q
                still = arriving[crowd.queued[arriving] < 0]
                crowd.goal[still] = head + len(members) * step
                crowd.goal_radius[still] = 1.0
            if members:
                idx = np.searchsorted(crowd.id, members)
                crowd.goal[idx] = head + np.arange(len(members))[:, None] * step
        return served


class Attractions:
    """PedSim's shopping: a walker passing within reach of an attraction it has not visited is drawn to it at a
    rate proportional to its strength, lingers there for an exponential time, then takes up its route again.
    ``visiting`` is the attraction a person is at, -1 for none."""

    def __init__(self, scenario: Scenario):
        attractions = scenario.attractions.values()
        centre = np.array([a.position for a in attractions], float).reshape(-1, 2)
        half = np.array([a.size for a in attractions], float).reshape(-1, 2) / 2
        self.lo, self.hi = centre - half, centre + half
        self.rate = ATTRACTION_RATE * np.array([a.strength for a in attractions], float)
        self.reach = np.array([a.reach for a in attractions], float)
        self.visit_time = np.array([a.visit_time for a in attractions], float)
        self.columns = {"visiting": PerAgent(np.int64, -1), "visit_end": PerAgent(float, 0.0),
                        "visited": PerAgent(bool, False, (len(self.rate),))}

    def update(self, crowd: Crowd, dt: float) -> None:
        """Send visitors whose time is up back to their route; draw passers-by within reach."""
        if not len(self.rate):
            return
        done = np.flatnonzero((crowd.visiting >= 0) & (crowd.t >= crowd.visit_end))
        crowd.visiting[done] = -1
        crowd.routes.head_for_stage(crowd, done)
        free = np.flatnonzero(~crowd.holding)
        p = crowd.pos[free, None, :]
        spot = np.clip(p, self.lo[None], self.hi[None])  # nearest point of each area
        dist = np.linalg.norm(p - spot, axis=2)
        draw = crowd.rng.random(dist.shape) < -np.expm1(-self.rate * dt)
        drawn = draw & (dist < self.reach) & ~crowd.visited[free]
        who = np.flatnonzero(drawn.any(axis=1))
        a = np.argmax(drawn[who], axis=1)
        k = free[who]
        crowd.visiting[k] = a
        crowd.visited[k, a] = True
        crowd.goal[k] = spot[who, a]
        crowd.visit_end[k] = (crowd.t + dist[who, a] / np.maximum(crowd.v0[k], 0.1)
                              + crowd.rng.exponential(self.visit_time[a]))


class Escapes:
    """The escape from walls and corners that PedSim lacks.

    A walker held for ``stuck_time`` (under ``SLOW_SHARE`` of its desired speed) while a wall hides its goal (the social
    forces balance there) follows the walls, the nearest wall kept on one side (the one that starts it towards its
    goal), until none hides the goal; one stuck again while following (a dead end, a crowd) keeps the wall on the
    other side instead. One held although it sees its goal (a slow walker before a narrow door, where the
    repulsion of the door's two edges outweighs its drive) ignores the walls' social repulsion for ``stuck_time``
    and squeezes through: contacts still keep its body out of the walls. ``escape`` is the side a follower keeps
    the wall on (+-1), else 0; ``squeeze_until`` the time until which a walker ignores the walls' repulsion.
    """

    columns = {"slow_time": PerAgent(float, 0.0), "escape": PerAgent(float, 0.0),
               "squeeze_until": PerAgent(float, 0.0)}

    def __init__(self, stuck_time: float):
        self.stuck_time = stuck_time

    def steer(self, crowd: Crowd, direction: np.ndarray) -> None:
        """Turn the desired ``direction`` of wall followers along the nearest wall."""
        escaping = np.flatnonzero(crowd.escape)
        if len(escaping):
            direction[escaping] = along_nearest_wall(crowd.pos[escaping], crowd.walls, crowd.escape[escaping])

    def repelled_by_walls(self, crowd: Crowd) -> np.ndarray:
        """Who feels the walls' social repulsion: everyone but those squeezing past."""
        return crowd.t >= crowd.squeeze_until

    def update(self, crowd: Crowd, dt: float, holding: np.ndarray) -> None:
        """Count the time each walker has been held; start, turn and end escapes (``holding``: ``crowd.holding``)."""
        crowd.slow_time = _held_for(crowd.slow_time, crowd.vel, crowd.v0, holding, dt)
        escaping = np.flatnonzero(crowd.escape)
        if len(escaping):
            clear = ~crowd.wall_grid.crossed(crowd.pos[escaping], crowd.goal[escaping]) | holding[escaping]
            crowd.escape[escaping[clear]] = 0.0
        stuck = np.flatnonzero(crowd.slow_time >= self.stuck_time)
        if len(stuck) == 0 or len(crowd.walls) == 0:
            return
        crowd.slow_time[stuck] = 0.0
        turning = crowd.escape[stuck] != 0
        crowd.escape[stuck[turning]] *= -1.0
        stuck = stuck[~turning]
        hidden = crowd.wall_grid.crossed(crowd.pos[stuck], crowd.goal[stuck])
        crowd.squeeze_until[stuck[~hidden]] = crowd.t + self.stuck_time
        start = stuck[hidden]
        start = start[closest_on_segments(crowd.pos[start], crowd.walls)[1].min(axis=1) < crowd.radius[start] + 0.3]
        if len(start):
            right = along_nearest_wall(crowd.pos[start], crowd.walls, np.ones(len(start)))
            towards_goal = np.einsum("ij,ij->i", right, crowd.goal[start] - crowd.pos[start]) >= 0
            crowd.escape[start] = np.where(towards_goal, 1.0, -1.0)


def along_nearest_wall(pos: np.ndarray, walls: np.ndarray, side: np.ndarray) -> np.ndarray:
    """Unit tangents of the nearest wall to each of ``pos``, pointed so that the wall lies on ``side`` (+1: on the
    right): following them walks round a wall's end and turns at concave corners (a bug algorithm)."""
    away, d = closest_on_segments(pos, walls)
    k = np.argmin(d, axis=1)
    seg = walls[k, 1] - walls[k, 0]
    tangent = seg / np.maximum(np.linalg.norm(seg, axis=1), 1e-9)[:, None]
    a = away[np.arange(len(pos)), k]
    # the wall on the right: the tangent turned left (+90 degrees) points away from it
    right = tangent[:, 0] * a[:, 1] - tangent[:, 1] * a[:, 0] > 0
    return tangent * np.where(right == (side > 0), 1.0, -1.0)[:, None]


@dataclass
class Source:
    """Where persons enter: a rectangle, a rate of groups, and the weights of routes, group sizes and agent types."""

    position: np.ndarray
    size: np.ndarray
    rate: float  # groups/s
    start: float
    stop: float
    route_ids: np.ndarray
    route_p: np.ndarray
    size_p: np.ndarray
    type_ids: np.ndarray
    type_p: np.ndarray
    next_time: float = np.inf


class Sources:
    """Poisson arrivals of groups at the sources; a group is emitted side by side if the walls leave room, else one
    behind the other, else (or while others stand in the way) it waits."""

    def __init__(self, specs: tuple[Section, ...], types: AgentTypes, routes: Routes, rng: np.random.Generator):
        self.sources = []
        for s in specs:
            weights = np.array(list(s.routes.values()), float)
            sizes = np.array(s.group_size_weights, float)
            size_p = sizes / sizes.sum()
            mean_size = float((np.arange(1, sizes.size + 1) * size_p).sum())
            type_w = np.array(list(s.agent_types.values()), float)
            src = Source(np.array(s.position), np.array(s.size), s.rate / mean_size, s.start, s.stop,
                         np.array([routes.names.index(r) for r in s.routes]), weights / weights.sum(), size_p,
                         np.array([types.names.index(t) for t in s.agent_types]), type_w / type_w.sum())
            src.next_time = src.start + self._interval(src, rng)
            self.sources.append(src)

    @staticmethod
    def _interval(src: Source, rng: np.random.Generator) -> float:
        return float(rng.exponential(1.0 / src.rate)) if src.rate > 0 else np.inf

    def update(self, crowd: Crowd) -> None:
        """Emit the groups due by now."""
        for src in self.sources:
            while src.next_time <= crowd.t and src.next_time <= src.stop:
                if not self._emit(crowd, src):
                    src.next_time = crowd.t + RETRY_EMISSION
                    break
                src.next_time += self._interval(src, crowd.rng)

    def _emit(self, crowd: Crowd, src: Source) -> bool:
        """Emit one group at ``src`` if its area is clear; False when it must wait."""
        rng = crowd.rng
        size = 1 + int(rng.choice(src.size_p.size, p=src.size_p))
        route = int(src.route_ids[rng.choice(src.route_ids.size, p=src.route_p)])
        kind = src.type_ids[rng.choice(src.type_ids.size, size=size, p=src.type_p)]
        r = crowd.types.radius[kind]
        centre = src.position + rng.uniform(-0.5, 0.5, 2) * np.maximum(src.size - 2 * r.max(), 0)
        heading = crowd.routes.goal[route, 0] - centre
        heading /= max(np.linalg.norm(heading), 1e-9)
        offsets = (np.arange(size) - (size - 1) / 2) * (2 * r.max() + 0.1)
        for axis in (np.array([-heading[1], heading[0]]), heading):
            pos = centre + offsets[:, None] * axis
            if _clear_of_walls(crowd.walls, centre, pos, r):
                break
        else:
            return False
        if len(crowd.pos) + size > crowd.p.max_agents:
            return False
        if len(crowd.pos):
            gap = np.linalg.norm(pos[:, None] - crowd.pos[None], axis=-1) - r[:, None] - crowd.radius[None]
            if gap.min() < 0.05:
                return False
        v0 = crowd.types.desired_speeds(kind, rng)
        group = np.full(size, crowd.groups.new(size))
        crowd.add(pos, at_slowest_pace(v0, group), kind, group, **crowd.routes.start(route, size))
        return True


def _clear_of_walls(walls: np.ndarray, centre: np.ndarray, pos: np.ndarray, r: np.ndarray) -> bool:
    """True when bodies at ``pos`` touch no wall and no wall stands between them and ``centre``."""
    if len(walls) == 0:
        return True
    _, dist = closest_on_segments(pos, walls)
    return bool((dist.min(axis=1) >= r + 0.02).all()
                and not segments_cross(np.repeat(centre[None], len(pos), 0), pos, walls).any())


def place_standing(crowd: Crowd, standing: tuple[Section, ...]) -> None:
    """Single standing persons and static conversation groups, the members evenly on a circle ``spacing`` apart
    (turned at random), each holding their spot."""
    for g in standing:
        centre, count = np.array(g.position, float), g.count
        if count == 1:
            pos = centre[None]
        else:
            ring = g.spacing / (2 * np.sin(np.pi / count))
            a = 2 * np.pi * np.arange(count) / count + crowd.rng.uniform(0, 2 * np.pi)
            pos = centre + ring * np.stack([np.cos(a), np.sin(a)], 1)
        kind = np.full(count, crowd.types.names.index(g.agent_type))
        crowd.add(pos, crowd.types.desired_speeds(kind, crowd.rng), kind, crowd.groups.new(count), route=-1,
                  goal=pos.copy(), goal_radius=np.full(count, STANDING_RADIUS))


def place_clusters(crowd: Crowd, clusters: tuple[Section, ...]) -> None:
    """PedSim's agent clusters: persons present from the start, spread at random over a rectangle, divided into
    groups, on a route."""
    for c in clusters:
        count = c.count
        kind = np.full(count, crowd.types.names.index(c.agent_type))
        pos = np.asarray(c.position) + crowd.rng.uniform(-0.5, 0.5, (count, 2)) * c.spread
        group = crowd.groups.divide(count, c.group_size_weights, crowd.rng)
        v0 = at_slowest_pace(crowd.types.desired_speeds(kind, crowd.rng), group)
        crowd.add(pos, v0, kind, group, **crowd.routes.start(crowd.routes.names.index(c.route), count))


@kernel
def _held_for(slow_time, vel, v0, holding, dt):
    """Each walker's time held so far: ``slow_time`` plus ``dt`` for those under ``SLOW_SHARE`` of their desired
    speed ``v0``, 0 for the others and for people holding a spot."""
    out = np.empty(len(v0))
    for i in range(len(v0)):
        slow = not holding[i] and math.sqrt(vel[i, 0] * vel[i, 0] + vel[i, 1] * vel[i, 1]) < SLOW_SHARE * v0[i]
        out[i] = slow_time[i] + dt if slow else 0.0
    return out


@kernel
def _arrived(goal, pos, radius, candidates):
    """Which of the ``candidates`` stand within ``radius`` of their ``goal``."""
    out = np.zeros(len(pos), np.bool_)
    for i in range(len(pos)):
        dx, dy = goal[i, 0] - pos[i, 0], goal[i, 1] - pos[i, 1]
        out[i] = candidates[i] and math.sqrt(dx * dx + dy * dy) < radius[i]
    return out
