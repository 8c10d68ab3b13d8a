"""Seed 003's RGB-D detector and tracker on the robot's 160 x 120 depth camera, stage by stage, against its Table 9
(26 frames/s for detector and tracker on a 2011 quad-core Xeon, 19 on a laptop; Euclidean clustering 46% of the time,
HOG 23%, the tracker 8-17%)."""

from __future__ import annotations

import time

SCENARIO = "ktp_group"  # five people gathering: the most candidates a frame
LEAD_IN = 30  # frames (1 s) before anything is timed: the ground plane found, the first tracks started


def bench_seed003(quick: bool) -> dict:
    """Seconds per frame of each detector stage and of the tracker, their shares, and frames per second."""
    from crowdsim.experiments.seed003 import record
    from pipeline.detectors.rgbd import RgbdPeopleDetector
    from pipeline.fusion import to_frame
    from pipeline.tracking.rgbd_tracker import RgbdTracker

    frames = record(SCENARIO.removeprefix("ktp_"), "still", 1)[:LEAD_IN + (60 if quick else 300)]
    detector, tracker = RgbdPeopleDetector(), RgbdTracker()
    tracking = 0.0
    for k, frame in enumerate(frames):
        if k == LEAD_IN:
            detector.timing, tracking = {}, 0.0
        image = frame.image
        detections = to_frame(detector.detect(image), image.pose, "odom")
        t = time.perf_counter()
        tracker.see([image])
        tracker.update(image.stamp, detections)
        tracking += time.perf_counter() - t
    stages = {**detector.timing, "tracker": tracking}
    timed = len(frames) - LEAD_IN
    total = sum(stages.values())
    return {"frame_ms": 1e3 * total / timed, "frames_per_s": timed / total,
            "stage_ms": {name: 1e3 * s / timed for name, s in stages.items()},
            "stage_share": {name: s / total for name, s in stages.items()}, "frames": timed}
