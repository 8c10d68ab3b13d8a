"""What every benchmark shares: the walled hall its crowds walk in, a rate measured as a median over timed blocks,
and the figures written as JSON.

Each figure is the median rate over repeated timed blocks after a warm-up block, so one slow block (another process
waking up) does not decide it.
"""

from __future__ import annotations

import json
import time

import numpy as np

from scenarios import scenario_from_dict
from scenarios.typed import Scenario

HALL = 40.0  # m, side of the walled hall the crowd benchmark walks in


def write_figures(json_path: str | None, figures: dict) -> None:
    """The figures as JSON, when asked for (the command checked the file is new before measuring)."""
    if json_path:
        with open(json_path, "x") as f:
            json.dump(figures, f, indent=2)
            f.write("\n")


def add_arguments(parser) -> None:
    """The flags every benchmark takes."""
    parser.add_argument("--json", help="also write the figures to this JSON file")
    parser.add_argument("--quick", action="store_true", help="shorter measurements (for a smoke test)")


def rate(fn, calls: int, blocks: int = 5) -> float:
    """Median calls/s of ``fn`` over ``blocks`` timed blocks of ``calls`` calls (one untimed block first)."""
    for _ in range(max(1, calls // 5)):
        fn()
    rates = []
    for _ in range(blocks):
        t = time.perf_counter()
        for _ in range(calls):
            fn()
        rates.append(calls / (time.perf_counter() - t))
    return float(np.median(rates))


def bench_scenario(n_agents: int) -> Scenario:
    """A square walled hall with four corner waypoints that ``n_agents`` walkers circle round."""
    h = HALL
    return scenario_from_dict({
        "name": "bench_hall",
        "map": {"walls": [[[0, 0], [h, 0], [h, h], [0, h], [0, 0]]]},
        "crowd": {"max_agents": n_agents},
        "waypoints": {f"c{k}": {"position": list(p), "radius": 2.0}
                      for k, p in enumerate([(5, 5), (h - 5, 5), (h - 5, h - 5), (5, h - 5)])},
        "routes": {"loop": {"waypoints": ["c0", "c1", "c2", "c3"], "sink": False}},
        "robot": {"start": [h / 2, h / 2, 0.0]},
        "sensors": {"lasers": [{"name": "front_laser", "mount": [0.25, 0, 0]},
                               {"name": "rear_laser", "mount": [-0.25, 0, float(np.pi)]}]},
    }, source="<bench hall>")


def populated_crowd(n_agents: int, seed: int = 0):
    """The bench hall's crowd with ``n_agents`` walkers on a jittered grid, and its scenario."""
    from crowdsim.crowd import Crowd

    scenario = bench_scenario(n_agents)
    rng = np.random.default_rng(seed)
    crowd = Crowd(scenario, rng)
    side = int(np.ceil(np.sqrt(n_agents)))
    g = (np.arange(side) + 0.5) * (HALL - 2) / side + 1
    xy = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)[:n_agents] + rng.uniform(-0.1, 0.1, (n_agents, 2))
    crowd.add_walkers(xy, "loop")
    return crowd, scenario
