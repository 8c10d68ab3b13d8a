"""``crowdsim bench``: the speed of each hot part (crowd, laser, each of Table II's trackers at 30 and 80 tracks, with
and without clutter, the group stage at 30 and 80 tracks, seed 001's cooperative system part by part) and of the whole
loop, measured side by side in one run."""

from __future__ import annotations

import platform
import time

import numpy as np

from scenarios import load_scenario

from .common import HALL, populated_crowd, rate, write_figures
from .common import add_arguments  # noqa: F401  (its flags: those every benchmark takes)
from .seed001 import bench_seed001
from .seed003 import bench_seed003

def bench_crowd(n_agents: int, quick: bool) -> float:
    crowd, _ = populated_crowd(n_agents)
    return rate(lambda: crowd.step(0.04), 5 if quick else 40 if n_agents <= 100 else 10)


def bench_laser(n_people: int, quick: bool) -> float:
    from sensors import Laser, Scene, parts_at
    from sensors.body import body_scale

    crowd, scenario = populated_crowd(n_people)
    scene = Scene(crowd.walls, 0.425, n_people, parts_at(scenario.sensors.lasers[0].height))
    pose = np.array([HALL / 2, HALL / 2, 0.0])
    scene.sync(pose, crowd.id, crowd.pos, crowd.vel, crowd.walked, body_scale(crowd.id, crowd.radius))
    laser = Laser(scene=scene, rng=np.random.default_rng(0), **scenario.sensors.lasers[0].params)
    return rate(lambda: laser.scan(0.0, pose), 50 if quick else 400)


CLUTTER = (0.05, 2)
"""The tracker rows' clutter: each person missed with probability 0.05, and 2 false alarms per cycle."""


def tracker_variants() -> list[tuple[str, str, dict]]:
    """Table II's trackers (``crowdsim.experiments.table2.ROWS``) as (figure key, label, tracker spec), key and label
    naming the parts each row adds to the base NNT."""
    from crowdsim.experiments.table2 import ROWS

    out = []
    for _, spec, _ in ROWS:
        if spec["type"] == "mht":
            out.append(("mht", "MHT", spec))
            continue
        parts = [spec.get("association", "greedy")]
        parts += [f"{spec['initiation']} init"] if "initiation" in spec else []
        parts += ["deletion"] if spec.get("deletion") == "young_mature" else []
        parts += ["IMM"] if spec.get("motion") == "imm" else []
        out.append(("_".join(parts).lower().replace(" ", "_"), "NNT " + " + ".join(parts), spec))
    # every NNT row has SPENCER's duplicate guards (pipeline/tracking/duplicates.py); the full NNT also without them
    key, label, spec = out[-2]
    out.insert(-1, (key + "_no_guards", label + ", no duplicate guards",
                    {k: v for k, v in spec.items() if k not in ("duplicate_distance", "new_track_clearance")}))
    return out


def bench_tracker(spec: dict, n_tracks: int, clutter: bool, quick: bool) -> float:
    """Cycles/s of the tracker ``spec`` on ``n_tracks`` walkers (``pipeline.tracking.nnt.bench_cycles``); the MHT,
    some 50 times slower, gets fewer cycles."""
    from pipeline.tracking.nnt import bench_cycles

    if spec["type"] == "mht":
        cycles, blocks, warm = (5, 1, 10) if quick else (20, 3, 50)
    else:
        cycles, blocks, warm = (20, 3, 20) if quick else (200, 5, 50)
    return bench_cycles(n_tracks, spec, *(CLUTTER if clutter else (0.0, 0)), cycles, blocks, warm).cycles_per_s


def group_scene(n_tracks: int, seed: int = 0):
    """Tracks for the group stage: ``n_tracks`` in a square at 0.55 persons/m^2 (a dense hall, about 15 others
    within the 3 m gate of each), half standing (heading 0 for all: every standing pair passes the heading gate),
    half walking at 1.2 m/s in pairs and alone in four directions; each call moves them one 0.08 s cycle, with 5 cm of
    noise, as a tracker's output."""
    from pipeline.types import TrackedPersons

    rng = np.random.default_rng(seed)
    side = np.sqrt(n_tracks / 0.55)
    xy = rng.uniform(0, side, (n_tracks, 2))
    heading = rng.integers(0, 4, n_tracks) * np.pi / 2
    v = np.where(np.arange(n_tracks)[:, None] % 2 == 0, 0.0, 1.2 * np.column_stack([np.cos(heading),
                                                                                     np.sin(heading)]))
    ids = np.arange(1, n_tracks + 1)
    z = np.zeros((n_tracks, 2, 2))

    def cycle(k: int) -> TrackedPersons:
        pos = np.remainder(xy + v * 0.08 * k, side) + rng.normal(0, 0.05, xy.shape)
        return TrackedPersons(0.08 * k, "odom", ids, np.ones(n_tracks, bool), np.zeros(n_tracks, bool),
                              -np.ones(n_tracks, np.int64), pos, v + rng.normal(0, 0.05, v.shape), z, z,
                              np.zeros(n_tracks))

    return cycle


def bench_groups(n_tracks: int, quick: bool, **stage) -> float:
    """Cycles/s of the group stage (relations, detection, composition tracking) on ``group_scene``."""
    from pipeline.groups import CoherentMotionGroups

    groups, cycle = CoherentMotionGroups(**stage), group_scene(n_tracks)
    scenes = [cycle(k) for k in range(200)]  # made beforehand: the stage alone is timed
    counter = iter(range(10 ** 9))

    def one() -> None:
        k = next(counter)
        groups.update(0.08 * k, scenes[k % len(scenes)])

    return rate(one, 20 if quick else 200)


# (figure key, label, the stage's parameters)
GROUP_STAGES = (("forest_average", "forest, average linkage (the airport's)",
                 {"model": "forest", "linkage": "average"}),
                ("spencer_single", "spencer, single linkage (SPENCER's, the default)", {}),
                ("svm_single", "svm, single linkage", {"model": "svm"}),
                ("forest_complete", "forest, complete linkage", {"model": "forest", "linkage": "complete"}))


def bench_loop(quick: bool) -> dict:
    from crowdsim.loop import Simulation

    duration = 5.0 if quick else 30.0
    scenario = load_scenario("airport_disembarkation", duration=duration)
    sim = Simulation(scenario)
    sim.warm_up()
    t, cpu = time.perf_counter(), time.process_time()
    n = sum(len(f.groundtruth) for f in sim.frames(duration))
    wall, cpu = time.perf_counter() - t, time.process_time() - cpu
    frames = sim.timing.tracker_cycles
    return {"realtime_factor": duration / wall, "cpu_realtime_factor": duration / cpu, "sim_s": duration,
            "wall_s": wall, "cpu_s": cpu,
            "mean_persons_in_range": n / max(frames, 1), "tracker_hz_in_loop": frames / sim.timing.tracker_s}


def run_benchmarks(json_path: str | None = None, quick: bool = False) -> dict:
    figures = {}

    def show(key, value, unit, what, digits=1):
        figures[key] = value
        print(f"{what:66s} {value:12,.{digits}f} {unit}", flush=True)

    print(f"crowdsim bench on {platform.processor() or platform.machine()}, Python {platform.python_version()}"
          f"{' (quick)' if quick else ''}")
    show("crowd_steps_per_s_100", bench_crowd(100, quick), "steps/s", "crowd step, 100 agents (dt 0.04 s)")
    show("crowd_steps_per_s_1000", bench_crowd(1000, quick), "steps/s", "crowd step, 1000 agents (dt 0.04 s)")
    show("laser_scans_per_s_100", bench_laser(100, quick), "scans/s", "laser scan, 381 beams, 100 people")
    for key, label, spec in tracker_variants():
        for n in (30, 80):
            for clutter in (False, True):
                show(f"tracker_{key}_cycles_per_s_{n}{'_clutter' if clutter else ''}",
                     bench_tracker(spec, n, clutter, quick), "cycles/s",
                     f"{label}, {n} tracks{', clutter' if clutter else ''}")
    for key, label, stage in GROUP_STAGES:
        for n in (30, 80):
            show(f"groups_{key}_ms_per_cycle_{n}", 1e3 / bench_groups(n, quick, **stage), "ms/cycle",
                 f"group stage, {label}, {n} tracks", digits=2)
    loop = bench_loop(quick)
    show("loop_realtime_factor", loop["realtime_factor"], "x real time",
         f"airport loop, 2 lasers @25 Hz, detectors, fusion, tracker, groups ({loop['mean_persons_in_range']:.0f} "
         "in range)")
    show("loop_cpu_realtime_factor", loop["cpu_realtime_factor"], "sim s/CPU s", "the same, in CPU time")
    figures["loop"] = loop
    coop = bench_seed001(quick)
    show("seed001_legs_ms", coop["legs_ms"], "ms/scan", "seed 001: leg detector and raw blobs, 361 beams")
    show("seed001_fseg_ms", coop["fseg_ms"], "ms/image", "seed 001: Sigma-Delta foreground people, 640 x 480")
    show("seed001_hog_ms", coop["hog_ms"], "ms/image", "seed 001: HOG people, 640 x 480, 8 scales")
    show("seed001_views_ms", coop["views_ms"], "ms/cycle", "seed 001: colour views of both cameras (HSV bins)")
    show("seed001_filter_ms", coop["filter_ms"], "ms/cycle", "seed 001: RJMCMC filter, all sensors, 4 passers-by")
    show("seed001_realtime_factor", coop["realtime_factor"], "x real time",
         f"seed 001: laser + {coop['cameras']} cameras + filter at 5 Hz ({coop['frames_per_s']:.1f} frames/s)", 2)
    rgbd = bench_seed003(quick)
    for stage, ms in rgbd["stage_ms"].items():
        show(f"seed003_{stage.replace(' ', '_')}_ms", ms, "ms/frame",
             f"seed 003: {stage} ({100 * rgbd['stage_share'][stage]:.0f}% of the time)", 2)
    show("seed003_frames_per_s", rgbd["frames_per_s"], "frames/s",
         "seed 003: RGB-D detector + tracker, 160 x 120, 5 people (paper: 26)", 1)
    figures["seed003"] = rgbd
    write_figures(json_path, figures)
    return figures


def main(args) -> int:
    """``crowdsim bench loop``."""
    from ..cli import check_json

    check_json(args)
    run_benchmarks(json_path=args.json, quick=args.quick)
    return 0
