"""The environments' episodes, batched: E worlds (``world.Worlds``), each robot's lasers and people pipeline, the
observations, the reward, the ends of episodes and their logs. ``gym.Env`` and the vector environment are thin
shells round one of these (E = 1 and E = n), so their episodes are the same.

Every random draw of world k comes from the generator its environment was reset with (``reset(k, generator)``),
through child generators spawned from it in a fixed order: the layout, the crowd's random force, the laser's
noise, the tag sensor's. Nothing reads a global generator.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evaluation.navigation import NavEpisode, PersonRows, navigation_metrics
from pipeline.assemble import build_pipeline
from pipeline.frames import compose, inverse, transform_points
from pipeline.software import RobotSoftware
from scenarios import scenario_from_dict
from scenarios.typed import plain
from sensors import Laser, Scene, parts_at
from sensors.body import body_scale
from sensors.tag import TagSensor

from ..errors import Error
from .layouts import LAYOUTS
from .observe import Observer
from .reward import BAND, Reward
from .world import Worlds

TASKS = ("navigate", "follow")
MODES = ("truth", "laser", "tracks")
GOAL_RADIUS = 0.3  # m: the goal is reached when the robot's centre is this near (CrowdNav: within the robot radius)
NOISE_BLOCK = 16  # steps of random force drawn at once per world (one generator call, not one a step)

# The robot, its laser and its pipeline: the scenario defaults (the SPENCER-like platform, a SICK LMS500 at 0.70 m,
# seed 000's segment detector and NNT), with one laser seeing all round, as the airport's two back to back lasers do
ENV_SCENARIO = {
    "name": "env",
    "robot": {"start": [0.0, 0.0, 0.0]},
    "sensors": {"lasers": [{"name": "laser", "mount": [0.0, 0.0, 0.0], "fov_deg": 360.0, "resolution_deg": 1.0,
                            "range_max": 20.0}]},
}


@dataclass
class Config:
    """What ``gymnasium.make`` chooses; ``reset(options=...)`` may change ``scenario``, ``people`` and
    ``robot_visible``."""

    task: str = "navigate"
    observation: tuple[str, ...] = ("truth",)
    scenario: str = "passers_by"
    people: int = 20
    robot_visible: bool = True  # CrowdNav's published results used an invisible robot: False gives that
    control_period: float = 0.2  # s, 5 ticks of 0.04 s
    time_limit: float = 30.0  # s
    k_nearest: int = 10
    reward: str | dict = "default"
    # scenario keys laid over ENV_SCENARIO (a mapping's keys over its keys: {"robot": {"max_speed": 1.0}})
    scenario_overrides: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.task not in TASKS:
            raise Error(f"task: expected one of {TASKS}, got {self.task!r}")
        obs = (self.observation,) if isinstance(self.observation, str) else tuple(self.observation)
        bad = [m for m in obs if m not in MODES]
        if not obs or bad:
            raise Error(f"observation: expected one or more of {MODES}, got {self.observation!r}")
        self.observation = obs
        if self.scenario not in LAYOUTS:
            raise Error(f"scenario: expected one of {sorted(LAYOUTS)}, got {self.scenario!r}")
        if int(self.people) != self.people or self.people < 0:
            raise Error(f"people: expected a whole number >= 0, got {self.people!r}")
        if self.k_nearest < 1:
            raise Error(f"k_nearest: expected at least 1, got {self.k_nearest}")
        if self.time_limit <= 0:
            raise Error(f"time_limit: expected seconds above 0, got {self.time_limit}")


@dataclass
class StepInfo:
    """A step's infos of every episode, as arrays [E] (the reward's terms by name, whether each collided and
    succeeded, its time), and the episode metrics of those that ended (episode -> metrics)."""

    terms: dict[str, np.ndarray]
    collision: np.ndarray
    success: np.ndarray
    time: np.ndarray
    metrics: dict[int, dict]

    def of(self, k: int) -> dict:
        """Episode k's info, as a single environment gives it."""
        info = {"reward_terms": {name: float(value[k]) for name, value in self.terms.items()},
                "collision": bool(self.collision[k]), "success": bool(self.success[k]), "time": float(self.time[k])}
        if k in self.metrics:
            info["episode_metrics"] = self.metrics[k]
        return info


class Episodes:
    """E episodes stepped together."""

    def __init__(self, n: int, config: Config):
        self.n, self.config = n, config
        raw = {key: {**ENV_SCENARIO[key], **value} if isinstance(ENV_SCENARIO.get(key), dict) else value
               for key, value in config.scenario_overrides.items()}
        raw = {**ENV_SCENARIO, **raw}
        self.scenario = scenario_from_dict(raw, source="<environment scenario>")
        self.ticks = int(round(config.control_period / self.scenario.dt))
        if self.ticks < 1 or abs(self.ticks * self.scenario.dt - config.control_period) > 1e-9:
            raise Error(f"control_period: expected a whole number of {self.scenario.dt} s ticks, "
                             f"got {config.control_period}")
        robot = self.scenario.robot
        self.top_speed = np.array([robot.max_speed, robot.max_angular_speed])  # actions of 1 command these
        self.sensing = "laser" in config.observation or "tracks" in config.observation
        self.observer = Observer(config, self.scenario)
        self.reward = Reward(config.reward, config.task)
        self.generators: list[np.random.Generator | None] = [None] * n
        self._build()

    def _build(self) -> None:
        """The worlds, and per world its laser's scene and its pipeline (only when an observation needs them)."""
        c = self.config
        self.worlds = Worlds(self.n, c.people, c.scenario, self.scenario, c.robot_visible)
        self.noise_rng: list[np.random.Generator | None] = [None] * self.n
        w = self.worlds
        self.noise = np.zeros((self.n, NOISE_BLOCK, self.ticks, 2, w.N))  # per world its next steps' draws
        self.noise_next = np.full(self.n, NOISE_BLOCK)  # per world the block's next unused step
        self.everyone = np.arange(self.n)
        self.scenes, self.lasers, self.software = [], [], []
        self.tracks = [None] * self.n
        self.scans = [None] * self.n
        self.start = np.zeros((self.n, 3))
        self.elapsed = np.zeros(self.n)
        self.distance = np.zeros(self.n)
        self._log_arrays(int(np.ceil(c.time_limit / c.control_period)) + 3)
        self.tags: list[TagSensor | None] = [None] * self.n
        self.tag_readings = [None] * self.n

    def apply_options(self, options: dict | None) -> None:
        """``scenario``, ``people`` and ``robot_visible`` from a reset's options: the worlds are made anew."""
        if not options:
            return
        unknown = set(options) - {"scenario", "people", "robot_visible", "reset_mask"}
        if unknown:
            raise Error(f"options: unknown key(s) {sorted(unknown)}; expected scenario, people, robot_visible")
        changed = {k: options[k] for k in ("scenario", "people", "robot_visible") if k in options}
        if changed:
            self.config = Config(**{**self.config.__dict__, **changed})
            self._build()

    def reset(self, k: int, generator: np.random.Generator) -> None:
        """Start episode k over with ``generator`` (the environment's ``np_random``)."""
        self.generators[k] = generator
        layout_rng, noise_rng, laser_rng, tag_rng = generator.spawn(4)
        self.noise_rng[k] = noise_rng
        self.noise_next[k] = NOISE_BLOCK
        self.worlds.reset(k, layout_rng)
        if self.config.task == "follow":
            self.tags[k] = TagSensor(rng=tag_rng)
            self._read_tag(k)
        self.start[k] = self.worlds.robot_pose[k]
        self.elapsed[k] = 0.0
        self.distance[k] = self._goal_distance(k)
        if self.sensing:
            self._reset_sensing(k, laser_rng)
        self.logged[k] = 0
        self._log(np.array([k]), {})

    def _reset_sensing(self, k: int, rng: np.random.Generator) -> None:
        laser_p = self.scenario.sensors.lasers[0]
        if len(self.scenes) < self.n:  # made once per world and kept: a MuJoCo model takes milliseconds to make
            w = self.worlds
            for _ in range(self.n):
                scene = Scene(w.walls, w.robot_radius, max(w.N, 1), parts_at(laser_p.height))
                self.scenes.append(scene)
                self.lasers.append(None)
                self.software.append(RobotSoftware(build_pipeline(plain(self.scenario.pipeline), [laser_p.name]),
                                                   groups=False))
        self.lasers[k] = Laser(scene=self.scenes[k], rng=rng, **laser_p.params)
        self.software[k].reset()
        self._sense(k)

    def _read_tag(self, k: int) -> None:
        """The tag sensor's reading of the target (person 0) at this step, or None."""
        w = self.worlds
        reading = self.tags[k].read(float(w.t[k]), w.robot_pose[k], np.array([w.x[k, 0], w.y[k, 0]]))
        self.tag_readings[k] = reading

    def _goal_distance(self, k: int) -> float:
        w = self.worlds
        return float(np.hypot(*(w.goal[k] - w.robot_pose[k, :2])))

    def odom_pose(self, k: int) -> np.ndarray:
        """The robot's pose in odom (exact odometry: the world pose relative to the start)."""
        return compose(inverse(self.start[k]), self.worlds.robot_pose[k])

    def _sense(self, k: int) -> None:
        """World k's laser scan and, when tracks are observed, one cycle of its robot's software (no groups)."""
        w, laser = self.worlds, self.lasers[k]
        ids = np.arange(1, w.N + 1)
        self.scenes[k].sync(w.robot_pose[k], ids, w.position[k], w.velocity[k], w.walked[k],
                            body_scale(ids, w.radius[k]))
        stamp = float(w.t[k])
        scan = laser.scan(stamp, w.robot_pose[k])
        self.scans[k] = scan
        if "tracks" in self.config.observation:
            software = self.software[k]
            software.receive(scan, laser.pose_in(self.odom_pose(k)))
            self.tracks[k] = software.cycle(stamp).tracks

    def step(self, actions: np.ndarray, unscored: np.ndarray | None = None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, StepInfo]:
        """One control period for every episode: actions [E, 2] in [-1, 1] scaled to the robot's limits. Returns
        rewards, terminated, truncated [E] and the episodes' infos. Episodes ``unscored`` [E] (bool; a vector
        environment's that start over after this step, their info dropped) get no episode metrics."""
        w = self.worlds
        command = np.minimum(np.maximum(np.asarray(actions, float).reshape(self.n, 2), -1.0), 1.0) * self.top_speed
        draws = self._noise_draws()  # [E, ticks, 2, N]
        noise = (draws[:, :, 0] + 1j * draws[:, :, 1]).transpose(1, 0, 2)  # [ticks, E, N]
        gaps, at_collision = w.tick(command, noise)  # at_collision: episode -> its state at its first collision
        gap = gaps.min(axis=0)
        self.elapsed += self.ticks * w.dt
        if self.sensing:
            for k in range(self.n):
                self._sense(k)
        if self.config.task == "follow":
            for k in range(self.n):
                self._read_tag(k)
        before = self.distance.copy()
        self.distance = np.hypot(*(w.goal - w.robot_pose[:, :2]).T)
        collided = gap < 0
        reached = (self.distance < GOAL_RADIUS) & ~collided & (self.config.task == "navigate")
        terminated = collided | reached
        truncated = ~terminated & (self.elapsed >= self.config.time_limit - 1e-9)
        rewards, terms = self.reward(self, before, gap, reached, collided)
        self._log(self.everyone, at_collision)
        metrics = {int(k): self.episode_metrics(k)
                   for k in np.flatnonzero((terminated | truncated) & (True if unscored is None else ~unscored))}
        info = StepInfo({name: value.astype(float) for name, value in terms.items()}, collided, reached,
                        self.elapsed.copy(), metrics)
        return rewards, terminated, truncated, info

    def _noise_draws(self) -> np.ndarray:
        """Every world's random force for this step [E, ticks, 2, N]: the next step of its block, a world whose block
        is used up drawing the next NOISE_BLOCK steps at once (the numbers one call a step would draw, in order)."""
        w = self.worlds
        for k in np.flatnonzero(self.noise_next == NOISE_BLOCK):
            self.noise[k] = self.noise_rng[k].normal(0.0, w.crowd_p.random_force, self.noise.shape[1:])
            self.noise_next[k] = 0
        draws = self.noise[self.everyone, self.noise_next]
        self.noise_next += 1
        return draws

    def _log_arrays(self, frames: int) -> None:
        """Empty logs with room for ``frames`` entries an episode (a step's end state and the follower's belief)."""
        w, n = self.worlds, self.n
        self.log = {"stamp": np.zeros((n, frames)), "pose": np.zeros((n, frames, 3)),
                    "z": np.zeros((n, frames, w.N), complex), "v": np.zeros((n, frames, w.N), complex),
                    "track": np.zeros((n, frames), np.int64), "visible": np.zeros((n, frames), bool)}
        self.logged = np.zeros(n, np.int64)  # entries per episode
        self._person_rows(frames)

    def _person_rows(self, frames: int) -> None:
        """The frame and id of each person row of ``frames`` entries (frame by frame, ids 1..N), sliced per episode."""
        N = self.worlds.N
        self.log_frame, self.log_id = np.repeat(np.arange(frames), N), np.tile(np.arange(1, N + 1), frames)

    def _log(self, worlds: np.ndarray, at_collision: dict) -> None:
        """One entry per step for each of ``worlds``: the state at its end, or at the tick of a collision within it
        (``at_collision``: world -> time, robot pose, persons' positions and velocities); for following, the
        target's track (the pipeline's track nearest the target, within the evaluation's threshold; the target's
        own id when the truth is observed) and whether the laser saw the target."""
        log, w, row = self.log, self.worlds, self.logged[worlds]
        if row.max() >= log["stamp"].shape[1]:  # an episode stepped on past its end: room for twice as many
            self.log = log = {name: np.concatenate([a, np.zeros_like(a)], axis=1) for name, a in log.items()}
            self._person_rows(log["stamp"].shape[1])
        log["stamp"][worlds, row], log["pose"][worlds, row] = w.t[worlds], w.robot_pose[worlds]
        log["z"][worlds, row], log["v"][worlds, row] = w.z[worlds], w.v[worlds]
        for k, (stamp, pose, z, v) in at_collision.items():
            r = self.logged[k]
            log["stamp"][k, r], log["pose"][k, r], log["z"][k, r], log["v"][k, r] = stamp, pose, z, v
        if self.config.task == "follow":
            for k, r in zip(worlds, row):
                log["track"][k, r], log["visible"][k, r] = self._target_seen(k)
        self.logged[worlds] += 1

    def _target_seen(self, k: int) -> tuple[int, bool]:
        if not self.sensing:
            return 1, True
        visible = bool((self.scans[k].person_id == 1).any())
        tracks = self.tracks[k]
        if tracks is None or len(tracks) == 0:
            return -1, visible
        w = self.worlds
        target = transform_points(inverse(self.start[k]), np.array([[w.x[k, 0], w.y[k, 0]]]))[0]
        d = np.hypot(*(tracks.position - target).T)
        best = int(np.argmin(d))
        threshold = self.scenario.evaluation.threshold
        return (int(tracks.track_id[best]) if d[best] <= threshold else -1), visible

    def episode_metrics(self, k: int) -> dict:
        """The navigation metrics of episode k's log (``evaluation.navigation``)."""
        log, w, T = self.log, self.worlds, self.logged[k]
        M = T * w.N
        persons = PersonRows(self.log_frame[:M], self.log_id[:M], log["z"][k, :T].view(float),
                             log["v"][k, :T].view(float), np.tile(w.radius[k], T))
        common = dict(stamp=log["stamp"][k, :T], robot_pose=log["pose"][k, :T], robot_radius=w.robot_radius,
                      persons=persons, walls=w.walls, time_limit=self.config.time_limit)
        if self.config.task == "follow":
            episode = NavEpisode(task="follow", target_id=1, band=BAND, target_track=log["track"][k, :T],
                                 target_visible=log["visible"][k, :T], **common)
        else:
            episode = NavEpisode(task="goal", goal=w.goal[k].copy(), goal_radius=GOAL_RADIUS, **common)
        return navigation_metrics(episode)

    def observe(self) -> dict[str, np.ndarray]:
        return self.observer(self)
