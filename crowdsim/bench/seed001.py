"""Seed 001's cooperative system, part by part: the leg detector on a scan, each wall camera's foreground blobs and
HOG windows on an image, the colour views and the RJMCMC filter on a cycle, and the whole at 5 Hz against real time
(seed 001 Sec. 7: about 1 frame/s, HOG its bottleneck)."""

from __future__ import annotations

import time

import numpy as np

SCENARIO = "seed001_room_3"  # four passers-by
RATE = 5.0  # Hz, the sequences' frame rate
LEAD_IN = 15  # frames that start the cameras' background model before anything is timed


def capture(frames: int) -> list:
    """Per cycle of sequence III (``frames`` after the lead-in ones): its stamp, its scans with their lasers' poses
    in odom, and its wall-camera frames."""
    from crowdsim.loop import Simulation
    from scenarios import load_scenario

    scenario = load_scenario(SCENARIO)
    # the parts are timed on their own below
    scenario = scenario.replace(pipeline=scenario.pipeline.replace(detectors={}, tracker={"type": "nnt"}))
    sim = Simulation(scenario)
    sim.reset(scenario.seed)
    sim.warm_up()
    lasers = {laser.name: laser for laser in sim.lasers}
    return [(f.stamp, [(scan, lasers[scan.frame].pose_in(sim.robot.odom_pose)) for scan in f.scans], f.camera_frames)
            for f in sim.frames((frames + LEAD_IN) / RATE)]


def bench_seed001(quick: bool) -> dict:
    """ms per call of each part, and the whole system's frames per second and real-time factor at 5 Hz."""
    from pipeline.detectors.legs import LegDetector
    from pipeline.detectors.wall_camera import WallCameraDetector
    from pipeline.fusion import fuse, to_frame
    from pipeline.tracking.rjmcmc import RjmcmcTracker

    cycles = capture(5 if quick else 25)
    legs = LegDetector(blobs=True)
    cameras = {c.frame: {"fseg": WallCameraDetector(hog=False), "hog": WallCameraDetector(foreground=False)}
               for c in cycles[0][2]}
    tracker = RjmcmcTracker()
    spent = {"legs": [], "fseg": [], "hog": [], "views": [], "filter": []}

    def timed(part, call, k):
        t = time.perf_counter()
        out = call()
        if k >= LEAD_IN:
            spent[part].append(time.perf_counter() - t)
        return out

    for k, (stamp, scans, frames) in enumerate(cycles):
        batches = {}
        for scan, pose in scans:
            found = timed("legs", lambda: legs.detect(scan), k)
            batches.update({f"{scan.frame}/{name}": to_frame(b, pose, "odom") for name, b in found.items()})
        for frame in frames:
            for kind, detector in cameras[frame.frame].items():
                found = timed(kind, lambda: detector.detect(frame), k)
                batches[f"{frame.frame}/{kind}"] = to_frame(found[kind], frame.pose, "odom")
        timed("views", lambda: tracker.see(frames), k)
        timed("filter", lambda: tracker.update(stamp, fuse(batches, 0.0)), k)
    ms = {part: 1e3 * float(np.median(values)) for part, values in spent.items()}
    per_frame = ms["legs"] + len(cameras) * (ms["fseg"] + ms["hog"]) + ms["views"] + ms["filter"]
    return {**{f"{part}_ms": value for part, value in ms.items()}, "frame_ms": per_frame,
            "frames_per_s": 1e3 / per_frame, "realtime_factor": 1e3 / per_frame / RATE, "cameras": len(cameras)}
