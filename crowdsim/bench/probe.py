"""One speed figure of one source tree, measured in a process of its own: ``python probe.py TREE FIGURE [--quick]``.

Run by path (``crowdsim bench speed`` starts it), so that the simulator it imports is TREE's: this tree's or an older
checkout's, measured by the same code. It uses only what both have long had (``load_scenario``, ``Simulation``,
``crowdsim.bench.sim.our_crowd``, the registered gym environments) and prints its figure as one line of JSON. Times
are CPU times of this process (``process_time``), which another job on the machine slows far less than wall time.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time


def loop(scenario: str, duration: float, timing=None) -> dict:
    """Simulated seconds per CPU second of ``scenario``'s loop after its warm-up (what ``Simulation.frames`` does:
    sensors, robot software, ground truth). A first second runs untimed, so that a fresh checkout's compiling of
    its kernels (a one-off cost of the first run after an install, not of the loop) is not timed. ``timing()`` is
    called where the timing starts (``floors.py`` times parts of the same window)."""
    from crowdsim.loop import Simulation
    from scenarios import load_scenario

    sim = Simulation(load_scenario(scenario, duration=duration + 1.0))
    sim.warm_up()
    for _ in sim.frames(1.0):
        pass
    if timing:
        timing()
    cpu = time.process_time()
    for _ in sim.frames(duration):
        pass
    return {"sim_s_per_cpu_s": duration / (time.process_time() - cpu)}


def run(tree: str, duration: float) -> dict:
    """Wall and CPU seconds of ``crowdsim run airport_disembarkation`` end to end, in a process of its own."""
    with tempfile.TemporaryDirectory() as out:
        before = _children_cpu()
        wall = time.perf_counter()
        subprocess.run([sys.executable, "-c", f"import sys; sys.path.insert(0, {tree!r}); from crowdsim.cli import "
                        "main; sys.exit(main(sys.argv[1:]))", "run", "airport_disembarkation", "--duration",
                        str(duration), "--out", f"{out}/run", "--quiet"], check=True, stdout=subprocess.DEVNULL)
        return {"wall_s": time.perf_counter() - wall, "cpu_s": _children_cpu() - before}


def _children_cpu() -> float:
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def crowd(agents: int, steps: int) -> dict:
    """Crowd steps per CPU second with ``agents`` walkers in ``crowdsim bench sim``'s corridor (dt 0.04 s)."""
    from crowdsim.bench.sim import our_crowd

    return _stepped(our_crowd(agents)[0], 5, steps)


def _stepped(walkers, untimed: int, steps: int) -> dict:
    """Steps per CPU second of the crowd ``walkers`` (dt 0.04 s) over ``steps`` steps after ``untimed`` ones."""
    for _ in range(untimed):
        walkers.step(0.04)
    cpu = time.process_time()
    for _ in range(steps):
        walkers.step(0.04)
    return {"steps_per_cpu_s": steps / (time.process_time() - cpu)}


def crowd_among_walls(agents: int, steps: int) -> dict:
    """Crowd steps per CPU second with ``agents`` walkers in a 120 m hall of 850 square pillars (3,368 wall
    segments: a building's worth, where the wall queries dominate)."""
    import numpy as np

    from crowdsim.crowd import Crowd
    from scenarios import scenario_from_dict

    h = 120.0
    pillars = [[[x, y], [x + 0.4, y], [x + 0.4, y + 0.4], [x, y + 0.4]]
               for x in np.arange(2, h - 2, 4.0) for y in np.arange(2, h - 2, 4.0)][:850]
    corners = [(5, 5), (h - 5, 5), (h - 5, h - 5), (5, h - 5)]
    scenario = scenario_from_dict({
        "name": "pillared_hall", "map": {"walls": [[[0, 0], [h, 0], [h, h], [0, h], [0, 0]]], "obstacles": pillars},
        "crowd": {"max_agents": agents},
        "waypoints": {f"c{k}": {"position": list(p), "radius": 2.0} for k, p in enumerate(corners)},
        "routes": {"loop": {"waypoints": ["c0", "c1", "c2", "c3"], "sink": False}}, "robot": {"start": [1.0, 1.0, 0.0]},
        "sensors": {"lasers": [{"name": "front_laser", "mount": [0.25, 0, 0]}]}}, source="<pillared hall>")
    rng = np.random.default_rng(0)
    walkers = Crowd(scenario, rng)
    walkers.add_walkers(rng.uniform(3, h - 3, (agents, 2)), "loop")
    return _stepped(walkers, 3, steps)


def env(observation: str, envs: int, people: int, steps: int, untimed: int = 20, timing=None) -> dict:
    """Environment steps per CPU second of ``crowdsim/Navigate-v0`` with random actions (all sub-environments'
    steps of a native vector environment, ``envs`` > 1), resetting where an episode ends, timed after ``untimed``
    steps and, for one environment, its first episode end (which loads the navigation metrics' compiled kernels
    from their cache once a process, as the untimed steps load the rest: start-up, not stepping); ``timing()`` is
    called where the timing starts."""
    import gymnasium as gym
    import numpy as np

    import crowdsim  # noqa: F401  (registers the environments)

    if envs == 1:
        e = gym.make("crowdsim/Navigate-v0", observation=observation, people=people)
    else:
        e = gym.make_vec("crowdsim/Navigate-v0", num_envs=envs, vectorization_mode="vector_entry_point",
                         observation=observation, people=people)
    e.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (steps + untimed, *e.action_space.shape)).astype(np.float32)

    def step(k: int) -> bool:
        _, _, terminated, truncated, _ = e.step(actions[k % len(actions)])
        if envs == 1 and (terminated or truncated):
            e.reset()
            return True
        return False

    k, ended = 0, envs > 1
    while k < untimed or not ended:
        ended |= step(k)
        k += 1
    if timing:
        timing()
    cpu = time.process_time()
    for j in range(steps):
        step(k + j)
    return {"env_steps_per_cpu_s": steps * envs / (time.process_time() - cpu)}


def figure(tree: str, name: str, quick: bool) -> dict:
    short = 0.25 if quick else 1.0
    return {
        "loop": lambda: loop("airport_disembarkation", 30.0 * short),
        "run": lambda: run(tree, 120.0 * short),
        "cameras": lambda: loop("airport_disembarkation_cameras", 10.0 * short),
        "crowd_20": lambda: crowd(20, int(2000 * short)),
        "crowd_400_walls": lambda: crowd_among_walls(400, int(20 * short)),
        "env_truth": lambda: env("truth", 1, 20, int(2000 * short)),
        "env_tracks": lambda: env("tracks", 1, 20, int(600 * short)),
        # timed from the 100th step: the 64 episodes start together, the first ends at step 36, and steps 20-120 hold 9
        # episode ends against 48 a hundred steps later on (each end computes its navigation metrics: a third of the
        # CPU then)
        "vector_truth": lambda: env("truth", 64, 10, int(400 * short), untimed=100),
        "vector_tracks": lambda: env("tracks", 64, 10, int(20 * short)),
    }[name]()


FIGURES = ("loop", "run", "cameras", "crowd_20", "crowd_400_walls", "env_truth", "env_tracks", "vector_truth",
           "vector_tracks")

if __name__ == "__main__":
    tree, name = sys.argv[1], sys.argv[2]
    sys.path[0] = tree  # the simulator measured is TREE's (and this folder's modules shadow nothing)
    print(json.dumps(figure(tree, name, "--quick" in sys.argv[3:])))
