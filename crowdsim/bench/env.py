"""``crowdsim bench env``: environment steps per second, side by side in one run.

Every configuration steps ``crowdsim/Navigate-v0`` (the passers_by layout, 0.2 s control of 5 ticks of 0.04 s) with
uniformly random actions drawn from a fixed seed, resetting where an episode ends (the 30 s time limit, a
collision, the goal), through ``gymnasium.make`` and its default wrappers, as a user would. Each figure is the
median rate over timed blocks after an untimed one (``common.rate``); a vector environment's rate counts the steps
of all its sub-environments.

* one environment, 20 people, with the ``truth``, ``laser`` and ``tracks`` observations;
* the native vector environment (``vector_entry_point``), 64 environments of 10 people, ``truth``;
* gymnasium's ``SyncVectorEnv`` of the same 64 single environments, for comparison: the same episodes, one after
  another in Python.

Side by side, when their interpreters are given (``peer_envs.py`` says how each is configured and timed): CrowdNav
(``--crowdnav PYTHON``, with ``--crowdnav-dir`` its checkout if not installed there) and SocNavGym (``--socnavgym
PYTHON --socnavgym-config`` one of its environment configs), each with 20 humans and random actions, timed the
same way in a subprocess of its own interpreter. Their steps are longer than ours (0.25 s and 1 s against 0.2 s),
so simulated seconds per wall second are printed too.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
from pathlib import Path

import gymnasium as gym
import numpy as np

from . import common
from .common import rate, write_figures

PEOPLE, VECTOR_ENVS, VECTOR_PEOPLE = 20, 64, 10


def _single(observation: str, quick: bool) -> float:
    env = gym.make("crowdsim/Navigate-v0", observation=observation, people=PEOPLE)
    env.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (100_000, 2)).astype(np.float32)
    state = {"t": 0}

    def step():
        _, _, terminated, truncated, _ = env.step(actions[state["t"] % len(actions)])
        state["t"] += 1
        if terminated or truncated:
            env.reset()

    return rate(step, 20 if quick else 300 if observation == "truth" else 100)


def _vector(mode: str, quick: bool) -> float:
    vec = gym.make_vec("crowdsim/Navigate-v0", num_envs=VECTOR_ENVS, vectorization_mode=mode,
                       people=VECTOR_PEOPLE)
    vec.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (1000, VECTOR_ENVS, 2)).astype(np.float32)
    state = {"t": 0}

    def step():
        vec.step(actions[state["t"] % len(actions)])
        state["t"] += 1

    steps = rate(step, 3 if quick else 30 if mode == "vector_entry_point" else 5)
    vec.close()
    return steps * VECTOR_ENVS


def _peer(name: str, python: str, extra: list[str], path: str | None) -> dict:
    """The peer's figures from ``peer_envs.py`` run by its own interpreter."""
    env = dict(os.environ)
    if path:
        env["PYTHONPATH"] = os.pathsep.join(p for p in (path, env.get("PYTHONPATH")) if p)
    script = Path(__file__).with_name("peer_envs.py")
    done = subprocess.run([python, str(script), name, "--humans", str(PEOPLE), *extra], capture_output=True,
                          text=True, env=env)
    if done.returncode:
        raise RuntimeError(f"{name} benchmark with {python} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def run_env_benchmark(json_path: str | None = None, quick: bool = False, crowdnav: str | None = None,
                      crowdnav_dir: str | None = None, socnavgym: str | None = None,
                      socnavgym_config: str | None = None) -> dict:
    figures = {}

    def show(key, value, what, step_s=None):
        figures[key] = value
        sim = f"  ({value * step_s:,.0f} sim s/s)" if step_s else ""
        print(f"{what:66s} {value:10,.0f} steps/s{sim}", flush=True)

    print(f"crowdsim bench env on {platform.processor() or platform.machine()}, Python {platform.python_version()}"
          f"{' (quick)' if quick else ''}: Navigate-v0, passers_by, 0.2 s control, random actions")
    for observation in ("truth", "laser", "tracks"):
        show(f"single_{observation}", _single(observation, quick), f"one env, {PEOPLE} people, {observation}", 0.2)
    show("vector_native_truth", _vector("vector_entry_point", quick),
         f"native vector env, {VECTOR_ENVS} envs x {VECTOR_PEOPLE} people, truth (all envs' steps)")
    show("vector_sync_truth", _vector("sync", quick),
         f"gymnasium SyncVectorEnv, {VECTOR_ENVS} envs x {VECTOR_PEOPLE} people, truth")
    figures["native_over_single"] = figures["vector_native_truth"] / figures["single_truth"]
    print(f"native vector env over one env: {figures['native_over_single']:.1f}x")
    peers = []
    if crowdnav:
        peers.append(("crowdnav", crowdnav, [], crowdnav_dir, "CrowdNav CrowdSim-v0"))
    if socnavgym:
        peers.append(("socnavgym", socnavgym, ["--config", socnavgym_config], None, "SocNavGym-v1"))
    for name, python, extra, path, label in peers:
        peer = _peer(name, python, extra, path)
        figures[name] = peer
        c = peer["config"]
        show(f"{name}_steps_per_s", peer["steps_per_s"], f"{label}, {c['humans']} humans, {c['time_step']} s steps",
             c["time_step"])
        print(f"{'':66s} {peer['steps_per_s_without_reset']:10,.0f} steps/s without the time in reset()")
    write_figures(json_path, figures)
    return figures


def add_arguments(parser) -> None:
    common.add_arguments(parser)
    parser.add_argument("--crowdnav", metavar="PYTHON", help="also time CrowdNav with this interpreter")
    parser.add_argument("--crowdnav-dir", metavar="DIR", help="CrowdNav's checkout, if not installed")
    parser.add_argument("--socnavgym", metavar="PYTHON", help="also time SocNavGym with this interpreter")
    parser.add_argument("--socnavgym-config", metavar="FILE", help="the SocNavGym environment config to use")


def main(args) -> int:
    """``crowdsim bench env``."""
    from ..cli import UsageError, check_json

    check_json(args)
    if args.socnavgym and not args.socnavgym_config:
        raise UsageError("--socnavgym: expected --socnavgym-config too (one of SocNavGym's environment configs)")
    run_env_benchmark(json_path=args.json, quick=args.quick, crowdnav=args.crowdnav, crowdnav_dir=args.crowdnav_dir,
                      socnavgym=args.socnavgym, socnavgym_config=args.socnavgym_config)
    return 0
