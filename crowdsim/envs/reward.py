"""The reward as a weighted sum of named terms, each term's value reported in ``info["reward_terms"]``.

Terms (per control step):

* ``progress``: metres the robot came nearer its goal (navigation);
* ``goal``: 1 on reaching the goal;
* ``collision``: 1 on touching a person or a wall;
* ``discomfort``: CrowdNav's (Chen et al. 2019, ``crowd_sim.py``): (gap - 0.2) x control period when the smallest
  gap between the robot and a person or wall during the step is below 0.2 m without touching (negative: the weight
  is positive);
* ``band`` (following): the control period when the target is within the following band, minus the metres it is
  outside it times the period.

``crowdnav`` reproduces CrowdNav's reward: success 1, collision -0.25, discomfort factor 0.5 below 0.2 m, nothing
else.
"""

from __future__ import annotations

import numpy as np

DISCOMFORT_DISTANCE = 0.2  # m (CrowdNav's discomfort_dist)
PRESETS = {
    "default": {"progress": 1.0, "goal": 10.0, "collision": -10.0, "discomfort": 2.0, "band": 1.0},
    "crowdnav": {"progress": 0.0, "goal": 1.0, "collision": -0.25, "discomfort": 0.5, "band": 0.0},
}
TERMS = tuple(PRESETS["default"])
BAND = (1.0, 2.0)  # m, the following band (issue default: 1-2 m behind the target)


class Reward:
    def __init__(self, spec: str | dict, task: str):
        if isinstance(spec, str):
            if spec not in PRESETS:
                raise ValueError(f"reward: expected one of {sorted(PRESETS)} or a dict of term weights, got {spec!r}")
            spec = PRESETS[spec]
        unknown = set(spec) - set(TERMS)
        if unknown:
            raise ValueError(f"reward: unknown term(s) {sorted(unknown)}; expected some of {TERMS}")
        self.weights = {name: float(spec.get(name, 0.0)) for name in TERMS}
        self.task = task

    def __call__(self, episodes, before: np.ndarray, gap: np.ndarray, reached: np.ndarray,
                 collided: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        period = episodes.ticks * episodes.worlds.dt
        terms = {"progress": before - episodes.distance if self.task == "navigate" else np.zeros(episodes.n),
                 "goal": reached.astype(float),
                 "collision": collided.astype(float),
                 "discomfort": np.where((gap < DISCOMFORT_DISTANCE) & ~collided,
                                        (gap - DISCOMFORT_DISTANCE) * period, 0.0),
                 "band": self._band(episodes, period)}
        total = sum(self.weights[name] * value for name, value in terms.items())
        return total, terms

    def _band(self, episodes, period: float) -> np.ndarray:
        if self.task != "follow":
            return np.zeros(episodes.n)
        w = episodes.worlds
        d = np.hypot(w.x[:, 0] - w.robot_pose[:, 0], w.y[:, 0] - w.robot_pose[:, 1])
        outside = np.maximum(BAND[0] - d, 0.0) + np.maximum(d - BAND[1], 0.0)
        return np.where(outside == 0, period, -outside * period)
