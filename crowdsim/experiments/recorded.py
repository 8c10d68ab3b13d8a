"""Record a run's laser scans once, then run any pipeline on them: what seed 000 did with its recorded data, and what
makes Table II and the tuning affordable (the crowd and the ray casting are most of a run's time, and neither depends
on the pipeline when the robot drives its route).

A recording keeps, per tracking cycle, the scans of that cycle with each laser's pose in the odometry frame, the
odometry's placement in the map (for the map filter), and the ground truth the run scores against (ids, positions,
ignored, speeds). ``detect`` runs a pipeline's detectors, map filter and fusion on it as the loop does
(``crowdsim.loop.Simulation``), and ``track`` its tracker on those detections; a test checks that both give the run's
own MOTA exactly.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from evaluation.clearmot import ClearMot
from pipeline.assemble import build_pipeline
from pipeline.fusion import to_frame
from pipeline.types import DetectedPersons, LaserScan
from scenarios.typed import Scenario, Section, plain


@dataclass(frozen=True)
class Cycle:
    """One tracking cycle of a recorded run (tracking frame: odom)."""

    stamp: float
    scans: list[tuple[LaserScan, np.ndarray]]  # each scan of the cycle with its laser's pose (x, y, yaw) in odom
    world_T_odom: np.ndarray
    gt_ids: np.ndarray
    gt_position: np.ndarray
    gt_ignore: np.ndarray  # occluded or out of range
    gt_speed: np.ndarray  # m/s


def record(scenario: Scenario, seed: int, duration: float | None = None) -> list[Cycle]:
    """``duration`` seconds (None: the scenario's) of ``scenario`` (a loaded scenario driving its route) from
    ``seed``, after its warm-up."""
    from crowdsim.loop import Simulation

    sim = Simulation(scenario)
    if sim.driver.name not in ("route", "script"):
        raise ValueError(f"recording needs a scenario whose robot drives its route or script, not '{sim.driver.name}': "
                         "the robot would move with the pipeline's output")
    lasers = {laser.name: laser for laser in sim.lasers}
    sim.reset(seed)
    sim.warm_up()
    cycles = []
    for f in sim.frames(scenario.duration if duration is None else duration):
        gt = f.groundtruth
        cycles.append(Cycle(f.stamp, [(scan, lasers[scan.frame].pose_in(sim.robot.odom_pose)) for scan in f.scans],
                            f.world_T_odom, gt.track_id, gt.position, f.gt_tags.ignore,
                            np.linalg.norm(gt.velocity, axis=1)))
    return cycles


def detect(cycles: list[Cycle], pipeline_spec: Section | dict, floor_plan: Section) -> list[DetectedPersons]:
    """The fused detections of each cycle from a validated ``pipeline`` section's detectors, map filter and fusion
    (on the scenario's ``map``, ``floor_plan``); the pipeline is built from plain data, as the robot's software is."""
    lasers = sorted({scan.frame for c in cycles for scan, _ in c.scans})
    pipeline = build_pipeline(plain(pipeline_spec), lasers, plain(floor_plan))
    out = []
    for c in cycles:
        batches = {}
        for scan, pose in c.scans:
            found = to_frame(pipeline.detectors[scan.frame].detect(scan), pose, "odom")
            if pipeline.map_filter is not None:
                found = pipeline.map_filter.filter(found, c.world_T_odom)
            batches[scan.frame] = found
        out.append(pipeline.fusion.fuse(batches))
    return out


def track(cycles: list[Cycle], detections: list[DetectedPersons], tracker, threshold: float = 1.0,
          evaluations: dict[str, float] | None = None) -> tuple[dict[str, dict], float]:
    """``tracker`` (a fresh one) over the recorded detections, scored by CLEAR-MOT at ``threshold`` once per entry of
    ``evaluations`` (name -> least speed counted, m/s: slower persons are ignored as the occluded are; default
    {"all": 0}): the ClearMotResult by name, and the tracker's cycles per second of its own update time."""
    evaluations = {"all": 0.0} if evaluations is None else evaluations
    scores = {name: ClearMot(threshold) for name in evaluations}
    spent = 0.0
    for c, dets in zip(cycles, detections):
        t = time.perf_counter()
        tracks = tracker.update(c.stamp, dets)
        spent += time.perf_counter() - t
        for name, min_speed in evaluations.items():
            ignore = c.gt_ignore | (c.gt_speed < min_speed) if min_speed > 0 else c.gt_ignore
            scores[name].update(c.gt_ids, c.gt_position, tracks.track_id, tracks.position, ignore)
    return {name: score.result() for name, score in scores.items()}, len(cycles) / spent
