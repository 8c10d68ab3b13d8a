"""``crowdsim experiment ppo``: stable-baselines3's PPO learns ``crowdsim/Navigate-v0`` from the ``tracks``
observation (what the robot's own pipeline believes, not the truth), within a wall-clock budget, and is compared
with the random policy on evaluation seeds that training never uses.

Needs the ``[rl]`` extra (``pip install -e ".[rl]"``: stable-baselines3 and PyTorch, CPU is enough).

Training runs the native vector environment (``CrowdVectorEnv``, same-step autoreset) through a small adapter to
stable-baselines3's ``VecEnv`` interface; sub-environment i starts from seed ``seed * 1000 + i`` and continues its
own generator from there. Evaluation episodes use seeds from ``EVAL_SEED`` on, so no evaluated crowd was trained on.
Writes ``curve.csv`` (one row per finished training episode), ``learning_curve.png``, ``model.zip`` and
``results.json``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

EVAL_SEED = 1_000_000  # evaluation seeds start here; training seeds are seed * 1000 + i, far below
WINDOW = 100  # episodes in the learning curve's moving average


def _install_hint() -> str:
    return 'crowdsim experiment ppo needs the [rl] extra: pip install -e ".[rl]"'


def make_vec_env(envs: int, people: int, seed: int):
    """The native vector environment as stable-baselines3's ``VecEnv``."""
    from gymnasium.vector import AutoresetMode
    from stable_baselines3.common.vec_env import VecEnv

    from crowdsim.envs.navigate import CrowdVectorEnv, info_of

    class CrowdSB3(VecEnv):
        """stable-baselines3's conventions over ``CrowdVectorEnv``: ``dones`` = terminated or truncated, the last
        observation in ``info["terminal_observation"]``, ``info["TimeLimit.truncated"]``."""

        def __init__(self):
            self.env = CrowdVectorEnv(envs, observation="tracks", people=people,
                                      autoreset_mode=AutoresetMode.SAME_STEP)
            super().__init__(envs, self.env.single_observation_space, self.env.single_action_space)
            self._actions = None

        def reset(self):
            obs, _ = self.env.reset(seed=seed * 1000)
            return obs

        def step_async(self, actions):
            self._actions = actions

        def step_wait(self):
            obs, rewards, terminated, truncated, info = self.env.step(self._actions)
            dones = terminated | truncated
            infos = [{} for _ in range(self.num_envs)]
            for i in np.flatnonzero(dones):
                infos[i]["terminal_observation"] = info["final_obs"][i]
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
                infos[i]["episode_metrics"] = info_of(info["final_info"], i)["episode_metrics"]
            return obs, rewards.astype(np.float32), dones, infos

        def close(self):
            self.env.close()

        def get_attr(self, attr_name, indices=None):
            return [getattr(self.env, attr_name)] * len(self._get_indices(indices))

        def set_attr(self, attr_name, value, indices=None):
            raise AttributeError(f"CrowdSB3 cannot set {attr_name}")

        def env_method(self, method_name, *args, indices=None, **kwargs):
            raise AttributeError(f"CrowdSB3 has no per-environment method {method_name}")

        def env_is_wrapped(self, wrapper_class, indices=None):
            return [False] * len(self._get_indices(indices))

    return CrowdSB3()


def evaluate(policy, episodes: int, people: int, progress: bool = False, **make) -> dict:
    """Success, collision and timeout rates and the mean return of ``policy(obs) -> action`` (None: uniformly random
    actions from a fixed generator) over evaluation seeds ``EVAL_SEED ..``; ``make`` keywords go to the
    environment."""
    import gymnasium as gym
    from tqdm import tqdm

    env = gym.make("crowdsim/Navigate-v0", observation="tracks", people=people, **make)
    actions = np.random.default_rng(EVAL_SEED)
    outcomes, returns = [], []
    for e in tqdm(range(episodes), desc="evaluating", unit="episode", disable=not progress):
        obs, _ = env.reset(seed=EVAL_SEED + e)
        total, done = 0.0, False
        while not done:
            action = actions.uniform(-1, 1, 2) if policy is None else policy(obs)
            obs, reward, terminated, truncated, info = env.step(action)
            total += reward
            done = terminated or truncated
        m = info["episode_metrics"]
        outcomes.append((m["success"], m["collision_person"] or m["collision_wall"], m["timeout"]))
        returns.append(total)
    o = np.array(outcomes, float)
    return {"episodes": episodes, "success_rate": float(o[:, 0].mean()), "collision_rate": float(o[:, 1].mean()),
            "timeout_rate": float(o[:, 2].mean()), "mean_return": float(np.mean(returns))}


def plot_curve(path: Path, curve: np.ndarray, random_success: float, trained_success: float) -> None:
    """Success rate and return (moving averages over ``WINDOW`` episodes) against environment steps."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    steps, ret, success = curve.T
    k = min(WINDOW, len(steps))
    kernel = np.ones(k) / k
    fig, (a, b) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    a.plot(steps[k - 1:], np.convolve(success, kernel, "valid"), label=f"PPO, training episodes (mean of {k})")
    a.axhline(random_success, color="grey", ls="--", label=f"random policy, evaluation seeds ({random_success:.0%})")
    a.axhline(trained_success, color="C1", ls=":", label=f"PPO at the end, evaluation seeds ({trained_success:.0%})")
    a.set_ylabel("success rate")
    a.set_ylim(-0.02, 1.02)
    a.legend(fontsize=8)
    b.plot(steps[k - 1:], np.convolve(ret, kernel, "valid"))
    b.set_ylabel("episode return")
    b.set_xlabel("environment steps")
    fig.suptitle("PPO on crowdsim/Navigate-v0, tracks observation")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def run_ppo(out: Path, minutes: float, envs: int = 8, people: int = 10, seed: int = 0, eval_episodes: int = 100,
            progress: bool = True) -> dict:
    try:
        from stable_baselines3 import PPO
        from stable_baselines3.common.callbacks import BaseCallback
    except ImportError as error:
        raise SystemExit(f"{_install_hint()} ({error})")
    from tqdm import tqdm

    import torch

    torch.set_num_threads(1)  # a small policy: more threads only contend with the environments for the cores
    venv = make_vec_env(envs, people, seed)
    budget = minutes * 60.0
    rows: list[tuple[int, float, bool]] = []

    class Curve(BaseCallback):
        """Each finished episode's return and success against steps; stops when the budget is spent."""

        def _on_training_start(self):
            self.returns = np.zeros(envs)
            self.start = time.perf_counter()
            self.bar = tqdm(total=round(budget), desc="training", unit="s", mininterval=5.0, disable=not progress)

        def _on_step(self) -> bool:
            self.returns += self.locals["rewards"]
            for i, info in enumerate(self.locals["infos"]):
                if "episode_metrics" in info:
                    rows.append((self.num_timesteps, float(self.returns[i]), bool(info["episode_metrics"]["success"])))
                    self.returns[i] = 0.0
            elapsed = time.perf_counter() - self.start
            advance = min(int(elapsed), round(budget)) - self.bar.n
            if advance > 0:  # the bar redraws at most every few seconds (tqdm's miniters and mininterval)
                self.bar.set_postfix(steps=self.num_timesteps, episodes=len(rows), refresh=False)
                self.bar.update(advance)
            return elapsed < budget

        def _on_training_end(self):
            self.bar.close()

    model = PPO("MultiInputPolicy", venv, n_steps=256, batch_size=512, n_epochs=5, learning_rate=3e-4, gamma=0.99,
                seed=seed, device="cpu", verbose=0)
    t0 = time.perf_counter()
    model.learn(total_timesteps=10**9, callback=Curve())
    train_s = time.perf_counter() - t0
    model.save(out / "model.zip")
    curve = np.array(rows, float).reshape(-1, 3)
    np.savetxt(out / "curve.csv", curve, fmt=["%d", "%.4f", "%d"], delimiter=",", header="steps,return,success",
               comments="")
    trained = evaluate(lambda obs: model.predict(obs, deterministic=True)[0], eval_episodes, people, progress)
    random = evaluate(None, eval_episodes, people, progress)
    plot_curve(out / "learning_curve.png", curve, random["success_rate"], trained["success_rate"])
    results = {"minutes": minutes, "train_wall_s": train_s, "steps": int(model.num_timesteps),
               "steps_per_s": model.num_timesteps / train_s, "training_episodes": len(rows), "envs": envs,
               "people": people, "seed": seed, "ppo": trained, "random": random}
    (out / "results.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


def add_arguments(parser) -> None:
    from ..cli import add_out_argument

    parser.add_argument("--minutes", type=float, default=30.0, help="wall-clock training budget (default 30)")
    parser.add_argument("--envs", type=int, default=8, help="environments stepped together (default 8)")
    parser.add_argument("--people", type=int, default=10, help="people per environment (default 10)")
    parser.add_argument("--seed", type=int, default=0, help="training seed (evaluation seeds are disjoint)")
    parser.add_argument("--eval-episodes", type=int, default=100, help="evaluation episodes per policy (default 100)")
    add_out_argument(parser, "ppo")


def main(args) -> int:
    """``crowdsim experiment ppo``."""
    from ..cli import UsageError, run_dir
    from ..outdir import write_directory

    if args.minutes <= 0:
        raise UsageError(f"--minutes: expected a time above 0, got {args.minutes}")
    out = run_dir(args, "ppo")
    r = write_directory(out, lambda tmp: run_ppo(tmp, args.minutes, envs=args.envs, people=args.people,
                                                 seed=args.seed, eval_episodes=args.eval_episodes))
    print(f"PPO: {r['steps']:,} steps in {r['train_wall_s'] / 60:.1f} min ({r['steps_per_s']:.0f}/s), "
          f"{r['training_episodes']} training episodes")
    for name in ("ppo", "random"):
        e = r[name]
        print(f"{name:7s} on {e['episodes']} evaluation seeds: success {e['success_rate']:.0%}, collision "
              f"{e['collision_rate']:.0%}, timeout {e['timeout_rate']:.0%}, mean return {e['mean_return']:.2f}")
    print(f"learning curve: {out / 'learning_curve.png'}")
    return 0
