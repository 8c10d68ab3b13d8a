"""The reward as a weighted sum of named terms, each term's value reported in ``info["reward_terms"]``.

Every term is an amount of something (its sign is the weight's), per control step:

* ``progress``: metres the robot came nearer its goal (navigation; negative when it went away);
* ``goal``: 1 on reaching the goal;
* ``collision``: 1 on touching a person or a wall;
* ``discomfort``: CrowdNav's (Chen et al. 2019, ``crowd_sim.py``): (0.2 - gap) x control period when the smallest
  gap between the robot and a person or wall during the step is below 0.2 m without touching;
* ``zone``: the control period when the robot's centre lies in a person's security zone (seed 001 Sec. 7, the
  zone planner's ``SecurityZones`` with its defaults, on the persons' true positions and velocities);
* ``band`` (following): the control period when the target is within the following band;
* ``band_distance`` (following): metres the target is outside the band, times the control period.

``crowdnav`` reproduces CrowdNav's reward: success 1, collision -0.25, discomfort -0.5 per metre-second below 0.2 m,
nothing else.
"""

from __future__ import annotations

import numpy as np

from pipeline.navigation.zones import SecurityZones

from ..errors import Error

DISCOMFORT_DISTANCE = 0.2  # m (CrowdNav's discomfort_dist)
PRESETS = {
    "default": {"progress": 1.0, "goal": 10.0, "collision": -10.0, "discomfort": -2.0, "zone": -1.0, "band": 1.0,
                "band_distance": -1.0},
    "crowdnav": {"goal": 1.0, "collision": -0.25, "discomfort": -0.5},
}
TERMS = tuple(PRESETS["default"])
ZONES = SecurityZones()
BAND = (1.0, 2.0)  # m, the following band (issue default: 1-2 m behind the target)


class Reward:
    def __init__(self, spec: str | dict, task: str):
        if isinstance(spec, str):
            if spec not in PRESETS:
                raise Error(f"reward: expected one of {sorted(PRESETS)} or a dict of term weights, got {spec!r}")
            spec = PRESETS[spec]
        unknown = set(spec) - set(TERMS)
        if unknown:
            raise Error(f"reward: unknown term(s) {sorted(unknown)}; expected some of {TERMS}")
        self.weights = {name: float(spec.get(name, 0.0)) for name in TERMS}
        self.task = task

    def __call__(self, episodes, before: np.ndarray, gap: np.ndarray, reached: np.ndarray,
                 collided: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        period = episodes.ticks * episodes.worlds.dt
        zero = np.zeros(episodes.n)
        terms = {"progress": before - episodes.distance if self.task == "navigate" else zero,
                 "goal": reached.astype(float),
                 "collision": collided.astype(float),
                 "discomfort": np.where((gap < DISCOMFORT_DISTANCE) & ~collided,
                                        (DISCOMFORT_DISTANCE - gap) * period, 0.0),
                 "zone": in_zone(episodes.worlds) * period if self.weights["zone"] else zero}
        if self.task == "follow":
            w = episodes.worlds
            d = np.hypot(w.x[:, 0] - w.robot_pose[:, 0], w.y[:, 0] - w.robot_pose[:, 1])
            outside = np.maximum(BAND[0] - d, 0.0) + np.maximum(d - BAND[1], 0.0)
            terms["band"], terms["band_distance"] = (outside == 0) * period, outside * period
        else:
            terms["band"] = terms["band_distance"] = zero
        total = sum((self.weights[name] * value for name, value in terms.items() if self.weights[name]), zero)
        return total, terms


def in_zone(worlds) -> np.ndarray:
    """Whether each robot's centre lies in the security zone of a person of its world [E] (the target's too)."""
    E, N = worlds.x.shape
    if N == 0:
        return np.zeros(E, bool)
    velocity = worlds.velocity
    headings = np.arctan2(velocity[..., 1], velocity[..., 0])
    walking = np.hypot(velocity[..., 0], velocity[..., 1]) >= ZONES.standing_speed
    inside = ZONES.inside_each(worlds.robot_pose[:, None, :2], worlds.position, headings, walking)  # [E, 1, N]
    return inside.any(axis=(1, 2))
