"""The pedestrian crowd: vectorized social forces (crowdsim.crowd.forces) with sources, routes, queues and sinks.

Every per-step computation works on arrays over agents or over neighbour pairs found with a k-d tree, so a step
costs O(N log N), not O(N^2). Social forces steer; pymunk then moves the bodies and resolves their contacts (the
force model alone does not keep bodies apart), and a last geometric pass keeps every body out of the walls.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from scenarios.geometry import closest_on_segments, near_segments, pair_vectors, segments_cross, wall_segments

from . import forces
from .contacts import ContactSolver

WALL_PASSES = 4  # push-out passes; two walls of a corner may each need one
ATTRACTION_RATE = 0.05  # 1/s per unit of PedSim's (unitless) attraction strength, while a walker is within reach
ARRIVAL_RADIUS = 0.3  # m: standing people slow down within this distance of their spot, and return to it when pushed


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


@dataclass
class _Source:
    position: np.ndarray
    size: np.ndarray
    rate: float
    start: float
    stop: float
    route_ids: np.ndarray
    route_p: np.ndarray
    size_p: np.ndarray
    type_ids: np.ndarray
    type_p: np.ndarray
    next_time: float


class Crowd:
    """The persons of one scenario; ``step(dt)`` advances them, ``states()`` reports the ground truth."""

    def __init__(self, scenario: dict, rng: np.random.Generator):
        self.p = scenario["crowd"]
        self.rng = rng
        self.t = 0.0
        self.walls = wall_segments(scenario)
        self.contacts = ContactSolver(self.walls, scenario["robot"]["radius"], self.p["max_agents"])
        self._robot_pos: np.ndarray | None = None
        self._next_id = 1
        self._next_group = 1
        types = self.p["agent_types"]
        self.type_names = list(types)
        self.type_speed = np.array([[t["speed_mean"], t["speed_std"], t["speed_min"], t["speed_max"]]
                                    for t in types.values()]).reshape(-1, 4)
        self.type_radius = np.array([t["radius"] for t in types.values()])
        names = self.route_names = list(scenario["routes"])
        wps, queues = scenario["waypoints"], scenario["queues"]
        queue_names = list(queues)
        length = max((len(r["waypoints"]) for r in scenario["routes"].values()), default=1)
        shape = (max(len(names), 1), length)
        self.route_goal = np.zeros(shape + (2,))
        self.route_radius = np.ones(shape)
        self.route_queue = np.full(shape, -1, np.int64)  # the queue a stage is, -1 for a waypoint
        self.route_len = np.zeros(shape[0], np.int64)
        self.route_sink = np.zeros(shape[0], bool)
        for k, name in enumerate(names):
            route = scenario["routes"][name]
            for i, stage in enumerate(route["waypoints"]):
                if stage in queues:
                    self.route_goal[k, i] = queues[stage]["position"]
                    self.route_queue[k, i] = queue_names.index(stage)
                else:
                    self.route_goal[k, i] = wps[stage]["position"]
                    self.route_radius[k, i] = wps[stage]["radius"]
            self.route_len[k] = len(route["waypoints"])
            self.route_sink[k] = route["sink"]
        self.queue_head = np.array([q["position"] for q in queues.values()], float).reshape(-1, 2)
        angle = np.radians([q["direction_deg"] for q in queues.values()])
        self.queue_dir = np.stack([np.cos(angle), np.sin(angle)], 1).reshape(-1, 2)
        self.queue_spacing = np.array([q["spacing"] for q in queues.values()], float)
        self.queue_service = np.array([q["service_time"] for q in queues.values()], float)
        self.queue_members: list[list[int]] = [[] for _ in queues]  # ids in line, head first
        self.queue_service_end = np.full(len(queues), np.nan)
        attractions = scenario["attractions"].values()
        centre = np.array([a["position"] for a in attractions], float).reshape(-1, 2)
        half = np.array([a["size"] for a in attractions], float).reshape(-1, 2) / 2
        self.attraction_lo, self.attraction_hi = centre - half, centre + half
        self.attraction_rate = ATTRACTION_RATE * np.array([a["strength"] for a in attractions], float)
        self.attraction_reach = np.array([a["reach"] for a in attractions], float)
        self.attraction_time = np.array([a["visit_time"] for a in attractions], float)
        self.sources = []
        for s in scenario["sources"]:
            weights = np.array(list(s["routes"].values()), float)
            sizes = np.array(s["group_size_weights"], float)
            size_p = sizes / sizes.sum()
            mean_size = float((np.arange(1, sizes.size + 1) * size_p).sum())
            type_w = np.array(list(s["agent_types"].values()), float)
            src = _Source(np.array(s["position"]), np.array(s["size"]), s["rate"] / mean_size, s["start"], s["stop"],
                          np.array([names.index(r) for r in s["routes"]]), weights / weights.sum(), size_p,
                          np.array([self.type_names.index(t) for t in s["agent_types"]]), type_w / type_w.sum(),
                          np.inf)
            src.next_time = src.start + self._interval(src)
            self.sources.append(src)
        n = 0
        self.id = np.zeros(n, np.int64)
        self.pos = np.zeros((n, 2))
        self.vel = np.zeros((n, 2))
        self.v0 = np.zeros(n)
        self.radius = np.zeros(n)
        self.kind = np.zeros(n, np.int64)  # index into type_names
        self.group = np.zeros(n, np.int64)
        self.route = np.zeros(n, np.int64)  # -1: standing at ``goal``
        self.wp = np.zeros(n, np.int64)
        self.goal = np.zeros((n, 2))
        self.goal_radius = np.zeros(n)
        self.walked = np.zeros(n)
        self.slow_time = np.zeros(n)  # s spent walking at under a fifth of the desired speed
        self.escape = np.zeros(n)  # walkers following a wall to get unstuck: the side the wall is on (+-1), else 0
        self.squeeze_until = np.zeros(n)  # a stuck walker ignores the walls' social repulsion until then (s)
        self.queued = np.zeros(n, np.int64)  # the queue a person stands in, -1 for none
        self.visiting = np.zeros(n, np.int64)  # the attraction a person is visiting, -1 for none
        self.visit_end = np.zeros(n)
        self.visited = np.zeros((n, len(self.attraction_rate)), bool)
        for g in scenario["standing"]:
            self._add_standing(np.array(g["position"], float), g["count"], g["spacing"],
                               self.type_names.index(g["agent_type"]))
        for c in scenario["clusters"]:
            kind = np.full(c["count"], self.type_names.index(c["agent_type"]))
            pos = np.asarray(c["position"]) + self.rng.uniform(-0.5, 0.5, (c["count"], 2)) * c["spread"]
            k = self.route_names.index(c["route"])
            group = self._divide_into_groups(c)
            v0 = self._desired_speeds(kind)
            grouped = np.flatnonzero(group >= 0)
            if len(grouped):  # a group walks at the pace of its slowest member
                _, member_of = np.unique(group[grouped], return_inverse=True)
                slowest = np.full(member_of.max() + 1, np.inf)
                np.minimum.at(slowest, member_of, v0[grouped])
                v0[grouped] = slowest[member_of]
            self._append(pos, v0, kind, group, k, np.repeat(self.route_goal[k, :1], c["count"], 0),
                         np.full(c["count"], self.route_radius[k, 0]))

    # -- population ---------------------------------------------------------------------------------------------

    def _interval(self, src: _Source) -> float:
        return float(self.rng.exponential(1.0 / src.rate)) if src.rate > 0 else np.inf

    def _desired_speeds(self, kind: np.ndarray) -> np.ndarray:
        """One draw per agent from its type's clipped normal distribution."""
        mean, std, lo, hi = self.type_speed[kind].T
        return np.clip(self.rng.normal(mean, std), lo, hi)

    def _append(self, pos, v0, kind, group, route, goal, goal_radius):
        n = len(pos)
        self.contacts.add(self.type_radius[kind])
        self.id = np.concatenate([self.id, np.arange(self._next_id, self._next_id + n)])
        self._next_id += n
        self.pos = np.concatenate([self.pos, pos])
        self.vel = np.concatenate([self.vel, np.zeros((n, 2))])
        self.v0 = np.concatenate([self.v0, v0])
        self.kind = np.concatenate([self.kind, kind])
        self.radius = np.concatenate([self.radius, self.type_radius[kind]])
        self.group = np.concatenate([self.group, np.full(n, group, np.int64)])
        self.route = np.concatenate([self.route, np.full(n, route, np.int64)])
        self.wp = np.concatenate([self.wp, np.zeros(n, np.int64)])
        self.goal = np.concatenate([self.goal, goal])
        self.goal_radius = np.concatenate([self.goal_radius, goal_radius])
        self.walked = np.concatenate([self.walked, np.zeros(n)])
        self.slow_time = np.concatenate([self.slow_time, np.zeros(n)])
        self.escape = np.concatenate([self.escape, np.zeros(n)])
        self.squeeze_until = np.concatenate([self.squeeze_until, np.zeros(n)])
        self.queued = np.concatenate([self.queued, np.full(n, -1, np.int64)])
        self.visiting = np.concatenate([self.visiting, np.full(n, -1, np.int64)])
        self.visit_end = np.concatenate([self.visit_end, np.zeros(n)])
        self.visited = np.concatenate([self.visited, np.zeros((n, self.visited.shape[1]), bool)])

    def add_walkers(self, positions: np.ndarray, route: str, desired_speed: float | None = None,
                    group: bool = False, agent_type: str = "adult") -> np.ndarray:
        """Place persons at ``positions`` [n, 2] on the named route (for tests, benchmarks and scripted scenes);
        returns their ids. Without ``desired_speed`` each draws their own from the agent type's distribution."""
        k = self.route_names.index(route)
        n = len(positions)
        kind = np.full(n, self.type_names.index(agent_type))
        v0 = np.full(n, float(desired_speed)) if desired_speed is not None else self._desired_speeds(kind)
        self._append(np.asarray(positions, float), v0, kind, self._new_group_id(n) if group else -1, k,
                     np.repeat(self.route_goal[k, :1], n, 0), np.full(n, self.route_radius[k, 0]))
        return self.id[len(self.id) - n:].copy()

    def _divide_into_groups(self, cluster: dict) -> np.ndarray:
        """Group ids for a cluster's persons, in order: sizes drawn from its weights until all have one, the last
        group cut to the persons left (as PedSim divides a cluster)."""
        w = np.asarray(cluster["group_size_weights"], float)
        ids = []
        while len(ids) < cluster["count"]:
            size = min(1 + int(self.rng.choice(w.size, p=w / w.sum())), cluster["count"] - len(ids))
            ids += [self._new_group_id(size)] * size
        return np.array(ids, np.int64)

    def _new_group_id(self, size: int) -> int:
        if size < 2:
            return -1
        self._next_group += 1
        return self._next_group - 1

    def _add_standing(self, centre: np.ndarray, count: int, spacing: float, type_index: int):
        if count == 1:
            pos = centre[None]
        else:
            ring = spacing / (2 * np.sin(np.pi / count))
            a = 2 * np.pi * np.arange(count) / count + self.rng.uniform(0, 2 * np.pi)
            pos = centre + ring * np.stack([np.cos(a), np.sin(a)], 1)
        kind = np.full(count, type_index)
        self._append(pos, self._desired_speeds(kind), kind, self._new_group_id(count), -1, pos.copy(),
                     np.full(count, 0.1))

    def _emit(self, src: _Source) -> bool:
        """Emit one group at ``src`` if its area is clear; False when it must wait."""
        size = 1 + int(self.rng.choice(src.size_p.size, p=src.size_p))
        route = int(src.route_ids[self.rng.choice(src.route_ids.size, p=src.route_p)])
        kind = src.type_ids[self.rng.choice(src.type_ids.size, size=size, p=src.type_p)]
        r = self.type_radius[kind]
        centre = src.position + self.rng.uniform(-0.5, 0.5, 2) * np.maximum(src.size - 2 * r.max(), 0)
        heading = self.route_goal[route, 0] - centre
        heading /= max(np.linalg.norm(heading), 1e-9)
        offsets = (np.arange(size) - (size - 1) / 2) * (2 * r.max() + 0.1)
        # side by side if the walls leave room, else one behind the other, else wait
        for axis in (np.array([-heading[1], heading[0]]), heading):
            pos = centre + offsets[:, None] * axis
            if self._clear_of_walls(centre, pos, r):
                break
        else:
            return False
        if len(self.pos) + size > self.p["max_agents"]:
            return False
        if len(self.pos):
            gap = np.linalg.norm(pos[:, None] - self.pos[None], axis=-1) - r[:, None] - self.radius[None]
            if gap.min() < 0.05:
                return False
        # a group walks at the pace of its slowest member (Moussaid et al. 2010: groups walk slower)
        v0 = np.full(size, self._desired_speeds(kind).min())
        self._append(pos, v0, kind, self._new_group_id(size), route, np.repeat(self.route_goal[route, :1], size, 0),
                     np.full(size, self.route_radius[route, 0]))
        return True

    def _clear_of_walls(self, centre: np.ndarray, pos: np.ndarray, r: np.ndarray) -> bool:
        """True when bodies at ``pos`` touch no wall and no wall stands between them and ``centre``."""
        if len(self.walls) == 0:
            return True
        _, dist = closest_on_segments(pos, self.walls)
        return bool((dist.min(axis=1) >= r + 0.02).all()
                    and not segments_cross(np.repeat(centre[None], len(pos), 0), pos, self.walls).any())

    def _run_sources(self):
        for src in self.sources:
            while src.next_time <= self.t and src.next_time <= src.stop:
                if not self._emit(src):
                    src.next_time = self.t + 0.2  # area occupied: try again shortly
                    break
                src.next_time += self._interval(src)

    def _remove(self, keep: np.ndarray):
        self.contacts.keep(keep)
        for name in ("id", "pos", "vel", "v0", "kind", "radius", "group", "route", "wp", "goal", "goal_radius",
                     "walked", "slow_time", "escape", "squeeze_until", "queued", "visiting", "visit_end", "visited"):
            setattr(self, name, getattr(self, name)[keep])

    @property
    def holding(self) -> np.ndarray:
        """Persons who hold a spot rather than walk: standing people, people in a queue or at an attraction."""
        return (self.route < 0) | (self.queued >= 0) | (self.visiting >= 0)

    def _run_queues(self) -> np.ndarray:
        """Line people up at their queue stages (PedSim's waiting queues); return who finished being served.

        A person whose stage is a queue heads for the tail and joins it on arrival; people in line hold their
        slots, spacing apart from the service point along the queue's direction; the head is served for an
        exponential time and then walks on, and everyone behind moves up a slot.
        """
        served = np.zeros(len(self.id), bool)
        if not len(self.queue_members):
            return served
        r = np.maximum(self.route, 0)
        stage_queue = np.where(self.route >= 0, self.route_queue[r, np.minimum(self.wp, self.route_len[r] - 1)], -1)
        for q, members in enumerate(self.queue_members):
            head = self.queue_head[q]
            step = self.queue_spacing[q] * self.queue_dir[q]
            if members:
                h = int(np.searchsorted(self.id, members[0]))
                if np.isnan(self.queue_service_end[q]):
                    if np.linalg.norm(self.pos[h] - head) < 0.5:
                        self.queue_service_end[q] = self.t + self.rng.exponential(self.queue_service[q])
                elif self.t >= self.queue_service_end[q]:
                    served[h] = True
                    self.queued[h] = -1
                    members.pop(0)
                    self.queue_service_end[q] = np.nan
            arriving = np.flatnonzero((stage_queue == q) & (self.queued < 0) & ~served)
            if len(arriving):
                tail = head + len(members) * step
                dist = np.linalg.norm(self.pos[arriving] - tail, axis=1)
                order = np.argsort(dist, kind="stable")
                for a in arriving[order][dist[order] < 1.0]:  # the few at the tail this step, nearest first
                    members.append(int(self.id[a]))
                    self.queued[a] = q
                still = arriving[self.queued[arriving] < 0]
                self.goal[still] = head + len(members) * step
                self.goal_radius[still] = 1.0
            if members:
                idx = np.searchsorted(self.id, members)
                self.goal[idx] = head + np.arange(len(members))[:, None] * step
        return served

    def _run_attractions(self, dt: float) -> None:
        """PedSim's shopping: a walker passing within reach of an attraction it has not visited is drawn to it at
        a rate proportional to its strength, lingers there for an exponential time, then takes up its route again."""
        if not len(self.attraction_rate):
            return
        done = np.flatnonzero((self.visiting >= 0) & (self.t >= self.visit_end))
        self.visiting[done] = -1
        self.goal[done] = self.route_goal[self.route[done], self.wp[done]]
        self.goal_radius[done] = self.route_radius[self.route[done], self.wp[done]]
        free = np.flatnonzero((self.route >= 0) & (self.queued < 0) & (self.visiting < 0))
        p = self.pos[free, None, :]
        spot = np.clip(p, self.attraction_lo[None], self.attraction_hi[None])  # nearest point of each area
        dist = np.linalg.norm(p - spot, axis=2)
        draw = self.rng.random(dist.shape) < -np.expm1(-self.attraction_rate * dt)
        drawn = draw & (dist < self.attraction_reach) & ~self.visited[free]
        who = np.flatnonzero(drawn.any(axis=1))
        a = np.argmax(drawn[who], axis=1)
        k = free[who]
        self.visiting[k] = a
        self.visited[k, a] = True
        self.goal[k] = spot[who, a]
        self.visit_end[k] = (self.t + dist[who, a] / np.maximum(self.v0[k], 0.1)
                             + self.rng.exponential(self.attraction_time[a]))

    def _advance_stages(self, dt: float):
        self._run_attractions(dt)
        served = self._run_queues()
        r = np.maximum(self.route, 0)
        at_waypoint = ((self.route >= 0) & (self.visiting < 0)
                       & (self.route_queue[r, np.minimum(self.wp, self.route_len[r] - 1)] < 0))
        reached = at_waypoint & (np.linalg.norm(self.goal - self.pos, axis=1) < self.goal_radius)
        reached |= served
        if not reached.any():
            return
        self.wp[reached] += 1
        done = reached & (self.wp >= self.route_len[r])
        sink = done & self.route_sink[r]
        self.wp[done & ~sink] = 0
        idx = np.flatnonzero(reached & ~sink)
        self.goal[idx] = self.route_goal[self.route[idx], self.wp[idx]]
        self.goal_radius[idx] = self.route_radius[self.route[idx], self.wp[idx]]
        if sink.any():
            self._remove(~sink)

    # -- forces -------------------------------------------------------------------------------------------------

    def desired_direction(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors towards the current goals (or along the wall for walkers escaping one, see
        ``_update_escapes``) and the desired speeds (standing people slow to their spot)."""
        to_goal = self.goal - self.pos
        dist = np.linalg.norm(to_goal, axis=1)
        e = to_goal / np.maximum(dist, 1e-9)[:, None]
        speed = np.where(self.holding, self.v0 * np.clip(dist / ARRIVAL_RADIUS, 0.0, 1.0), self.v0)
        escaping = np.flatnonzero(self.escape)
        if len(escaping):
            e[escaping] = self._along_nearest_wall(escaping, self.escape[escaping])
        return e, speed

    def _along_nearest_wall(self, who: np.ndarray, side: np.ndarray) -> np.ndarray:
        """Unit tangents of the nearest wall to each of ``who``, pointed so that the wall lies on ``side`` (+1: on
        the right): following them walks round a wall's end and turns at concave corners (a bug algorithm)."""
        away, d = closest_on_segments(self.pos[who], self.walls)
        k = np.argmin(d, axis=1)
        seg = self.walls[k, 1] - self.walls[k, 0]
        tangent = seg / np.maximum(np.linalg.norm(seg, axis=1), 1e-9)[:, None]
        a = away[np.arange(len(who)), k]
        # the wall on the right: the tangent turned left (+90 degrees) points away from it
        right = tangent[:, 0] * a[:, 1] - tangent[:, 1] * a[:, 0] > 0
        return tangent * np.where(right == (side > 0), 1.0, -1.0)[:, None]

    def _update_escapes(self):
        """The escape from walls and corners that PedSim lacks.

        A walker held for ``stuck_time`` while a wall hides its goal (the social forces balance there) follows the
        walls, the nearest wall kept on one side (the one that starts it towards its goal), until none hides the
        goal; one stuck again while following (a dead end, a crowd) keeps the wall on the other side instead. One
        held although it sees its goal (a slow walker before a narrow door, where the repulsion of the door's two
        edges outweighs its drive) ignores the walls' social repulsion for ``stuck_time`` and squeezes through:
        contacts still keep its body out of the walls.
        """
        escaping = np.flatnonzero(self.escape)
        clear = ~segments_cross(self.pos[escaping], self.goal[escaping], self.walls) | self.holding[escaping]
        self.escape[escaping[clear]] = 0.0
        stuck = np.flatnonzero(self.slow_time >= self.p["stuck_time"])
        if len(stuck) == 0 or len(self.walls) == 0:
            return
        self.slow_time[stuck] = 0.0
        turning = self.escape[stuck] != 0
        self.escape[stuck[turning]] *= -1.0
        stuck = stuck[~turning]
        hidden = segments_cross(self.pos[stuck], self.goal[stuck], self.walls)
        self.squeeze_until[stuck[~hidden]] = self.t + self.p["stuck_time"]
        start = stuck[hidden]
        start = start[closest_on_segments(self.pos[start], self.walls)[1].min(axis=1) < self.radius[start] + 0.3]
        if len(start):
            right = self._along_nearest_wall(start, np.ones(len(start)))
            towards_goal = np.einsum("ij,ij->i", right, self.goal[start] - self.pos[start]) >= 0
            self.escape[start] = np.where(towards_goal, 1.0, -1.0)

    def interaction_forces(self, e: np.ndarray) -> np.ndarray:
        """The configured agent-agent force over neighbour pairs from a k-d tree (O(N log N), not O(N^2))."""
        p = self.p
        n = len(self.pos)
        # an unbalanced tree builds faster and queries no slower for crowds
        tree = cKDTree(self.pos, balanced_tree=False, compact_nodes=False) if n > 1 else None
        pairs = (tree.query_pairs(p["interaction_range"], output_type="ndarray") if n > 1
                 else np.zeros((0, 2), np.int64))
        if len(pairs) == 0:
            return np.zeros((n, 2))
        if p["interaction"] == "moussaid2009":
            return forces.moussaid2009(self.pos, self.vel, pairs, p["moussaid_strength"], p["moussaid_lambda"],
                                       p["moussaid_gamma"], p["moussaid_n"], p["moussaid_n_prime"],
                                       walking=~self.holding, direction=e, fov_deg=p["fov_deg"],
                                       out_of_view=p["out_of_view_weight"])
        i = np.concatenate([pairs[:, 0], pairs[:, 1]])
        j = np.concatenate([pairs[:, 1], pairs[:, 0]])
        return forces.helbing_molnar1995(self.pos, self.vel, e, i, j, p["agent_strength"], p["agent_range"],
                                         p["step_time"], p["fov_deg"], p["out_of_view_weight"])

    def acceleration(self, e: np.ndarray, speed: np.ndarray, robot_pos: np.ndarray | None,
                     robot_radius: float) -> np.ndarray:
        """The sum of every force term on every agent, walking in directions ``e`` at desired ``speed``."""
        p = self.p
        acc = forces.desired_force(e, speed, self.vel, p["relaxation_time"])
        acc += self.interaction_forces(e)
        acc += forces.wall_force(self.pos, self.radius, e, self.walls, p["wall_strength"], p["wall_range"],
                                 p["wall_interaction_range"], p["fov_deg"], p["out_of_view_weight"]
                                 ) * (self.t >= self.squeeze_until)[:, None]
        walking_groups = np.where(self.holding, -1, self.group)
        acc += forces.group_forces(self.pos, self.vel, e, self.radius, walking_groups, p["group_gaze"],
                                   p["group_coherence"], p["group_repulsion"])
        if robot_pos is not None:
            acc += forces.obstacle_disc_force(self.pos, e, robot_pos, robot_radius, p["robot_strength"],
                                              p["robot_range"], p["fov_deg"], p["out_of_view_weight"])
        if p["random_force"] > 0:
            acc += self.rng.normal(0.0, p["random_force"], acc.shape)
        return acc

    # -- contacts -----------------------------------------------------------------------------------------------

    def _push_out_of_walls(self, pos: np.ndarray):
        """Move every body that overlaps a wall out along the wall's normal, the deepest overlap first (summing
        pushes from the two walls of a corner would over-correct); a few passes settle corners."""
        if len(self.walls) == 0 or len(pos) == 0:
            return
        for _ in range(WALL_PASSES):
            p, s = near_segments(pos, self.walls, self.radius)
            away, dist = pair_vectors(pos, self.walls, p, s)
            depth = self.radius[p] - dist
            inside = depth > 0
            if not inside.any():
                return
            p, away, dist, depth = p[inside], away[inside], dist[inside], depth[inside]
            order = np.lexsort((-depth, p))
            first = order[np.unique(p[order], return_index=True)[1]]  # each body's deepest wall
            pos[p[first]] += (depth[first] / np.maximum(dist[first], 1e-12))[:, None] * away[first]

    # -- stepping -----------------------------------------------------------------------------------------------

    def step(self, dt: float, robot_pos: np.ndarray | None = None, robot_radius: float = 0.0) -> None:
        self._run_sources()
        if len(self.pos):
            e, speed = self.desired_direction()
            vel = self.vel + self.acceleration(e, speed, robot_pos, robot_radius) * dt
            # The field-of-view weighting makes the forces from those ahead outweigh those from behind, so in a
            # jam the net force points backwards and a whole crowd would walk backwards. Pressure from ahead
            # stops a walker; it does not make them walk backwards (contacts still push bodies physically).
            along = np.einsum("ij,ij->i", vel, e)
            back = ~self.holding & (along < 0)
            vel[back] -= along[back, None] * e[back]
            vmax = self.p["max_speed_factor"] * self.v0
            s = np.linalg.norm(vel, axis=1)
            vel *= np.minimum(1.0, vmax / np.maximum(s, 1e-9))[:, None]
            before = self.pos.copy()
            robot_vel = None
            if robot_pos is not None and self._robot_pos is not None:
                robot_vel = (robot_pos - self._robot_pos) / dt
            parked = np.array([1e6, 1e6])  # no robot in this simulation: its disc waits far away
            self.pos = self.contacts.step(self.pos, vel, dt, parked if robot_pos is None else robot_pos, robot_vel)
            self._push_out_of_walls(self.pos)  # Chipmunk tolerates a little overlap; walls get none
            # pushes from a dense crowd can carry a body across a thin wall within one step: such a body stays put
            crossed = segments_cross(before, self.pos, self.walls)
            self.pos[crossed] = before[crossed]
            self.vel = (self.pos - before) / dt
            speed = np.linalg.norm(self.vel, axis=1)
            self.walked += speed * dt
            slow = ~self.holding & (speed < 0.2 * self.v0)
            self.slow_time = np.where(slow, self.slow_time + dt, 0.0)
            self._update_escapes()
        self._robot_pos = None if robot_pos is None else np.array(robot_pos, float)
        self.t += dt
        self._advance_stages(dt)

    def states(self) -> AgentStates:
        return AgentStates(self.t, self.id.copy(), self.pos.copy(), self.vel.copy(), self.goal.copy(),
                           self.group.copy(), self.walked.copy(), self.radius.copy())
