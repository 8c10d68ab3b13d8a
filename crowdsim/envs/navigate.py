"""``crowdsim/Navigate-v0`` and ``crowdsim/Follow-v0``: the gymnasium shells round ``core.Episodes``.

``CrowdEnv`` is one episode (``Episodes`` of one world); ``CrowdVectorEnv`` steps n of them in one batched call
(gymnasium's ``vector_entry_point``, with the three autoreset modes gymnasium defines). Sub-environment i of a
vector environment reset with seed s is the single environment reset with seed s + i, step for step.

``render_mode="rgb_array"`` draws the episode from above (``render``); ``record="file.rrd"`` (single environment)
writes a rerun recording of every step.

Actions: (v, omega) in [-1, 1]^2, scaled to the robot's speed limits (its acceleration limits then apply).
An episode ends ``terminated`` on reaching the goal or touching a person or a wall, ``truncated`` at the time limit;
the last step's info holds ``episode_metrics``.
"""

from __future__ import annotations

import numbers

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..errors import Error
from .core import Config, Episodes, StepInfo
from .record import EnvRecording
from .render import top_down

ACTION_SPACE = spaces.Box(-1.0, 1.0, (2,), np.float32)


def _config(task: str, kwargs: dict) -> Config:
    defaults = {"time_limit": 60.0, "scenario": "following", "people": 10} if task == "follow" else {}
    return Config(task=task, **{**defaults, **kwargs})


class CrowdEnv(gym.Env):
    """One robot among a crowd (see the module docstring); ``make`` keywords are ``core.Config``'s fields."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 5}

    def __init__(self, task: str = "navigate", render_mode: str | None = None, record: str | None = None,
                 **kwargs):
        if render_mode not in (None, "rgb_array"):
            raise Error(f"render_mode: expected None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.episodes = Episodes(1, _config(task, kwargs))
        self.recording = EnvRecording(record) if record else None
        self.observation_space = self.episodes.observer.space
        self.action_space = ACTION_SPACE
        self.metadata = {**self.metadata, "render_fps": 1.0 / self.episodes.config.control_period}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.episodes.apply_options(options)
        self.episodes.reset(0, self.np_random)
        if self.recording:
            self.recording.reset(self.episodes)
        return _row(self.episodes.observe(), 0), {}

    def step(self, action):
        rewards, terminated, truncated, step = self.episodes.step(np.asarray(action, float)[None])
        if self.recording:
            self.recording.log(self.episodes)
        return _row(self.episodes.observe(), 0), float(rewards[0]), bool(terminated[0]), bool(truncated[0]), step.of(0)

    def render(self):
        if self.render_mode == "rgb_array":
            return top_down(self.episodes, 0)
        return None

    def close(self):
        if self.recording:
            self.recording.close()


class CrowdVectorEnv(VectorEnv):
    """n episodes stepped as one (``core.Episodes`` of n worlds)."""

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, num_envs: int = 1, task: str = "navigate", render_mode: str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP, **kwargs):
        if num_envs < 1:
            raise Error(f"num_envs: expected at least 1, got {num_envs}")
        self.num_envs = num_envs
        self.render_mode = render_mode
        self.episodes = Episodes(num_envs, _config(task, kwargs))
        self.single_observation_space = self.episodes.observer.space
        self.single_action_space = ACTION_SPACE
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        self._generators: list[np.random.Generator | None] = [None] * num_envs
        self._needs_reset = np.zeros(num_envs, bool)

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        """Reset every episode (or those of ``options["reset_mask"]``): sub-environment i with ``seed + i`` (or the
        i-th of a list of seeds), else continuing its own generator."""
        mask = np.ones(self.num_envs, bool) if not options or "reset_mask" not in options else np.asarray(
            options["reset_mask"], bool)
        if mask.shape != (self.num_envs,):
            raise Error(f"options['reset_mask']: expected {self.num_envs} booleans, got shape {mask.shape}")
        seeds = ([int(seed) + i for i in range(self.num_envs)] if isinstance(seed, numbers.Integral)
                 else list(seed) if seed is not None else [None] * self.num_envs)
        if len(seeds) != self.num_envs:
            raise Error(f"seed: expected an int or {self.num_envs} seeds, got {len(seeds)}")
        changes = {k: v for k, v in (options or {}).items() if k != "reset_mask"}
        if changes and not mask.all():
            raise Error("options: scenario, people and robot_visible change every sub-environment; "
                             "expected no reset_mask with them")
        self.episodes.apply_options(changes)
        for i in np.flatnonzero(mask):
            self._reset_one(int(i), seeds[i])
        self._needs_reset[mask] = False
        return self.episodes.observe(), {}

    def _reset_one(self, i: int, seed: int | None) -> None:
        if seed is not None or self._generators[i] is None:
            self._generators[i], _ = seeding.np_random(seed)
        self.episodes.reset(i, self._generators[i])

    def step(self, actions):
        actions = np.asarray(actions, float).reshape(self.num_envs, 2)
        restart = self._needs_reset.copy()
        rewards, terminated, truncated, step = self.episodes.step(actions, unscored=restart)
        if self.autoreset_mode == AutoresetMode.NEXT_STEP and restart.any():
            # the episodes that ended last step start over now; their action is ignored, their info is their reset's
            for i in np.flatnonzero(restart):
                self._reset_one(int(i), None)
            rewards[restart], terminated[restart], truncated[restart] = 0.0, False, False
        ended = terminated | truncated
        if self.autoreset_mode == AutoresetMode.SAME_STEP and ended.any():
            # the ended episodes start over now: their info is their reset's, with their last step's as final_info
            final_obs = self.episodes.observe()
            for i in np.flatnonzero(ended):
                self._reset_one(int(i), None)
            info = self._batched(step, ~ended)
            info["final_obs"], info["_final_obs"] = _masked(final_obs, ended), ended.copy()
            info["final_info"], info["_final_info"] = self._batched(step, ended), ended.copy()
        else:
            info = self._batched(step, ~restart)
        self._needs_reset = ended if self.autoreset_mode == AutoresetMode.NEXT_STEP else np.zeros(self.num_envs,
                                                                                                      bool)
        return self.episodes.observe(), rewards, terminated, truncated, info

    def _batched(self, step: StepInfo, shown: np.ndarray) -> dict:
        """The step's infos of the sub-environments ``shown`` as gymnasium's vector info, what ``SyncVectorEnv``
        gives for the same episodes: each key an array over sub-environments (zero where not shown) with its mask
        ``_key``, a nested dict a dict of such arrays. Built from the step's arrays at once; the episode metrics of
        the few that ended by gymnasium's own ``VectorEnv._add_info``."""
        if not shown.any():
            return {}
        terms = {}
        for name, value in step.terms.items():
            terms[name], terms["_" + name] = np.where(shown, value, 0.0), shown.copy()
        info = {"reward_terms": terms, "_reward_terms": shown.copy()}
        for name, value in (("collision", step.collision), ("success", step.success), ("time", step.time)):
            info[name], info["_" + name] = np.where(shown, value, np.zeros((), value.dtype)), shown.copy()
        for k in sorted(step.metrics):
            if shown[k]:
                info = self._add_info(info, {"episode_metrics": step.metrics[k]}, k)
        return info

    def render(self):
        if self.render_mode == "rgb_array":
            return tuple(top_down(self.episodes, i) for i in range(self.num_envs))
        return None


def info_of(info: dict, i: int) -> dict:
    """Sub-environment i's own info out of a vector info in gymnasium's layout (each key an array over the
    sub-environments with its mask ``_key``, a nested dict in turn): the dict the single environment gives, numbers
    as Python's."""
    out = {}
    for key, value in info.items():
        if key.startswith("_") or not info["_" + key][i]:
            continue
        out[key] = info_of(value, i) if isinstance(value, dict) else (
            value[i].item() if isinstance(value[i], np.generic) else value[i])
    return out


def _row(batch: dict[str, np.ndarray], i: int) -> dict[str, np.ndarray]:
    return {name: value[i] for name, value in batch.items()}


def _masked(batch: dict[str, np.ndarray], mask: np.ndarray) -> np.ndarray:
    """Per sub-environment its observation where ``mask``, else None (gymnasium's ``final_obs``)."""
    out = np.empty(len(mask), dtype=object)
    for i in range(len(mask)):
        out[i] = _row(batch, i) if mask[i] else None
    return out
