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
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

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
WALL_CHUNK = 1 << 20  # frame-wall distances computed at once (8 MB a temporary), whatever the run's length


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


def _first(mask: np.ndarray) -> int | None:
    k = np.flatnonzero(mask)
    return int(k[0]) if k.size else None


def _wall_distance(xy: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Each point's distance (m) to the nearest wall segment; inf without walls. Chunks of points keep the
    point-wall table small."""
    out = np.full(len(xy), np.inf)
    if not len(walls):
        return out
    a, ab = walls[:, 0], walls[:, 1] - walls[:, 0]
    ab2 = np.maximum((ab * ab).sum(-1), 1e-18)  # a zero-length segment is its point
    step = max(1, WALL_CHUNK // len(walls))
    for lo in range(0, len(xy), step):
        ap = xy[lo:lo + step, None, :] - a
        s = np.clip((ap * ab).sum(-1) / ab2, 0.0, 1.0)
        out[lo:lo + step] = np.hypot(*np.moveaxis(ap - s[..., None] * ab, -1, 0)).min(axis=1)
    return out


def _frame_min(values: np.ndarray, frame: np.ndarray, frames: int) -> np.ndarray:
    """Per frame the smallest of its rows' values; inf in a frame without rows."""
    out = np.full(frames, np.inf)
    np.minimum.at(out, frame, values)
    return out


def _outcome(ep: NavEpisode, person_gap_min: np.ndarray, wall_gap: np.ndarray) -> tuple[int, dict]:
    """The episode's last frame and its outcome. A collision: the robot's disc overlaps a person's or a wall
    (gap < 0). The log covers the time limit when its last frame is within one frame interval of it."""
    elapsed = ep.stamp - ep.stamp[0]
    within = elapsed <= ep.time_limit + 1e-9
    last = int(np.flatnonzero(within)[-1])
    dt = float(np.median(np.diff(ep.stamp))) if len(ep.stamp) > 1 else 0.0
    covers = elapsed[last] >= ep.time_limit - dt - 1e-9
    collided = ((person_gap_min < 0) | (wall_gap < 0)) & within
    c = _first(collided)
    g = _first((np.hypot(*(ep.robot_pose[:, :2] - ep.goal).T) <= ep.goal_radius) & within) \
        if ep.task == "goal" else None
    success = g is not None and (c is None or g < c)
    end = g if success else c if c is not None else last
    out = {"success": bool(success or (ep.task == "follow" and c is None and covers)),
           "collision_person": bool(not success and c is not None and person_gap_min[c] < 0),
           "collision_wall": bool(not success and c is not None and wall_gap[c] < 0),
           "timeout": bool(ep.task == "goal" and not success and c is None and covers),
           "ended_early": bool(not success and c is None and not covers),
           "time_to_goal": float(elapsed[g]) if success else float("nan")}
    return end, out


def _derivative(values: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Finite differences of samples at times ``t``: the rates and the midpoints they belong to."""
    return np.diff(values) / np.diff(t), 0.5 * (t[1:] + t[:-1])


def _mean_peak(values: np.ndarray) -> tuple[float, float]:
    a = np.abs(values)
    return (float(a.mean()), float(a.max())) if a.size else (float("nan"), float("nan"))


def _smoothness(stamp: np.ndarray, pose: np.ndarray) -> dict:
    """Acceleration and jerk of the path speed and of the yaw rate, by finite differences of the log."""
    out = {}
    dt, t1 = np.diff(stamp), 0.5 * (stamp[1:] + stamp[:-1])
    speed = np.hypot(*np.diff(pose[:, :2], axis=0).T) / dt
    turn = wrap_angle(np.diff(pose[:, 2])) / dt
    for name, rate in (("linear", speed), ("angular", turn)):
        acc, t2 = _derivative(rate, t1)
        jerk, _ = _derivative(acc, t2)
        out[f"mean_{name}_acceleration"], out[f"peak_{name}_acceleration"] = _mean_peak(acc)
        out[f"mean_{name}_jerk"], out[f"peak_{name}_jerk"] = _mean_peak(jerk)
    return out


def _time_to_collision(rel_p: np.ndarray, rel_v: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Seconds until two discs (relative position and velocity of one from the other, sum of radii) touch moving at
    constant velocity: the smallest tau >= 0 with |rel_p + tau rel_v| = radii; 0 when they overlap, inf if never."""
    a = (rel_v * rel_v).sum(-1)
    b = (rel_p * rel_v).sum(-1)  # half of the quadratic's b
    c = (rel_p * rel_p).sum(-1) - radii ** 2
    disc = b * b - a * c
    closing = (a > 0) & (b < 0) & (disc >= 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        tau = np.where(closing, (-b - np.sqrt(np.maximum(disc, 0.0))) / a, np.inf)
    return np.where(c <= 0, 0.0, tau)


def social_force(pos_a, vel_a, pos_b, vel_b) -> np.ndarray:
    """The social force (m/s^2, per unit mass) that agents at ``pos_a`` moving at ``vel_a`` exert on agents at
    ``pos_b`` moving at ``vel_b`` (rows paired): Moussaid et al., "Experimental study of the behavioural mechanisms
    underlying self-organization in human crowds", Proc. R. Soc. B 276, 2009, Eq. 2.3-2.5, in lightsfm's
    implementation (``computeSocialForce``, include/sfm.hpp), which HuNavSim's evaluator copies: interaction vector
    I = lambda (v_b - v_a) + e (e the unit vector from b to a), t = I / |I|, B = gamma |I|, theta the angle from t
    to e, f = -A exp(-d / B) [exp(-(n' B theta)^2) t + sign(theta) exp(-(n B theta)^2) t_left], d the centre
    distance. lightsfm's small bias epsilon B on theta is left out, as HuNavSim's evaluator leaves it out."""
    diff = pos_a - pos_b
    d = np.hypot(*diff.T)
    e = diff / np.maximum(d, 1e-12)[:, None]
    inter = SFM_LAMBDA * (vel_b - vel_a) + e
    length = np.maximum(np.hypot(*inter.T), 1e-12)
    t = inter / length[:, None]
    b = SFM_GAMMA * length
    theta = wrap_angle(np.arctan2(e[:, 1], e[:, 0]) - np.arctan2(t[:, 1], t[:, 0]))
    along = -np.exp(-d / b - (SFM_N_PRIME * b * theta) ** 2)
    across = -np.sign(theta) * np.exp(-d / b - (SFM_N * b * theta) ** 2)
    left = np.column_stack([-t[:, 1], t[:, 0]])
    return SFM_SOCIAL * (along[:, None] * t + across[:, None] * left)


def _social_work(stamp, robot_xy, robot_v, robot_r, people: PersonRows, wall_dist) -> float:
    """HuNavSim's social work (``SFM.computeSocialWork``) integrated over time: per frame, |the summed social force
    of the people on the robot| + |the obstacle force on the robot| + the sum over people of |the social force of the
    robot on them|; HuNavSim adds these per frame, we integrate over the stamps (trapezoid rule) so the figure does
    not depend on the logging rate: m/s^2 * s = m/s per unit mass. The obstacle force is lightsfm's with a map (its
    nearest obstacle point: here the nearest wall point): 10 exp(-(distance - robot radius) / 0.2 m)."""
    n = len(stamp)
    rp, rv = robot_xy[people.frame], robot_v[people.frame]
    on_robot = social_force(people.position, people.velocity, rp, rv)
    by_robot = np.hypot(*social_force(rp, rv, people.position, people.velocity).T)
    fx = np.bincount(people.frame, on_robot[:, 0], n)
    fy = np.bincount(people.frame, on_robot[:, 1], n)
    obstacle = SFM_OBSTACLE * np.exp(-(wall_dist - robot_r) / SFM_OBSTACLE_SIGMA)
    work = np.hypot(fx, fy) + obstacle + np.bincount(people.frame, by_robot, n)
    return float(np.trapezoid(work, stamp)) if n > 1 else 0.0


def _crossings(robot_xy, robot_r, people: PersonRows) -> tuple[int, int]:
    """(in front, behind): the times the robot crossed a walking person's path within CROSSING_RANGE of them.

    In the person's frame (x along their velocity, y to their left), the robot is on a side of their path while its
    disc is clear of the strip their disc sweeps: |y| >= robot radius + person radius. A crossing is a change of
    side between consecutive frames of one walking stretch (the person faster than WALKING_SPEED in every frame;
    frames inside the strip between them), so a robot that wanders inside the strip, following straight behind
    someone say, or walks beside them, crosses nothing however much it jitters. Where the robot crossed the path
    (y = 0) is interpolated between the last frame on the old side and the first on the new: in front if x > 0
    there. Sides are relative: a person stepping across a still robot crosses it too; one walking past it does not.
    A side change while the person's heading turned by more than 90 degrees is the person turning, not the robot
    crossing, and does not count."""
    if not len(people.frame):
        return 0, 0
    order = np.lexsort((people.frame, people.id))
    p = people.select(order)
    speed = np.hypot(*p.velocity.T)
    walking = speed > WALKING_SPEED
    u = p.velocity / np.maximum(speed, 1e-12)[:, None]
    rel = robot_xy[p.frame] - p.position
    x = (rel * u).sum(-1)
    y = u[:, 0] * rel[:, 1] - u[:, 1] * rel[:, 0]
    clear = robot_r + p.radius
    side = np.where(walking & (y >= clear), 1, np.where(walking & (y <= -clear), -1, 0))
    rows = np.arange(len(side))
    goes_on = np.r_[False, (p.id[1:] == p.id[:-1]) & (p.frame[1:] == p.frame[:-1] + 1) & walking[1:] & walking[:-1]]
    start = np.maximum.accumulate(np.where(goes_on, 0, rows))  # first row of each row's walking stretch
    last_side = np.maximum.accumulate(np.where(side != 0, rows, -1))  # latest row on a side, up to each row
    prev = np.r_[-1, last_side[:-1]]
    event = (side != 0) & goes_on & (prev >= start)
    event[event] = side[prev[event]] == -side[event]
    b = np.flatnonzero(event)
    a = prev[b]
    xc = x[a] + (x[b] - x[a]) * y[a] / (y[a] - y[b])
    counted = (np.abs(xc) <= CROSSING_RANGE) & ((u[a] * u[b]).sum(-1) > 0)
    front = int(np.count_nonzero(counted & (xc > 0)))
    return front, int(np.count_nonzero(counted)) - front


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
    gap_all = np.hypot(*(people.position - rxy_all[people.frame]).T) - people.radius - ep.robot_radius
    wall_dist_all = _wall_distance(rxy_all, ep.walls)
    end, out = _outcome(ep, _frame_min(gap_all, people.frame, t_all), wall_dist_all - ep.robot_radius)
    n = end + 1
    stamp, pose, rxy = ep.stamp[:n], ep.robot_pose[:n], rxy_all[:n]

    length = float(np.hypot(*np.diff(rxy, axis=0).T).sum())
    out["path_length"] = length
    irregularity = float("nan")
    if ep.task == "goal" and length > 0:
        turned = float(np.abs(wrap_angle(np.diff(pose[:, 2]))).sum())
        bearing = np.arctan2(ep.goal[1] - rxy[0, 1], ep.goal[0] - rxy[0, 0])
        irregularity = max(turned - abs(float(wrap_angle(bearing - pose[0, 2]))), 0.0) / length
    out["path_irregularity"] = irregularity
    out.update(_smoothness(stamp, pose))

    keep = people.frame <= end
    if ep.task == "follow":
        keep &= people.id != ep.target_id
    others, gap = people.select(keep), gap_all[keep]
    gap_min = _frame_min(gap, others.frame, n)
    robot_v = np.gradient(rxy, stamp, axis=0) if n > 1 else np.zeros((1, 2))
    ttc = _time_to_collision(others.position - rxy[others.frame], others.velocity - robot_v[others.frame],
                             others.radius + ep.robot_radius)
    front, behind = _crossings(rxy, ep.robot_radius, others)
    out.update({"min_distance": float(gap.min()) if gap.size else float("inf"),
                "discomfort_frequency": float((gap_min < DISCOMFORT_GAP).mean()),
                "intimate_share": float((gap_min < INTIMATE_GAP).mean()),
                "personal_share": float(((gap_min >= INTIMATE_GAP) & (gap_min < PERSONAL_GAP)).mean()),
                "min_time_to_collision": float(ttc.min()) if ttc.size else float("inf"),
                "social_work": _social_work(stamp, rxy, robot_v, ep.robot_radius, others, wall_dist_all[:n]),
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
