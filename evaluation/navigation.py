"""Navigation metrics of one episode, computed from logged trajectories only.

Why: a navigation policy (ours in the loop, a gym agent, anyone's planner on real robot logs) is judged with the
figures the social-navigation literature reports, so that its numbers compare with published ones. Everything here
needs only the robot's world pose over time, the people's positions, velocities and radii, the walls and the task:
no simulator state, no end reason logged by the robot (the metrics decide success, collision and timeout).

The episode (``_outcome``) runs from the first frame to the first of: the goal reached (goal tasks), a collision,
the time limit. Every other figure is taken over those frames only, as CrowdNav ends its episodes (Chen et al.,
"Crowd-robot interaction: crowd-aware robot navigation with attention-based deep reinforcement learning", ICRA
2019, and its code's ``Explorer``). Exactly one of success, collision (person or wall), timeout and ended_early
holds. Shares of time are shares of the episode's frames: a run logs the robot at a fixed rate (crowdsim/run.py
writes robot.csv every tracking cycle).

Distances between the robot and a person are the *gap*, centre distance minus both radii (negative: the discs
overlap), as CrowdNav (``dmin``), HuNavSim (``hunav_evaluator/hunav_metrics.py``) and SocNavBench measure them,
unless a figure says centre distance. For a following task, the target takes part in the collision test but not in
the social and passers-by figures, which concern the people the robot shares the space with; the band figures cover
the target.

Each figure, its unit and its source are in ``navigation_metrics``'s docstring and in docs/navigation-metrics.md.

An environment scores every episode it ends (thousands a minute), where numpy's per-call cost on a few thousand rows
was the time: the figures are kernels (``pipeline.compiled``) doing numpy's arithmetic in numpy's order (its
pairwise sums, its median and gradient), so they are the bits the numpy code gave; the angles and exponentials of
the social force stay numpy's calls, one each, since numba's differ in the last bit.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.compiled import by_label, kernel, pairwise
from pipeline.frames import wrap_angle

from .columns import FOLLOWING, PERSONS, ROBOT
from .io import EvaluationInputError, read_table, read_text

__all__ = ["NavEpisode", "PersonRows", "navigation_metrics", "navigation_task", "read_nav_run"]

DISCOMFORT_GAP = 0.2  # m: CrowdNav's discomfort_dist (Chen et al. 2019; its env.config)
INTIMATE_GAP, PERSONAL_GAP = 0.45, 1.2  # m: Hall 1966's intimate and personal zones' outer limits, as HuNavSim's
#                                          indicator_function counts them (intimate < 0.45 <= personal < 1.2)
WALKING_SPEED = 0.3  # m/s: a person faster than this walks and has a path to cross (the task's threshold)
# m: a crossing counts within Hall's social zone of the person (its outer limit, 3.6 m; beyond is public space). Not
# seed 001's security zone reach (R = 1.5 m, Fig. 11): a robot that keeps out of that zone may still cut across a
# passer-by's path 2 m ahead, and that is what the front count is to show.
CROSSING_RANGE = 3.6
# The social force model of HuNavSim's evaluator (hunav_evaluator/sfm.py, the same parameters as lightsfm's
# sfm.hpp): Moussaid et al. 2009's pedestrian interaction with lightsfm's weight; the obstacle force of lightsfm.
SFM_SOCIAL, SFM_LAMBDA, SFM_GAMMA, SFM_N, SFM_N_PRIME = 2.1, 2.0, 0.35, 2.0, 3.0
SFM_OBSTACLE, SFM_OBSTACLE_SIGMA = 10.0, 0.2  # m/s^2, m


@dataclass
class PersonRows:
    """Every person alive in every frame, long format, world frame."""

    frame: np.ndarray  # [M] int, index into NavEpisode.stamp
    id: np.ndarray  # [M] int
    position: np.ndarray  # [M, 2] m
    velocity: np.ndarray  # [M, 2] m/s
    radius: np.ndarray  # [M] m

    def __post_init__(self):
        self.frame = np.asarray(self.frame, np.int64).reshape(-1)
        self.id = np.asarray(self.id, np.int64).reshape(-1)
        m = len(self.frame)
        self.position = np.asarray(self.position, float).reshape(m, 2)
        self.velocity = np.asarray(self.velocity, float).reshape(m, 2)
        self.radius = np.asarray(self.radius, float).reshape(m)
        if len(self.id) != m:
            raise ValueError(f"PersonRows.id has {len(self.id)} rows, frame has {m}")

    def select(self, rows) -> "PersonRows":
        return PersonRows(self.frame[rows], self.id[rows], self.position[rows], self.velocity[rows],
                          self.radius[rows])


@dataclass
class NavEpisode:
    """One navigation episode as logged: the robot's world pose per frame, the people, the walls and the task.
    ``task`` "goal": reach ``goal`` within ``goal_radius``; "follow": keep person ``target_id`` within ``band``
    (centre distance, m) until ``time_limit``, with the follower's belief ``target_track`` (its track id of the
    target, -1 for none) and ``target_visible`` (any robot sensor saw the target) per frame."""

    stamp: np.ndarray  # [T] s, increasing
    robot_pose: np.ndarray  # [T, 3] world x, y (m), yaw (rad)
    robot_radius: float  # m
    persons: PersonRows
    walls: np.ndarray  # [W, 2, 2] m, world segments
    task: str  # "goal" or "follow"
    time_limit: float  # s from the first frame
    goal: np.ndarray | None = None  # [2] m (goal tasks)
    goal_radius: float = float("nan")  # m (goal tasks)
    target_id: int = -1  # following
    band: tuple[float, float] = (1.0, 2.0)  # m, centre distance (following)
    target_track: np.ndarray | None = None  # [T] int (following)
    target_visible: np.ndarray | None = None  # [T] bool (following)

    def __post_init__(self):
        self.stamp = np.asarray(self.stamp, float).reshape(-1)
        t = len(self.stamp)
        self.robot_pose = np.asarray(self.robot_pose, float).reshape(t, 3)
        self.walls = np.asarray(self.walls, float).reshape(-1, 2, 2)
        if t == 0 or (np.diff(self.stamp) <= 0).any():
            raise ValueError("NavEpisode.stamp must hold at least one frame, strictly increasing")
        if len(self.persons.frame) and (self.persons.frame.min() < 0 or self.persons.frame.max() >= t):
            raise ValueError(f"NavEpisode.persons.frame must index stamp's {t} frames")
        if self.task == "goal":
            if self.goal is None:
                raise ValueError("a goal task needs goal and goal_radius")
            self.goal = np.asarray(self.goal, float).reshape(2)
        elif self.task == "follow":
            if self.target_track is None or self.target_visible is None:
                raise ValueError("a follow task needs target_track and target_visible")
            self.target_track = np.asarray(self.target_track, np.int64).reshape(t)
            self.target_visible = np.asarray(self.target_visible, bool).reshape(t)
        else:
            raise ValueError(f"NavEpisode.task must be 'goal' or 'follow', got {self.task!r}")


@kernel
def _least(a, b):
    """numpy's minimum of two numbers: NaN when either is."""
    return a if a < b or a != a else b


@kernel
def _mean_peak(values):
    """Mean and largest |value| (the mean a pairwise sum over the count, as numpy's); NaN for none."""
    if len(values) == 0:
        return np.nan, np.nan
    a = np.abs(values)
    peak = a[0]
    for v in a:
        peak = v if v > peak or v != v else peak
    return pairwise(a, 0, len(a)) / len(a), peak


@kernel
def _person_gaps(frame, position, radius, robot_xy, robot_radius, frames):
    """Each person row's gap to the robot's disc (centre distance minus both radii), and per frame the least (inf
    in a frame without rows)."""
    gap, least = np.empty(len(frame)), np.full(frames, np.inf)
    for i in range(len(frame)):
        f = frame[i]
        gap[i] = math.hypot(position[i, 0] - robot_xy[f, 0], position[i, 1] - robot_xy[f, 1]) - radius[i] \
            - robot_radius
        least[f] = _least(least[f], gap[i])
    return gap, least


@kernel
def _wall_distance(xy, walls):
    """Each point's distance (m) to the nearest wall segment [W, 2, 2] (a zero-length segment is its point); inf
    without walls."""
    out = np.full(len(xy), np.inf)
    for w in range(len(walls)):
        ax, ay = walls[w, 0, 0], walls[w, 0, 1]
        bx, by = walls[w, 1, 0] - ax, walls[w, 1, 1] - ay
        ab2 = max(bx * bx + by * by, 1e-18)
        for i in range(len(xy)):
            px, py = xy[i, 0] - ax, xy[i, 1] - ay
            s = min(max((px * bx + py * by) / ab2, 0.0), 1.0)
            out[i] = _least(out[i], math.hypot(px - s * bx, py - s * by))
    return out


@kernel
def _end_frames(stamp, robot_xy, goal, goal_radius, time_limit, person_gap_min, wall_gap):
    """``_outcome``'s frames: the last within the time limit, the log's median frame interval, the first collision
    and the first at the goal (-1: none; no goal when ``goal`` is empty) within the limit."""
    last, collided, reached = 0, -1, -1
    for i in range(len(stamp)):
        if stamp[i] - stamp[0] <= time_limit + 1e-9:
            last = i
            if collided < 0 and (person_gap_min[i] < 0 or wall_gap[i] < 0):
                collided = i
            if reached < 0 and len(goal) and math.hypot(robot_xy[i, 0] - goal[0],
                                                         robot_xy[i, 1] - goal[1]) <= goal_radius:
                reached = i
    steps = np.sort(stamp[1:] - stamp[:-1])
    m = len(steps)
    if m == 0:
        dt = 0.0
    elif steps[m - 1] != steps[m - 1]:  # np.median: NaN when any is (sorted last)
        dt = np.nan
    elif m % 2:
        dt = steps[m // 2]
    else:
        dt = (steps[m // 2 - 1] + steps[m // 2]) / 2.0
    return last, dt, collided, reached


def _outcome(ep: NavEpisode, person_gap_min: np.ndarray, wall_gap: np.ndarray) -> tuple[int, dict]:
    """The episode's last frame and its outcome. A collision: the robot's disc overlaps a person's or a wall
    (gap < 0). The log covers the time limit when its last frame is within one frame interval of it."""
    goal = ep.goal if ep.task == "goal" else np.zeros(0)
    last, dt, c, g = _end_frames(ep.stamp, ep.robot_pose, goal, ep.goal_radius, ep.time_limit, person_gap_min,
                                 wall_gap)
    covers = ep.stamp[last] - ep.stamp[0] >= ep.time_limit - dt - 1e-9
    success = g >= 0 and (c < 0 or g < c)
    end = g if success else c if c >= 0 else last
    out = {"success": bool(success or (ep.task == "follow" and c < 0 and covers)),
           "collision_person": bool(not success and c >= 0 and person_gap_min[c] < 0),
           "collision_wall": bool(not success and c >= 0 and wall_gap[c] < 0),
           "timeout": bool(ep.task == "goal" and not success and c < 0 and covers),
           "ended_early": bool(not success and c < 0 and not covers),
           "time_to_goal": float(ep.stamp[g] - ep.stamp[0]) if success else float("nan")}
    return end, out


@kernel
def _path(stamp, pose, n):
    """Over frames 0..n-1 (n >= 1): the path length, the total rotation sum |wrap(dyaw)|, and the smoothness
    figures (``SMOOTHNESS_KEYS``' order): acceleration and jerk of the path speed |p_k+1 - p_k| / dt and of the
    yaw rate wrap(dyaw) / dt, by finite differences at the intervals' midpoints."""
    m = n - 1
    step, turn, rates, mid = np.empty(m), np.empty(m), np.empty((2, m)), np.empty(m)
    for i in range(m):
        dt = stamp[i + 1] - stamp[i]
        step[i] = math.hypot(pose[i + 1, 0] - pose[i, 0], pose[i + 1, 1] - pose[i, 1])
        dyaw = wrap_angle(pose[i + 1, 2] - pose[i, 2])
        turn[i] = abs(dyaw)
        rates[0, i], rates[1, i] = step[i] / dt, dyaw / dt
        mid[i] = 0.5 * (stamp[i + 1] + stamp[i])
    out = np.empty(10)
    out[0], out[1] = pairwise(step, 0, m), pairwise(turn, 0, m)
    m1, m2 = max(m - 1, 0), max(m - 2, 0)
    mid2 = np.empty(m1)
    for i in range(m1):
        mid2[i] = 0.5 * (mid[i + 1] + mid[i])
    for r in range(2):
        acc, jerk = np.empty(m1), np.empty(m2)
        for i in range(m1):
            acc[i] = (rates[r, i + 1] - rates[r, i]) / (mid[i + 1] - mid[i])
        for i in range(m2):
            jerk[i] = (acc[i + 1] - acc[i]) / (mid2[i + 1] - mid2[i])
        out[2 + 4 * r], out[3 + 4 * r] = _mean_peak(acc)
        out[4 + 4 * r], out[5 + 4 * r] = _mean_peak(jerk)
    return out


SMOOTHNESS_KEYS = tuple(f"{kind}_{name}_{rate}" for name in ("linear", "angular") for rate in ("acceleration", "jerk")
                        for kind in ("mean", "peak"))


@kernel
def _gradient(xy, stamp, n):
    """``np.gradient(xy[:n], stamp[:n], axis=0)`` (n >= 2), its arithmetic: central differences inside (numpy's
    non-uniform formula unless every interval equals the first), one-sided at the ends."""
    out = np.empty((n, 2))
    dx0 = stamp[1] - stamp[0]
    uniform = True
    for i in range(1, n - 1):
        uniform = uniform and stamp[i + 1] - stamp[i] == dx0
    for i in range(1, n - 1):
        for j in range(2):
            if uniform:
                out[i, j] = (xy[i + 1, j] - xy[i - 1, j]) / (2. * dx0)
            else:
                dx1, dx2 = stamp[i] - stamp[i - 1], stamp[i + 1] - stamp[i]
                a = -dx2 / (dx1 * (dx1 + dx2))
                b = (dx2 - dx1) / (dx1 * dx2)
                c = dx1 / (dx2 * (dx1 + dx2))
                out[i, j] = a * xy[i - 1, j] + b * xy[i, j] + c * xy[i + 1, j]
    dxn = dx0 if uniform else stamp[n - 1] - stamp[n - 2]
    for j in range(2):
        out[0, j] = (xy[1, j] - xy[0, j]) / dx0
        out[n - 1, j] = (xy[n - 1, j] - xy[n - 2, j]) / dxn
    return out


@kernel
def _time_to_collision(px, py, vx, vy, radii):
    """Seconds until two discs (relative position p and velocity v of one from the other, sum of radii) touch moving at
    constant velocity: the smallest tau >= 0 with |p + tau v| = radii; 0 when they overlap, inf if never."""
    a = vx * vx + vy * vy
    b = px * vx + py * vy  # half of the quadratic's b
    c = (px * px + py * py) - radii * radii
    if c <= 0:
        return 0.0
    disc = b * b - a * c
    if a > 0 and b < 0 and disc >= 0:
        return (-b - math.sqrt(disc)) / a
    return np.inf


@kernel
def _social(rows, frame, position, velocity, radius, gap, robot_xy, robot_v, robot_radius, frames):
    """Over person ``rows``: the least gap and the least time to collision (``_time_to_collision``; inf without
    rows), and the counts of frames whose least gap is below DISCOMFORT_GAP, below INTIMATE_GAP, and from it to
    PERSONAL_GAP (a frame without rows in none)."""
    least, closest, soonest = np.full(frames, np.inf), np.inf, np.inf
    for i in rows:
        f = frame[i]
        least[f], closest = _least(least[f], gap[i]), _least(closest, gap[i])
        px, py = position[i, 0] - robot_xy[f, 0], position[i, 1] - robot_xy[f, 1]
        vx, vy = velocity[i, 0] - robot_v[f, 0], velocity[i, 1] - robot_v[f, 1]
        soonest = _least(soonest, _time_to_collision(px, py, vx, vy, radius[i] + robot_radius))
    discomfort = intimate = personal = 0
    for g in least:
        discomfort += g < DISCOMFORT_GAP
        intimate += g < INTIMATE_GAP
        personal += INTIMATE_GAP <= g < PERSONAL_GAP
    return closest, soonest, discomfort, intimate, personal


@kernel
def _force_geometry(pos_a, vel_a, pos_b, vel_b):
    """``social_force``'s geometry, row by row: the centre distance d, B = gamma |I|, the unit vector t of I, and the
    arguments (y [2, M], x [2, M]) of the angles of e and of t."""
    m = len(pos_a)
    d, b, t, y, x = np.empty(m), np.empty(m), np.empty((m, 2)), np.empty((2, m)), np.empty((2, m))
    for i in range(m):
        dx, dy = pos_a[i, 0] - pos_b[i, 0], pos_a[i, 1] - pos_b[i, 1]
        d[i] = math.hypot(dx, dy)
        ex, ey = dx / max(d[i], 1e-12), dy / max(d[i], 1e-12)
        ix = SFM_LAMBDA * (vel_b[i, 0] - vel_a[i, 0]) + ex
        iy = SFM_LAMBDA * (vel_b[i, 1] - vel_a[i, 1]) + ey
        length = max(math.hypot(ix, iy), 1e-12)
        t[i, 0], t[i, 1] = ix / length, iy / length
        b[i] = SFM_GAMMA * length
        y[0, i], x[0, i], y[1, i], x[1, i] = ey, ex, t[i, 1], t[i, 0]
    return d, b, t, y, x


@kernel
def _force_exponents(angle, d, b):
    """theta (the angle from t to e, wrapped) and the exponents [2, M] of the force along t and across it."""
    m = len(d)
    theta, exponent = np.empty(m), np.empty((2, m))
    for i in range(m):
        theta[i] = wrap_angle(angle[0, i] - angle[1, i])
        exponent[0, i] = -d[i] / b[i] - (SFM_N_PRIME * b[i] * theta[i]) ** 2
        exponent[1, i] = -d[i] / b[i] - (SFM_N * b[i] * theta[i]) ** 2
    return theta, exponent


@kernel
def _force(theta, falloff, t):
    """-A [exp(-(n' B theta)^2 - d / B) t + sign(theta) exp(-(n B theta)^2 - d / B) t_left], from the exponentials."""
    out = np.empty((len(theta), 2))
    for i in range(len(theta)):
        along, across = -falloff[0, i], -np.sign(theta[i]) * falloff[1, i]
        out[i, 0] = SFM_SOCIAL * (along * t[i, 0] + across * -t[i, 1])
        out[i, 1] = SFM_SOCIAL * (along * t[i, 1] + across * t[i, 0])
    return out


def social_force(pos_a, vel_a, pos_b, vel_b) -> np.ndarray:
    """The social force (m/s^2, per unit mass) that agents at ``pos_a`` moving at ``vel_a`` exert on agents at
    ``pos_b`` moving at ``vel_b`` (rows paired, [M, 2] each): Moussaid et al., "Experimental study of the
    behavioural mechanisms underlying self-organization in human crowds", Proc. R. Soc. B 276, 2009, Eq. 2.3-2.5, in
    lightsfm's implementation (``computeSocialForce``, include/sfm.hpp), which HuNavSim's evaluator copies:
    interaction vector I = lambda (v_b - v_a) + e (e the unit vector from b to a), t = I / |I|, B = gamma |I|, theta
    the angle from t to e, f = -A exp(-d / B) [exp(-(n' B theta)^2) t + sign(theta) exp(-(n B theta)^2) t_left], d
    the centre distance. lightsfm's small bias epsilon B on theta is left out, as HuNavSim's evaluator leaves it
    out. The angles and exponentials are numpy's (one call each), the rest kernels."""
    rows = [np.asarray(v, float).reshape(-1, 2) for v in (pos_a, vel_a, pos_b, vel_b)]
    if len({len(v) for v in rows}) != 1:
        raise ValueError(f"social_force: pos_a, vel_a, pos_b, vel_b must hold as many rows, got "
                         f"{[len(v) for v in rows]}")
    d, b, t, y, x = _force_geometry(*rows)
    theta, exponent = _force_exponents(np.arctan2(y, x), d, b)
    return _force(theta, np.exp(exponent), t)


@kernel
def _work_pairs(rows, frame, position, velocity, robot_xy, robot_v):
    """The agent pairs of the social work: the people on the robot (rows 0..M-1), then the robot on them."""
    m = len(rows)
    pos_a, vel_a, pos_b, vel_b = np.empty((2 * m, 2)), np.empty((2 * m, 2)), np.empty((2 * m, 2)), np.empty((2 * m, 2))
    for k in range(m):
        i, f = rows[k], frame[rows[k]]
        for j in range(2):
            pos_a[k, j], vel_a[k, j] = position[i, j], velocity[i, j]
            pos_b[k, j], vel_b[k, j] = robot_xy[f, j], robot_v[f, j]
            pos_a[m + k, j], vel_a[m + k, j] = robot_xy[f, j], robot_v[f, j]
            pos_b[m + k, j], vel_b[m + k, j] = position[i, j], velocity[i, j]
    return pos_a, vel_a, pos_b, vel_b


@kernel
def _integrated_work(stamp, force, rows, frame, obstacle):
    """Per frame |the summed force on the robot| + the obstacle force + the sum of |the forces of the robot|, over
    the stamps by the trapezoid rule (numpy's: a pairwise sum of the intervals' d (w1 + w0) / 2)."""
    n, m = len(stamp), len(rows)
    fx, fy, by = np.zeros(n), np.zeros(n), np.zeros(n)
    for k in range(m):
        f = frame[rows[k]]
        fx[f] += force[k, 0]
        fy[f] += force[k, 1]
        by[f] += math.hypot(force[m + k, 0], force[m + k, 1])
    work = np.empty(n)
    for f in range(n):
        work[f] = math.hypot(fx[f], fy[f]) + obstacle[f] + by[f]
    area = np.empty(n - 1)
    for f in range(n - 1):
        area[f] = (stamp[f + 1] - stamp[f]) * (work[f + 1] + work[f]) / 2.0
    return pairwise(area, 0, n - 1)


def _social_work(stamp, robot_xy, robot_v, robot_r, people: PersonRows, rows, wall_dist) -> float:
    """HuNavSim's social work (``SFM.computeSocialWork``) integrated over time: per frame, |the summed social force
    of the people (``rows`` of ``people``) on the robot| + |the obstacle force on the robot| + the sum over people of
    |the social force of the robot on them|; HuNavSim adds these per frame, we integrate over the stamps (trapezoid
    rule) so the figure does not depend on the logging rate: m/s^2 * s = m/s per unit mass. The obstacle force is
    lightsfm's with a map (its nearest obstacle point: here the nearest wall point): 10 exp(-(distance - robot
    radius) / 0.2 m)."""
    if len(stamp) < 2:
        return 0.0
    force = social_force(*_work_pairs(rows, people.frame, people.position, people.velocity, robot_xy, robot_v))
    obstacle = SFM_OBSTACLE * np.exp(-(wall_dist - robot_r) / SFM_OBSTACLE_SIGMA)
    return float(_integrated_work(stamp, force, rows, people.frame, obstacle))


@kernel
def _by_person(rows, frame, ids):
    """``rows`` ordered by person id, then frame (``np.lexsort((frame, id))``'s order: both sorts stable). Rows
    logged frame by frame skip the sort by frame, and a few ids sort by counting."""
    m = len(rows)
    by_frame = np.arange(m)
    for k in range(1, m):
        if frame[rows[k]] < frame[rows[k - 1]]:
            by_frame = np.argsort(frame[rows], kind="mergesort")
            break
    if m == 0:
        return rows
    person = ids[rows][by_frame]
    lo, hi = person.min(), person.max()
    if hi - lo > 4 * m:
        return rows[by_frame[np.argsort(person, kind="mergesort")]]
    _, order = by_label(person - lo, hi - lo + 1)
    return rows[by_frame[order]]


@kernel
def _crossings(rows, frame, ids, position, velocity, radius, robot_xy, robot_r):
    """(in front, behind): the times the robot crossed a walking person's path within CROSSING_RANGE of them, over
    person ``rows``.

    In the person's frame (x along their velocity, y to their left), the robot is on a side of their path while its
    disc is clear of the strip their disc sweeps: |y| >= robot radius + person radius. A crossing is a change of
    side between consecutive frames of one walking stretch (the person faster than WALKING_SPEED in each; any
    frames inside the strip between them), so a robot that wanders inside the strip, following straight behind
    someone say, or walks beside them, crosses nothing however much it jitters. Where the robot crossed the path
    (y = 0) is interpolated between the last frame on the old side and the first on the new: in front if x > 0
    there. Sides are relative: a person stepping across a still robot crosses it too; one walking past does not.
    A side change while the person's heading turned by more than 90 degrees is the person turning, not a
    crossing, and does not count."""
    order = _by_person(rows, frame, ids)
    m = len(order)
    x, y, u = np.empty(m), np.empty(m), np.empty((m, 2))
    side, walking = np.zeros(m, np.int64), np.zeros(m, np.bool_)
    front = behind = 0
    start, last_side = 0, -1  # the first row of the current walking stretch; the latest row on a side
    for k in range(m):
        i = order[k]
        f = frame[i]
        speed = math.hypot(velocity[i, 0], velocity[i, 1])
        walking[k] = speed > WALKING_SPEED
        u[k, 0], u[k, 1] = velocity[i, 0] / max(speed, 1e-12), velocity[i, 1] / max(speed, 1e-12)
        rx, ry = robot_xy[f, 0] - position[i, 0], robot_xy[f, 1] - position[i, 1]
        x[k] = rx * u[k, 0] + ry * u[k, 1]
        y[k] = u[k, 0] * ry - u[k, 1] * rx
        clear = robot_r + radius[i]
        side[k] = 1 if walking[k] and y[k] >= clear else -1 if walking[k] and y[k] <= -clear else 0
        goes_on = k > 0 and ids[i] == ids[order[k - 1]] and f == frame[order[k - 1]] + 1 and walking[k] \
            and walking[k - 1]
        if not goes_on:
            start = k
        a = last_side
        if side[k] != 0:
            last_side = k
            if goes_on and a >= start and side[a] == -side[k]:
                xc = x[a] + (x[k] - x[a]) * y[a] / (y[a] - y[k])
                if abs(xc) <= CROSSING_RANGE and u[a, 0] * u[k, 0] + u[a, 1] * u[k, 1] > 0:
                    if xc > 0:
                        front += 1
                    else:
                        behind += 1
    return front, behind


def _following(ep: NavEpisode, n: int) -> dict:
    """The band figures over the frames the target is alive in, and the follower's losses of it."""
    stamp = ep.stamp[:n]
    lo, hi = ep.band
    rows = (ep.persons.id == ep.target_id) & (ep.persons.frame < n)
    dist = np.full(n, np.nan)
    f = ep.persons.frame[rows]
    dist[f] = np.hypot(*(ep.persons.position[rows] - ep.robot_pose[f, :2]).T)
    dist = dist[~np.isnan(dist)]
    outside = np.maximum(np.maximum(lo - dist, dist - hi), 0.0)
    track = ep.target_track[:n]
    lost = np.flatnonzero((track[:-1] != -1) & (track[1:] != track[:-1])) + 1  # frames the belief lost its track
    valid = np.flatnonzero(track != -1)
    k = np.searchsorted(valid, lost)
    back = np.full(lost.size, n - 1)  # never recovered: until the last frame
    back[k < valid.size] = valid[k[k < valid.size]]
    wait = stamp[back] - stamp[lost]
    return {"distance_error": float(outside.mean()) if dist.size else float("nan"),
            "in_band_share": float(((dist >= lo) & (dist <= hi)).mean()) if dist.size else float("nan"),
            "target_losses": int(lost.size),
            "mean_reacquire_time": float(wait.mean()) if wait.size else float("nan"),
            "max_reacquire_time": float(wait.max()) if wait.size else float("nan"),
            "target_hidden_share": float((~ep.target_visible[:n]).mean())}


FOLLOWING_KEYS = ("distance_error", "in_band_share", "target_losses", "mean_reacquire_time", "max_reacquire_time",
                  "target_hidden_share")


def navigation_metrics(ep: NavEpisode) -> dict:
    """The episode's navigation figures. Distances in m, times in s, shares in [0, 1]; NaN where undefined.

    Outcome (episode and gap as the module says):

    - ``success`` (bool): goal task: the robot's centre within ``goal_radius`` of the goal before any collision and
      within the time limit (CrowdNav's ReachGoal; HuNavSim's ``goal_reached``); follow task: no collision and the
      log covers the time limit (the run was not ended early).
    - ``collision_person``, ``collision_wall`` (bool): the episode ended on the robot's disc overlapping a person's
      disc / a wall segment (gap < 0; CrowdNav's Collision test, walls as segments of no thickness).
    - ``timeout`` (bool): goal task, time limit reached without goal or collision (CrowdNav's Timeout).
    - ``ended_early`` (bool): the log stops before the time limit without goal or collision.
    - ``time_to_goal`` (s): from the first frame to the goal frame; NaN unless success (CrowdNav's nav time).
    - ``path_length`` (m): summed distance between consecutive positions (Perez-Higueras et al. 2018, HuNavSim).
    - ``path_irregularity`` (rad/m): Guzzi et al., "Human-friendly robot navigation in dynamic environments",
      ICRA 2013: "the amount of unnecessary turning per unit path length", unnecessary turning being the robot's
      total rotation, sum |wrap(yaw_k+1 - yaw_k)|, minus the least rotation reaching the goal by the most direct
      path needs, |wrap(bearing from start to goal - yaw_0)| (turn on the spot, drive straight); at least 0; over
      the path length. SocNavBench's docstring quotes the same definition. NaN for a follow task (no fixed goal)
      and for a path of no length.

    Smoothness (finite differences of the log: path speed |p_k+1 - p_k| / dt and yaw rate wrap(dyaw) / dt at the
    intervals' midpoints, then their differences; SocNavBench's and HuNavSim's acceleration and jerk of the linear
    speed, and the same for the angular rate): ``mean_linear_acceleration``, ``peak_linear_acceleration`` (mean and
    largest |.|, m/s^2), ``mean_linear_jerk``, ``peak_linear_jerk`` (m/s^3), ``mean_angular_acceleration``,
    ``peak_angular_acceleration`` (rad/s^2), ``mean_angular_jerk``, ``peak_angular_jerk`` (rad/s^3).

    Social (people other than a following task's target):

    - ``min_distance`` (m): smallest gap to anyone over the episode (negative in a collision; HuNavSim's
      minimum_distance_to_people without its clipping at 0); inf with nobody around.
    - ``discomfort_frequency``: share of frames whose smallest gap is < 0.2 m (Chen et al. 2019, CrowdNav's
      "frequency of being in danger", too_close / steps; a collision frame counts too, where CrowdNav's last step
      reports the collision instead).
    - ``intimate_share``, ``personal_share``: share of frames whose smallest gap is < 0.45 m, in [0.45, 1.2) m (Hall,
      "The Hidden Dimension", 1966; HuNavSim's intimate/personal_space_intrusions over 100). Gap, not centre
      distance: Hall's distances are between the people's bodies (his close intimate phase is contact), and
      HuNavSim measures the gap too, so the figures compare.
    - ``min_time_to_collision`` (s): over frames and people, the time until robot and person, discs moving at
      constant velocity (the person's logged velocity, the robot's by central differences of its positions),
      touch; 0 while overlapping, inf if never on a collision course (the discs' time to collision of Karamouzas,
      Skinner and Guy, "Universal power law governing pedestrian interactions", Phys. Rev. Lett. 113, 2014).
    - ``social_work`` (m/s, per unit mass): HuNavSim's social_work integrated over time (``_social_work``: the
      social force model of Moussaid et al. 2009 with HuNavSim's parameters, ``social_force``).

    Passers-by: ``crossings_front``, ``crossings_behind`` (counts): the robot crossing a walking person's path in
    front of or behind them (``_crossings``); seed 001 (Mekonnen et al., Sec. 7, Fig. 10-11) wants them behind.

    Following (task "follow"; NaN otherwise): ``distance_error`` (m): mean over the frames the target is alive of
    how far the robot-target centre distance d lies outside the band, max(lo - d, d - hi, 0): the band is the
    task's tolerance, so any distance within it is no error (|d - band centre| would penalise a follower for
    holding 1.1 m in a 1-2 m band). ``in_band_share``: share of those frames with lo <= d <= hi.
    ``target_losses``: frames where ``target_track`` goes from an id to -1 or to another id.
    ``mean_reacquire_time``, ``max_reacquire_time`` (s): from each loss to the next frame ``target_track`` is
    not -1 (0 for a change to another id); a loss never recovered counts until the episode's last frame, a lower
    bound. ``target_hidden_share``: share of frames ``target_visible`` is False.
    """
    people, t_all = ep.persons, len(ep.stamp)
    rxy_all = ep.robot_pose[:, :2]
    gap_all, gap_min_all = _person_gaps(people.frame, people.position, people.radius, rxy_all, ep.robot_radius, t_all)
    wall_dist_all = _wall_distance(rxy_all, ep.walls)
    end, out = _outcome(ep, gap_min_all, wall_dist_all - ep.robot_radius)
    n = end + 1
    stamp, pose, rxy = ep.stamp[:n], ep.robot_pose[:n], rxy_all[:n]

    path = _path(stamp, pose, n)
    length = float(path[0])
    out["path_length"] = length
    irregularity = float("nan")
    if ep.task == "goal" and length > 0:
        bearing = np.arctan2(ep.goal[1] - rxy[0, 1], ep.goal[0] - rxy[0, 0])
        irregularity = max(float(path[1]) - abs(float(wrap_angle(bearing - pose[0, 2]))), 0.0) / length
    out["path_irregularity"] = irregularity
    out.update(zip(SMOOTHNESS_KEYS, path[2:].tolist()))

    keep = people.frame <= end
    if ep.task == "follow":
        keep &= people.id != ep.target_id
    rows = np.flatnonzero(keep)
    robot_v = _gradient(rxy, stamp, n) if n > 1 else np.zeros((1, 2))
    closest, soonest, discomfort, intimate, personal = _social(rows, people.frame, people.position, people.velocity,
                                                               people.radius, gap_all, rxy, robot_v,
                                                               ep.robot_radius, n)
    front, behind = _crossings(rows, people.frame, people.id, people.position, people.velocity, people.radius, rxy,
                               ep.robot_radius)
    out.update({"min_distance": closest, "discomfort_frequency": discomfort / n, "intimate_share": intimate / n,
                "personal_share": personal / n, "min_time_to_collision": soonest,
                "social_work": _social_work(stamp, rxy, robot_v, ep.robot_radius, people, rows, wall_dist_all[:n]),
                "crossings_front": front, "crossings_behind": behind})
    out.update(_following(ep, n) if ep.task == "follow" else dict.fromkeys(FOLLOWING_KEYS, float("nan")))
    return out


# ---- reading a run directory ----

ROBOT_COLUMNS = ROBOT.pick("frame", "t", "x", "y", "yaw")  # the true pose
PERSON_COLUMNS = PERSONS.pick(*PERSONS)
FOLLOWING_COLUMNS = FOLLOWING.pick(*FOLLOWING)
NAV_KEYS = ("task", "goal", "goal_radius", "robot_radius", "time_limit", "walls", "target_id", "band")


def _positive(spec: dict, key: str, path: Path) -> float:
    value = spec.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value <= 0:
        raise EvaluationInputError(f"{path}: key {key!r} is {value!r}; expected a number above 0")
    return float(value)


def _pair(spec: dict, key: str, path: Path) -> np.ndarray:
    value = spec.get(key)
    try:
        pair = np.asarray(value, float)
    except (TypeError, ValueError):
        pair = np.zeros(0)
    if pair.shape != (2,) or not np.all(np.isfinite(pair)):
        raise EvaluationInputError(f"{path}: key {key!r} is {value!r}; expected two numbers [a, b]")
    return pair


def _navigation_spec(path: Path) -> dict:
    """navigation.json read and checked (``navigation_task``)."""
    try:
        spec = json.loads(read_text(path))  # UTF-8 (a byte order mark skipped), or one error naming the line
    except json.JSONDecodeError as e:
        raise EvaluationInputError(f"{path}: not JSON ({e}); expected an object with keys {', '.join(NAV_KEYS)}") \
            from None
    return navigation_task(spec, path)


def navigation_task(spec, path) -> dict:
    """A task as navigation.json holds it, checked (known keys only, each of the right kind, the task's own keys
    present; errors name ``path``), as ``NavEpisode``'s task keywords: what ``read_nav_run`` makes of the file, and
    what ``crowdsim navigate`` makes of the same task in memory, so that both score one episode alike."""
    if not isinstance(spec, dict):
        raise EvaluationInputError(f"{path}: expected a JSON object with keys {', '.join(NAV_KEYS)}")
    unknown = sorted(set(spec) - set(NAV_KEYS))
    if unknown:
        raise EvaluationInputError(f"{path}: unknown key(s) {', '.join(map(repr, unknown))}; expected only "
                                   f"{', '.join(NAV_KEYS)}")
    task = spec.get("task")
    if task not in ("goal", "follow"):
        raise EvaluationInputError(f"{path}: key 'task' is {task!r}; expected \"goal\" or \"follow\"")
    out = {"task": task, "robot_radius": _positive(spec, "robot_radius", path),
           "time_limit": _positive(spec, "time_limit", path)}
    try:
        walls = np.asarray(spec.get("walls") or [], float)
    except (TypeError, ValueError):
        walls = np.full(1, np.nan)
    if (walls.size and (walls.ndim != 2 or walls.shape[1] != 4)) or not np.isfinite(walls).all():
        raise EvaluationInputError(f"{path}: key 'walls' is {spec.get('walls')!r}; expected a list of "
                                   f"[x0, y0, x1, y1] segments (m)")
    out["walls"] = walls.reshape(-1, 2, 2)
    if task == "goal":
        out["goal"] = _pair(spec, "goal", path)
        out["goal_radius"] = _positive(spec, "goal_radius", path)
    else:
        target = spec.get("target_id")
        if isinstance(target, bool) or not isinstance(target, int):
            raise EvaluationInputError(f"{path}: key 'target_id' is {target!r}; expected the target person's id "
                                       f"(a whole number)")
        out["target_id"] = target
        band = _pair(spec, "band", path) if spec.get("band") is not None else np.array([1.0, 2.0])
        if not 0 <= band[0] < band[1]:
            raise EvaluationInputError(f"{path}: key 'band' is {spec.get('band')!r}; expected [lo, hi] with "
                                       f"0 <= lo < hi (m)")
        out["band"] = (float(band[0]), float(band[1]))
    return out


def read_nav_run(run_dir) -> NavEpisode:
    """The episode of a run directory: robot.csv (world pose), persons.csv, navigation.json and, for a following
    task, following.csv (layouts in docs/navigation-metrics.md), the rows in the files' order. Bad input raises
    EvaluationInputError naming the file, the key or column, and what was expected. ``crowdsim run`` writes the
    numbers read here at full precision, so its episode is the very one ``crowdsim navigate`` scores in memory
    (crowdsim/navigate.py ``episode_metrics``), and the figures are equal to the last bit."""
    run_dir = Path(run_dir)
    spec = _navigation_spec(run_dir / "navigation.json")
    path = run_dir / ROBOT.file
    robot = read_table(path, ROBOT_COLUMNS)
    frames = robot["frame"].astype(np.int64)
    if not len(frames) or (np.diff(frames) <= 0).any() or (np.diff(robot["t"]) <= 0).any():
        raise EvaluationInputError(f"{path}: expected at least one row, frame and t strictly increasing")

    def frame_index(table: dict, path: Path) -> np.ndarray:
        f = table["frame"].astype(np.int64)
        k = np.minimum(np.searchsorted(frames, f), len(frames) - 1)
        bad = np.flatnonzero(frames[k] != f)
        if bad.size:
            raise EvaluationInputError(f"{path}: frame {f[bad[0]]} is not in robot.csv; expected the frames of "
                                       f"robot.csv")
        return k

    path = run_dir / PERSONS.file
    people = read_table(path, PERSON_COLUMNS)
    if (people["radius"] <= 0).any():
        raise EvaluationInputError(f"{path}: column radius must hold numbers above 0 (m)")
    persons = PersonRows(frame_index(people, path), people["id"].astype(np.int64),
                         np.column_stack([people["x"], people["y"]]), np.column_stack([people["vx"], people["vy"]]),
                         people["radius"])
    if len(np.unique(np.column_stack([persons.frame, persons.id]), axis=0)) != len(persons.frame):
        raise EvaluationInputError(f"{path}: an id appears twice in one frame; expected ids unique within a frame")
    following = {}
    if spec["task"] == "follow":
        path = run_dir / FOLLOWING.file
        table = read_table(path, FOLLOWING_COLUMNS)
        if not np.array_equal(table["frame"].astype(np.int64), frames):
            raise EvaluationInputError(f"{path}: column frame differs from robot.csv's; expected one row per "
                                       f"robot.csv frame, in the same order")
        visible = table["target_visible"].astype(np.int64)
        if not np.isin(visible, (0, 1)).all():
            raise EvaluationInputError(f"{path}: column target_visible must hold 0 or 1")
        following = {"target_track": table["target_track"].astype(np.int64),
                     "target_visible": visible.astype(bool)}
    return NavEpisode(stamp=robot["t"], robot_pose=np.column_stack([robot["x"], robot["y"], robot["yaw"]]),
                      persons=persons, **spec, **following)
