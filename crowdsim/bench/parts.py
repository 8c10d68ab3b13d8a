"""``crowdsim bench``: the speed of each hot part (crowd, laser, tracker) and of the whole loop, measured side by side
in one run."""

from __future__ import annotations

import platform
import time

import numpy as np

from scenarios import load_scenario

from .common import HALL, populated_crowd, rate, write_figures

def bench_crowd(n_agents: int, quick: bool) -> float:
    crowd, _ = populated_crowd(n_agents)
    return rate(lambda: crowd.step(0.04), 5 if quick else 40 if n_agents <= 100 else 10)


def bench_laser(n_people: int, quick: bool) -> float:
    from sensors import Laser, Scene, parts_at
    from sensors.body import body_scale

    crowd, scenario = populated_crowd(n_people)
    scene = Scene(crowd.walls, 0.425, n_people, parts_at(scenario["sensors"]["lasers"][0]["height"]))
    pose = np.array([HALL / 2, HALL / 2, 0.0])
    scene.sync(pose, crowd.id, crowd.pos, crowd.vel, crowd.walked, body_scale(crowd.id, crowd.radius))
    laser = Laser(scenario["sensors"]["lasers"][0], scene, np.random.default_rng(0))
    return rate(lambda: laser.scan(0.0, pose), 50 if quick else 400)


def bench_tracker(n_tracks: int, quick: bool) -> float:
    from pipeline.tracking.nnt import NearestNeighbourTracker
    from pipeline.types import DetectedPersons

    rng = np.random.default_rng(0)
    start = rng.uniform(0, 30, (n_tracks, 2))
    heading = rng.uniform(-np.pi, np.pi, n_tracks)
    vel = 1.3 * np.stack([np.cos(heading), np.sin(heading)], 1)
    cov = np.zeros((n_tracks, 3, 3))
    cov[:, 0, 0] = cov[:, 1, 1] = 0.1
    cov[:, 2, 2] = 1e6
    frames = []
    for k in range(400):
        pos = np.concatenate([start + vel * k * 0.04 + rng.normal(0, 0.05, (n_tracks, 2)), np.zeros((n_tracks, 1))],
                             1)
        frames.append(DetectedPersons(k * 0.04, "odom", "laser2d", np.arange(n_tracks) + k * n_tracks, pos, cov,
                                      np.ones(n_tracks)))
    tracker = NearestNeighbourTracker(frame="odom")
    for f in frames[:10]:  # confirm the tracks first, so the timed cycles run with n_tracks tracks
        tracker.update(f.stamp, f)
    state = {"k": 10}

    def cycle():
        f = frames[state["k"] % len(frames)]
        f.stamp = state["k"] * 0.04
        tracker.update(f.stamp, f)
        state["k"] += 1

    return rate(cycle, 50 if quick else 190 // 5)


def bench_loop(quick: bool) -> dict:
    from crowdsim.loop import Simulation

    duration = 5.0 if quick else 30.0
    scenario = load_scenario("airport_disembarkation", duration=duration)
    sim = Simulation(scenario)
    sim.warm_up()
    t = time.perf_counter()
    n = sum(len(f.groundtruth) for f in sim.frames(duration))
    wall = time.perf_counter() - t
    frames = sim.timing.tracker_cycles
    return {"realtime_factor": duration / wall, "sim_s": duration, "wall_s": wall,
            "mean_persons_in_range": n / max(frames, 1), "tracker_hz_in_loop": frames / sim.timing.tracker_s}


def run_benchmarks(json_path: str | None = None, quick: bool = False) -> dict:
    figures = {}

    def show(key, value, unit, what):
        figures[key] = value
        print(f"{what:58s} {value:12,.1f} {unit}", flush=True)

    print(f"crowdsim bench on {platform.processor() or platform.machine()}, Python {platform.python_version()}"
          f"{' (quick)' if quick else ''}")
    show("crowd_steps_per_s_100", bench_crowd(100, quick), "steps/s", "crowd step, 100 agents (dt 0.04 s)")
    show("crowd_steps_per_s_1000", bench_crowd(1000, quick), "steps/s", "crowd step, 1000 agents (dt 0.04 s)")
    show("laser_scans_per_s_100", bench_laser(100, quick), "scans/s", "laser scan, 381 beams, 100 people")
    show("tracker_cycles_per_s_30", bench_tracker(30, quick), "cycles/s", "tracker cycle, 30 tracks")
    show("tracker_cycles_per_s_80", bench_tracker(80, quick), "cycles/s", "tracker cycle, 80 tracks")
    loop = bench_loop(quick)
    show("loop_realtime_factor", loop["realtime_factor"], "x real time",
         f"airport loop, 2 lasers @25 Hz + tracker + CLEAR-MOT ({loop['mean_persons_in_range']:.0f} in range)")
    figures["loop"] = loop
    write_figures(json_path, figures)
    return figures
