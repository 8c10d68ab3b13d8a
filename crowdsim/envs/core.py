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
        self.scenes, self.lasers, self.software = [], [], []
        self.tracks = [None] * self.n
        self.scans = [None] * self.n
        self.start = np.zeros((self.n, 3))
        self.elapsed = np.zeros(self.n)
        self.distance = np.zeros(self.n)
        self.log: list[list] = [[] for _ in range(self.n)]
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
        self.worlds.reset(k, layout_rng)
        if self.config.task == "follow":
            self.tags[k] = TagSensor(rng=tag_rng)
            self._read_tag(k)
        self.start[k] = self.worlds.robot_pose[k]
        self.elapsed[k] = 0.0
        self.distance[k] = self._goal_distance(k)
        if self.sensing:
            self._reset_sensing(k, laser_rng)
        self.log[k] = []
        self._log(k, None)

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

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict]]:
        """One control period for every episode: actions [E, 2] in [-1, 1] scaled to the robot's limits. Returns
        rewards, terminated, truncated [E] and one info per episode."""
        w = self.worlds
        command = np.minimum(np.maximum(np.asarray(actions, float).reshape(self.n, 2), -1.0), 1.0) * self.top_speed
        draws = np.stack([g.normal(0.0, w.crowd_p.random_force, (self.ticks, 2, w.N)) for g in self.noise_rng], 2)
        noise = draws[:, 0] + 1j * draws[:, 1]  # [ticks, E, N]
        gaps, at_collision = w.tick(command, noise)  # at_collision: episode -> its state at its first collision
        gap = gaps.min(axis=0)
        self.elapsed += self.ticks * w.dt
        for k in range(self.n):
            if self.sensing:
                self._sense(k)
            if self.config.task == "follow":
                self._read_tag(k)
        before = self.distance.copy()
        self.distance = np.hypot(*(w.goal - w.robot_pose[:, :2]).T)
        collided = gap < 0
        reached = (self.distance < GOAL_RADIUS) & ~collided & (self.config.task == "navigate")
        terminated = collided | reached
        truncated = ~terminated & (self.elapsed >= self.config.time_limit - 1e-9)
        rewards, terms = self.reward(self, before, gap, reached, collided)
        infos = []
        for k in range(self.n):
            self._log(k, at_collision.get(k))
            info = {"reward_terms": {name: float(v[k]) for name, v in terms.items()}, "collision": bool(collided[k]),
                    "success": bool(reached[k]), "time": float(self.elapsed[k])}
            if terminated[k] or truncated[k]:
                info["episode_metrics"] = self.episode_metrics(k)
            infos.append(info)
        return rewards, terminated, truncated, infos

    def _state(self, k: int) -> tuple:
        w = self.worlds
        return float(w.t[k]), w.robot_pose[k].copy(), w.z[k].copy(), w.v[k].copy()

    def _log(self, k: int, state: tuple | None) -> None:
        """One entry per step: the state at its end, or at the tick of a collision within it; for following, the
        target's track (the pipeline's track nearest the target, within the evaluation's threshold; the target's
        own id when the truth is observed) and whether the laser saw the target."""
        entry = state or self._state(k)
        if self.config.task == "follow":
            entry += self._target_seen(k)
        self.log[k].append(entry)

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
        log, w = self.log[k], self.worlds
        T, N = len(log), w.N
        persons = PersonRows(np.repeat(np.arange(T), N), np.tile(np.arange(1, N + 1), T),
                             np.concatenate([e[2] for e in log]).view(float).reshape(-1, 2),
                             np.concatenate([e[3] for e in log]).view(float).reshape(-1, 2), np.tile(w.radius[k], T))
        common = dict(stamp=np.array([e[0] for e in log]), robot_pose=np.array([e[1] for e in log]),
                      robot_radius=w.robot_radius, persons=persons, walls=w.walls, time_limit=self.config.time_limit)
        if self.config.task == "follow":
            episode = NavEpisode(task="follow", target_id=1, band=BAND, target_track=np.array([e[4] for e in log]),
                                 target_visible=np.array([e[5] for e in log]), **common)
        else:
            episode = NavEpisode(task="goal", goal=w.goal[k].copy(), goal_radius=GOAL_RADIUS, **common)
        return navigation_metrics(episode)

    def observe(self) -> dict[str, np.ndarray]:
        return self.observer(self)
