"""``crowdsim bench sim``: simulated seconds per wall second of our crowd and of JuPedSim's SocialForceModel, side by
side in one run, on the same corridor with the same agents.

Set-up (the same for both simulators and for every agent count):

* Geometry: a walled corridor ``CORRIDOR_LENGTH`` x ``CORRIDOR_WIDTH`` (250 m x 20 m). The agents start on a
  jittered grid (+-0.1 m) filling its first ``START_LENGTH`` m (200 m x 20 m, 0.5 m clear of the walls), so 5000
  agents stand at 1.25 persons/m^2, 1000 at 0.25 and 100 at 0.025. Everyone walks towards the far end: ours on a
  one-waypoint route that ends in a sink at (249, 10), JuPedSim on a journey to an exit stage, the corridor's last
  metre. No one gets there while timing: a configuration simulates at most ``MAX_SIM_S`` (12 s, warm-up included)
  and the front row starts 49 m short of the end (at most 2.6 m/s, ours' cap of 1.3 x the fastest desired speed,
  covers 31 m), so the agent count stays constant without loops or teleports; each simulator's count at the end is
  reported and checked.
* Agents: the same start positions, the same radius (0.25 m, our adult's) and the same per-agent desired speeds
  for both: the adult distribution N(1.34, 0.26) m/s clipped to [0.6, 2.0], drawn once by our crowd and handed to
  JuPedSim's ``desired_speed`` agent by agent. Every other parameter is each simulator's default: ours the scenario
  defaults (Moussaid 2009 interaction, walls, pymunk contacts, random force); JuPedSim's ``SocialForceModel()`` and
  ``SocialForceModelAgentParameters`` defaults.
* Time step: each simulator's own default: ours 0.04 s (the scenario default), JuPedSim's ``Simulation(dt=0.01)``
  (its documented default; it recommends leaving it). Read from ``Simulation.delta_time()``, not assumed.
* Measure: both warm up for ``WARMUP_SIM_S`` simulated seconds (5 of our steps, 20 of JuPedSim's; untimed, as the
  first step pays one-off costs: ours builds Chipmunk's index of every body, 2 s at 5000 agents), then run a short
  timed probe of ``PROBE_SIM_S``. From the slower probe a common simulated span is chosen, about ``TARGET_WALL_S``
  of wall time for the slower simulator (capped by ``MAX_SIM_S``, at least ``MIN_OUR_STEPS`` of our steps), and
  each simulator then runs that span as a fixed number of its own steps under one timer: simulated s per wall s =
  steps x dt / wall. Both thus cover the same stretch of simulated time from the same start, so neither is timed
  on an easier phase of the flow.
"""

from __future__ import annotations

import platform
import sys
import time

import numpy as np

from scenarios import scenario_from_dict
from scenarios.typed import Scenario

from .common import write_figures
from .common import add_arguments  # noqa: F401  (its flags: those every benchmark takes)

CORRIDOR_LENGTH = 250.0  # m
CORRIDOR_WIDTH = 20.0  # m
START_LENGTH = 200.0  # m of the corridor the agents start in
WALL_CLEARANCE = 0.5  # m between the walls and the start grid's outer cells
JITTER = 0.1  # m, +- uniform on each axis of the start grid
GOAL = (CORRIDOR_LENGTH - 1.0, CORRIDOR_WIDTH / 2)
OURS_DT = 0.04  # s, the scenario default
WARMUP_SIM_S = 0.2  # s simulated before timing (a multiple of both time steps)
PROBE_SIM_S = 0.12  # s simulated after the warm-up to size the timed span (3 of our steps, 12 of JuPedSim's)
TARGET_WALL_S = 2.0  # s of wall time the slower simulator gets per configuration
QUICK_WALL_S = 0.3
MAX_SIM_S = 12.0  # s simulated per configuration, warm-up included: no one reaches the far end
MIN_OUR_STEPS = 10  # a timed span never covers fewer of our steps
INSTALL_HINT = 'pip install -e ".[bench]"'


def corridor_scenario(n_agents: int) -> Scenario:
    """The walled corridor with one route to a sink at the far end."""
    length, width = CORRIDOR_LENGTH, CORRIDOR_WIDTH
    return scenario_from_dict({
        "name": "bench_corridor",
        "map": {"walls": [[[0, 0], [length, 0], [length, width], [0, width], [0, 0]]]},
        "crowd": {"max_agents": max(int(n_agents), 1)},
        "waypoints": {"far_end": {"position": list(GOAL), "radius": 1.0}},
        "routes": {"walk": {"waypoints": ["far_end"], "sink": True}},
        "robot": {"start": [1.0, 1.0, 0.0]},  # unused: the crowd steps without a robot
        "sensors": {"lasers": [{"name": "front_laser", "mount": [0.25, 0, 0]}]},
    }, source="<bench corridor>")


def start_positions(n_agents: int, rng: np.random.Generator) -> np.ndarray:
    """A jittered grid of ``n_agents`` points [n, 2] over the corridor's first ``START_LENGTH`` m, cells about as
    long as wide."""
    span_x = START_LENGTH - 2 * WALL_CLEARANCE
    span_y = CORRIDOR_WIDTH - 2 * WALL_CLEARANCE
    rows = max(1, int(round(np.sqrt(n_agents * span_y / span_x))))
    cols = int(np.ceil(n_agents / rows))
    x = WALL_CLEARANCE + (np.arange(cols) + 0.5) * span_x / cols
    y = WALL_CLEARANCE + (np.arange(rows) + 0.5) * span_y / rows
    grid = np.stack(np.meshgrid(x, y, indexing="ij"), -1).reshape(-1, 2)[:n_agents]
    return grid + rng.uniform(-JITTER, JITTER, grid.shape)


def our_crowd(n_agents: int, seed: int = 0):
    """Our crowd in the corridor with ``n_agents`` adults; returns it, their start positions and desired speeds."""
    from crowdsim.crowd import Crowd

    rng = np.random.default_rng(seed)
    positions = start_positions(n_agents, rng)
    crowd = Crowd(corridor_scenario(n_agents), rng)
    crowd.add_walkers(positions, "walk", agent_type="adult")  # each draws a desired speed from N(1.34, 0.26)
    return crowd, positions, crowd.v0.copy()


def jupedsim_simulation(jps, positions: np.ndarray, desired_speed: np.ndarray, radius: np.ndarray):
    """JuPedSim's SocialForceModel at its default time step on the same corridor, agents, desired speeds and radii."""
    length, width = CORRIDOR_LENGTH, CORRIDOR_WIDTH
    sim = jps.Simulation(model=jps.SocialForceModel(), geometry=[(0, 0), (length, 0), (length, width), (0, width)])
    exit_id = sim.add_exit_stage([(length - 1.0, 0), (length, 0), (length, width), (length - 1.0, width)])
    journey = sim.add_journey(jps.JourneyDescription([exit_id]))
    for (x, y), v0, r in zip(positions, desired_speed, radius):
        sim.add_agent(jps.SocialForceModelAgentParameters(
            position=(float(x), float(y)), orientation=(1.0, 0.0), journey_id=journey, stage_id=exit_id,
            desired_speed=float(v0), radius=float(r)))
    return sim


def _import_jupedsim():
    try:
        import jupedsim
    except ImportError:
        return None
    return jupedsim


class _Progress:
    """One status line on stderr, rewritten in place on a terminal, a line each elsewhere."""

    def __init__(self):
        self.tty = sys.stderr.isatty()
        self.width = 0

    def __call__(self, text: str):
        if self.tty:
            sys.stderr.write("\r" + text.ljust(self.width))
            self.width = len(text)
        else:
            sys.stderr.write(text + "\n")
        sys.stderr.flush()

    def clear(self):
        if self.tty and self.width:
            sys.stderr.write("\r" + " " * self.width + "\r")
            sys.stderr.flush()
        self.width = 0


def _timed(step, steps: int) -> float:
    t = time.perf_counter()
    for _ in range(steps):
        step()
    return time.perf_counter() - t


def bench_count(n_agents: int, quick: bool = False, jps=None, progress=None, seed: int = 0) -> dict:
    """Time ours (and JuPedSim when ``jps`` is the imported module) over a common simulated span at ``n_agents``."""
    say = progress or (lambda text: None)
    say(f"{n_agents} agents: setting up")
    crowd, positions, v0 = our_crowd(n_agents, seed)
    ours_step = lambda: crowd.step(OURS_DT)  # noqa: E731
    sim = jps_dt = None
    if jps is not None:
        sim = jupedsim_simulation(jps, positions, v0, crowd.radius)
        jps_dt = float(sim.delta_time())
        jps_step = lambda: sim.iterate()  # noqa: E731  # one iteration of dt, like one crowd.step

    # warm-up (untimed: the first step pays one-off costs, ours building Chipmunk's index of every body), then a
    # short timed probe of each rate, which sizes the common span
    say(f"{n_agents} agents: warming up ours")
    _timed(ours_step, int(round(WARMUP_SIM_S / OURS_DT)))
    probe = [PROBE_SIM_S / _timed(ours_step, int(round(PROBE_SIM_S / OURS_DT)))]
    if sim is not None:
        say(f"{n_agents} agents: warming up JuPedSim")
        _timed(jps_step, int(round(WARMUP_SIM_S / jps_dt)))
        probe.append(PROBE_SIM_S / _timed(jps_step, int(round(PROBE_SIM_S / jps_dt))))
    target = QUICK_WALL_S if quick else TARGET_WALL_S
    span = min(target * min(probe), MAX_SIM_S - WARMUP_SIM_S - PROBE_SIM_S)
    ours_steps = max(MIN_OUR_STEPS, int(round(span / OURS_DT)))
    span = ours_steps * OURS_DT  # a whole number of both simulators' steps (0.04 s = 4 x 0.01 s)

    say(f"{n_agents} agents: timing ours, {ours_steps} steps of {OURS_DT:g} s")
    wall = _timed(ours_step, ours_steps)
    row = {"agents": n_agents, "sim_span_s": span, "ours_dt": OURS_DT, "ours_steps": ours_steps, "ours_wall_s": wall,
           "ours_sim_s_per_s": ours_steps * OURS_DT / wall, "ours_agents_end": int(len(crowd.id))}
    if sim is not None:
        jps_steps = int(round(span / jps_dt))
        say(f"{n_agents} agents: timing JuPedSim, {jps_steps} steps of {jps_dt:g} s")
        wall = _timed(jps_step, jps_steps)
        row.update({"jupedsim_dt": jps_dt, "jupedsim_steps": jps_steps, "jupedsim_wall_s": wall,
                    "jupedsim_sim_s_per_s": jps_steps * jps_dt / wall,
                    "jupedsim_agents_end": int(sim.agent_count())})
        row["ratio"] = row["ours_sim_s_per_s"] / row["jupedsim_sim_s_per_s"]
    row["agents_constant"] = row["ours_agents_end"] == n_agents and row.get("jupedsim_agents_end", n_agents) == n_agents
    return row


def _cell(value, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def run_sim_benchmark(counts=(100, 1000, 5000), quick: bool = False, json_path: str | None = None) -> dict:
    """Print a table of simulated seconds per wall second, ours and JuPedSim's SocialForceModel, one row per agent
    count, and return the figures (``rows`` keyed by the count as a string). Without jupedsim installed only ours is
    measured, and the table says how to install it."""
    jps = _import_jupedsim()
    print(f"crowdsim bench sim on {platform.processor() or platform.machine()}, Python {platform.python_version()}"
          f"{' (quick)' if quick else ''}")
    print(f"walled corridor {CORRIDOR_LENGTH:g} m x {CORRIDOR_WIDTH:g} m, agents start on a jittered grid over the "
          f"first {START_LENGTH:g} m and walk to the far end; same positions, radius and desired speeds for both")
    if jps is None:
        print(f"JuPedSim is not installed: measuring ours only. Install it with: {INSTALL_HINT}")
        jps_version = None
    else:
        jps_version = jps.__version__
        print(f"ours: dt {OURS_DT:g} s; JuPedSim {jps_version} SocialForceModel: its default dt "
              f"(shown per row), default parameters")
    figures = {"ours_dt": OURS_DT, "jupedsim_version": jps_version,
               "corridor_m": [CORRIDOR_LENGTH, CORRIDOR_WIDTH], "start_length_m": START_LENGTH,
               "quick": quick, "rows": {}}
    header = (f"{'agents':>7} {'ours sim-s/s':>13} {'JuPedSim sim-s/s':>17} {'ours/JuPedSim':>14}"
              f" {'sim span':>9} {'steps ours/JPS':>15} {'agents at end':>14}")
    print(header)
    progress = _Progress()
    for n in counts:
        row = bench_count(int(n), quick, jps, progress)
        progress.clear()
        figures["rows"][str(n)] = row
        if "jupedsim_dt" in row:
            figures["jupedsim_dt"] = row["jupedsim_dt"]
        steps = f"{row['ours_steps']}/{row.get('jupedsim_steps', '-')}"
        end = f"{row['ours_agents_end']}/{row.get('jupedsim_agents_end', '-')}"
        print(f"{n:>7} {row['ours_sim_s_per_s']:>13.2f} {_cell(row.get('jupedsim_sim_s_per_s'), '.2f'):>17}"
              f" {_cell(row.get('ratio'), '.2f'):>14} {row['sim_span_s']:>8.2f}s {steps:>15} {end:>14}"
              f"{'' if row['agents_constant'] else '  AGENT COUNT CHANGED'}", flush=True)
    if jps is None:
        print(f"(JuPedSim not installed; {INSTALL_HINT} adds it)")
    else:
        print(f"ours dt {OURS_DT:g} s, JuPedSim dt {figures.get('jupedsim_dt', float('nan')):g} s; ratio > 1: ours "
              "simulates faster")
    write_figures(json_path, figures)
    return figures


def main(args) -> int:
    """``crowdsim bench sim``."""
    from ..cli import check_json

    check_json(args)
    run_sim_benchmark(quick=args.quick, json_path=args.json)
    return 0


if __name__ == "__main__":
    run_sim_benchmark(quick="--quick" in sys.argv)
