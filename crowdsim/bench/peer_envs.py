"""Steps per second of the peers' navigation environments, timed as ``crowdsim bench env`` times ours.

This file is a script for the peer's own interpreter (its gym and its dependencies differ from ours); it imports
nothing of crowdsim. ``crowdsim bench env --crowdnav PYTHON`` and ``--socnavgym PYTHON --socnavgym-config FILE``
run it and print its figure beside ours:

    PYTHON peer_envs.py crowdnav [--humans 20]                   # import crowd_sim, crowd_nav must work
    PYTHON peer_envs.py socnavgym --config exp1_no_sngnn.yaml [--humans 20]

* CrowdNav (Chen et al. 2019, vita-epfl/CrowdNav): its ``crowd_nav/configs/env.config`` with ``human_num`` set,
  circle crossing, ORCA humans (Python-RVO2), an invisible robot, 0.25 s steps; the robot's actions are uniformly
  random holonomic velocities in [-1, 1] m/s, handed to ``env.step`` as ``ActionXY``.
* SocNavGym (gnns4hri/SocNavGym, ``SocNavGym-v1``): the given config (theirs, e.g. environment_configs/
  exp1_no_sngnn.yaml) with its dynamic humans set to ``--humans``; uniformly random actions in its action space.

Resets are timed with the steps (as ours are). Prints one line of JSON: the median rate of 5 timed blocks after an
untimed one, each block's rate, the rate with the time spent in ``reset`` left out, and the configuration.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
import warnings

import numpy as np

CALLS, BLOCKS = 300, 5


def timed(step, reset_time: dict) -> dict:
    """``crowdsim.bench.common.rate``'s method (an untimed block, then the median of timed ones), and the same with
    the seconds ``reset_time["s"]`` spent in resets taken out."""
    for _ in range(max(1, CALLS // 5)):
        step()
    rates, without_reset = [], []
    for _ in range(BLOCKS):
        reset_time["s"] = 0.0
        t = time.perf_counter()
        for _ in range(CALLS):
            step()
        wall = time.perf_counter() - t
        rates.append(CALLS / wall)
        without_reset.append(CALLS / (wall - reset_time["s"]))
    return {"steps_per_s": float(np.median(rates)), "blocks": rates,
            "steps_per_s_without_reset": float(np.median(without_reset))}


def crowdnav(humans: int) -> dict:
    import configparser
    import os

    import crowd_nav
    import crowd_sim  # noqa: F401  (registers CrowdSim-v0)
    import gym
    from crowd_sim.envs.policy.policy import Policy
    from crowd_sim.envs.utils.action import ActionXY
    from crowd_sim.envs.utils.robot import Robot

    class GivenAction(Policy):
        """A holonomic robot whose actions the benchmark hands to ``env.step``."""

        def __init__(self):
            super().__init__()
            self.name, self.trainable, self.multiagent_training, self.kinematics = "given", False, True, "holonomic"

        def predict(self, state):
            raise NotImplementedError

    config = configparser.RawConfigParser()
    config.read(os.path.join(os.path.dirname(crowd_nav.__file__), "configs", "env.config"))
    config.set("sim", "human_num", str(humans))
    env = gym.make("CrowdSim-v0", disable_env_checker=True)  # the checker rejects CrowdSim's missing spaces
    env.unwrapped.configure(config)
    robot = Robot(config, "robot")
    robot.set_policy(GivenAction())
    env.unwrapped.set_robot(robot)
    env.reset(phase="test")
    actions = np.random.default_rng(0).uniform(-1, 1, (100_000, 2))
    state, reset_time = {"t": 0}, {"s": 0.0}

    def step():
        a = actions[state["t"] % len(actions)]
        state["t"] += 1
        if env.step(ActionXY(float(a[0]), float(a[1])))[2]:
            t = time.perf_counter()
            env.reset(phase="test")
            reset_time["s"] += time.perf_counter() - t

    figures = timed(step, reset_time)
    e = env.unwrapped
    figures["config"] = {"humans": len(e.humans), "time_step": e.time_step, "scenario": e.test_sim,
                         "human_policy": config.get("humans", "policy"), "robot_visible": robot.visible}
    return figures


def socnavgym(humans: int, config_path: str) -> dict:
    import types

    import yaml

    # dgl 2.1 (SocNavGym imports it for its SNGNN reward) loads a GraphBolt library built only for torch <= 2.2:
    # with a newer torch the import fails, so an inert module stands in for GraphBolt; this benchmark's rewards do
    # not use dgl
    class Inert(types.ModuleType):
        def __getattr__(self, name):
            if name.startswith("__"):
                raise AttributeError(name)
            return type(name, (), {})

    sys.modules.setdefault("dgl.graphbolt", Inert("dgl.graphbolt"))
    import gym
    import socnavgym  # noqa: F401  (registers SocNavGym-v1)

    with open(config_path) as f:
        config = yaml.safe_load(f)
    config["env"]["min_dynamic_humans"] = config["env"]["max_dynamic_humans"] = humans
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        yaml.safe_dump(config, f)
    env = gym.make("SocNavGym-v1", config=f.name, disable_env_checker=True)  # gym 0.26's checker needs np.bool8
    env.reset(seed=0)
    low, high = env.action_space.low, env.action_space.high
    actions = np.random.default_rng(0).uniform(low, high, (100_000, len(low))).astype(np.float32)
    state, reset_time = {"t": 0}, {"s": 0.0}

    def step():
        state["t"] += 1
        _, _, terminated, truncated, _ = env.step(actions[state["t"] % len(actions)])
        if terminated or truncated:
            t = time.perf_counter()
            env.reset()
            reset_time["s"] += time.perf_counter() - t

    figures = timed(step, reset_time)
    e = env.unwrapped
    figures["config"] = {"humans": len(e.dynamic_humans), "time_step": e.TIMESTEP, "robot": e.robot.type,
                         "map": [e.MAP_X, e.MAP_Y]}
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("peer", choices=("crowdnav", "socnavgym"))
    parser.add_argument("--humans", type=int, default=20)
    parser.add_argument("--config", help="SocNavGym's environment config (YAML)")
    args = parser.parse_args()
    warnings.filterwarnings("ignore")
    figures = crowdnav(args.humans) if args.peer == "crowdnav" else socnavgym(args.humans, args.config)
    print(json.dumps(figures))


if __name__ == "__main__":
    main()
