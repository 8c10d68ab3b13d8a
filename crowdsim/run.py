"""``crowdsim run``: simulate a scenario, score the tracker, and write the run directory.

Outputs are written into a fresh temporary directory beside the target and moved into place only when complete,
so an interrupted or failed run leaves nothing half-written, and an existing non-empty directory is never touched.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from tqdm import tqdm

from evaluation.io import load_sequence
from pipeline.frames import compose, inverse
from evaluation.score import score_tracking, tracking_table
from scenarios.geometry import wall_segments

from .loop import Simulation

CSV_HEADER = "frame,t,id,x,y,vx,vy"
# the ground truth adds, per person, the true distance from the robot, whether within the evaluation's range, the
# laser beams that hit them this cycle (all lasers), whether any did, and seed 000's own occlusion test: the
# evaluation ignores persons out of range or physically occluded (evaluation/io.py)
GT_HEADER = CSV_HEADER + ",range,in_range,beams,visible,visible_seed000"
DETECTIONS_HEADER = "frame,t,id,x,y,confidence"  # the fused detections the tracker was given, odom
# the robot's true pose in the world and its odometry pose in odom (what the pipeline saw), per tracking cycle
ROBOT_HEADER = "frame,t,x,y,yaw,odom_x,odom_y,odom_yaw"
# every sensor frame's ground truth: for each person in the sensor's view or seen by it, the laser beams that hit
# them or the camera's visible share of them (amount), whether in view, and whether in view but unseen (occluded);
# t is the sensor frame's own time, frame the tracking cycle that delivered it
VISIBILITY_HEADER = "frame,t,id,sensor,amount,in_view,occluded"
CROWD_EVERY = 5  # tracking cycles between the crowd snapshots drawn in the top-down picture


class RunDirError(ValueError):
    pass


def check_out_dir(out: Path) -> None:
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise RunDirError(f"--out {out}: already exists and is not empty; expected a new or empty directory "
                          f"(nothing was written)")


def _rows(frame_index: int, stamp: float, persons) -> np.ndarray:
    n = len(persons)
    return np.column_stack([np.full(n, frame_index), np.full(n, stamp), persons.track_id, persons.position,
                            persons.velocity])


INTEGER_COLUMNS = {"id", "in_range", "beams", "visible", "visible_seed000"}


def _without_unset(value):
    """The data without the optional keys left unset (None), which a scenario file leaves out."""
    if isinstance(value, dict):
        return {k: _without_unset(v) for k, v in value.items() if v is not None}
    if isinstance(value, list):
        return [_without_unset(v) for v in value]
    return value


def _detection_rows(frame) -> np.ndarray:
    d = frame.detections
    return np.column_stack([np.full(len(d), frame.index), np.full(len(d), frame.stamp), d.detection_id,
                            d.position[:, :2], d.confidence])


def _robot_row(frame) -> np.ndarray:
    odom_pose = compose(inverse(frame.world_T_odom), frame.robot_pose)
    return np.array([[frame.index, frame.stamp, *frame.robot_pose, *odom_pose]])


def _gt_rows(frame) -> np.ndarray:
    """Ground-truth rows with their range and occlusion tags."""
    tags = frame.gt_tags
    return np.column_stack([_rows(frame.index, frame.stamp, frame.groundtruth), tags.range, tags.in_range,
                            tags.beams, tags.visible, tags.visible_seed000])


def _visibility_rows(frame, written: dict[str, float]) -> list[np.ndarray]:
    """Rows [frame, t, id, sensor index, amount, in_view, occluded] of the sensors with a frame new since
    ``written`` (sensor -> the stamp last written, updated)."""
    v, out = frame.visibility, []
    for k, name in enumerate(v.sensors):
        if np.isnan(v.stamps[k]) or written.get(name) == v.stamps[k]:
            continue
        written[name] = v.stamps[k]
        rows = np.flatnonzero(v.in_view[:, k] | (v.amount[:, k] > 0))
        out.append(np.column_stack([np.full(len(rows), frame.index), np.full(len(rows), v.stamps[k]), v.ids[rows],
                                    np.full(len(rows), k), v.amount[rows, k], v.in_view[rows, k],
                                    v.occluded[rows, k]]))
    return out


def write_visibility(path: Path, rows: list[np.ndarray], sensors: list[str]) -> None:
    table = (np.concatenate(rows) if rows else np.zeros((0, 7))).astype(object)
    table[:, 3] = np.array(sensors, object)[table[:, 3].astype(int)]
    np.savetxt(path, table, fmt=["%d", "%.2f", "%d", "%s", "%.4g", "%d", "%d"], delimiter=",",
               header=VISIBILITY_HEADER, comments="")


def write_csv(path: Path, rows: list[np.ndarray], header: str = CSV_HEADER) -> None:
    columns = header.count(",") + 1
    data = np.concatenate(rows) if rows else np.zeros((0, columns))
    fmt = ["%d", "%.2f"] + ["%d" if name in INTEGER_COLUMNS else "%.4f" for name in header.split(",")[2:]]
    np.savetxt(path, data, fmt=fmt, delimiter=",", header=header, comments="")


def summary_table(metrics: dict) -> str:
    tm = metrics["timing"]
    return tracking_table(metrics["tracking"], {"tracker Hz": f"{tm['tracker_hz']:.0f}",
                                                "real-time factor": f"{tm['realtime_factor']:.2f}x"})


def cameras_line(metrics: dict, before: str = "") -> str:
    """Which renderer drew the cameras, as a sentence ("" for a run without cameras)."""
    by_renderer = {}
    for name, backend in metrics["cameras"].items():
        by_renderer.setdefault(backend, []).append(name)
    return "".join(f"{before}Cameras rendered by {backend}: {', '.join(names)}."
                   for backend, names in by_renderer.items())


def write_directory(out: Path, write):
    """Call ``write(tmp)`` to fill a fresh temporary directory beside ``out`` and move it into place only when
    complete: a failure leaves nothing half-written, and an existing non-empty ``out`` is never touched.
    Returns what ``write`` returns."""
    out = Path(out)
    check_out_dir(out)
    made = [p for p in reversed(out.absolute().parents) if not p.exists()]  # parents this creates
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = None
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
        umask = os.umask(0)
        os.umask(umask)
        tmp.chmod(0o777 & ~umask)  # mkdtemp makes it private; the finished directory is an ordinary one
        result = write(tmp)
        if out.exists():
            out.rmdir()  # checked empty above
        tmp.rename(out)
    except BaseException:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
        for parent in reversed(made):
            try:
                parent.rmdir()
            except OSError:
                break
        raise
    return result


def run(scenario: dict, out: Path, rrd: bool = False, progress: bool = True) -> dict:
    """Simulate, score and write ``out``; return metrics.json's content."""
    return write_directory(out, lambda tmp: _simulate(scenario, tmp, rrd, progress))


def _simulate(scenario: dict, tmp: Path, rrd: bool, progress: bool) -> dict:
    from .plot import plot_run
    from .recording import Recording

    sim = Simulation(scenario)
    start = time.perf_counter()
    sim.warm_up()
    warmup_s = time.perf_counter() - start
    recording = Recording(tmp / "recording.rrd", wall_segments(scenario), sim) if rrd else None
    gt_rows, track_rows, detection_rows, robot_rows, counts, robot_path, odom, crowd = [], [], [], [], [], [], [], []
    visibility_rows, written = [], {}
    duration = scenario["duration"]
    bar = tqdm(total=round(duration, 2), unit="sim s", disable=not progress, desc=scenario["name"],
               bar_format="{l_bar}{bar}| {n:.1f}/{total:.0f} sim s [{elapsed}<{remaining}, {rate_fmt}]")
    t0 = sim.crowd.t
    for frame in sim.frames(duration):
        gt_rows.append(_gt_rows(frame))
        track_rows.append(_rows(frame.index, frame.stamp, frame.tracks))
        detection_rows.append(_detection_rows(frame))
        robot_rows.append(_robot_row(frame))
        visibility_rows += _visibility_rows(frame, written)
        counts.append(int(frame.gt_tags.in_range.sum()))
        robot_path.append(frame.robot_pose)
        odom.append(frame.world_T_odom)
        if frame.index % CROWD_EVERY == 0:  # everyone, in range or not, for the picture
            crowd.append(np.column_stack([frame.agents.id, frame.agents.position]))
        if recording:
            recording.log(frame)
            recording.log_images(frame)
        bar.update(round(frame.stamp - t0, 2) - bar.n)
    bar.close()
    if recording:
        recording.close()
    timing = sim.timing
    write_csv(tmp / "groundtruth.csv", gt_rows, GT_HEADER)
    write_csv(tmp / "tracks.csv", track_rows)
    write_csv(tmp / "detections.csv", detection_rows, DETECTIONS_HEADER)
    write_csv(tmp / "robot.csv", robot_rows, ROBOT_HEADER)
    write_visibility(tmp / "visibility.csv", visibility_rows, [laser.name for laser in sim.lasers]
                     + [camera.name for camera in (*sim.depth_cameras, *sim.wall_cameras)])
    # the scenario as run, every default filled in: a scenario file that runs again as it is
    resolved = _without_unset({key: value for key, value in scenario.items() if key != "source"})
    (tmp / "scenario.yaml").write_text(f"# resolved from {scenario['source']}\n"
                                       + yaml.safe_dump(resolved, sort_keys=False))
    # scored from the files as written, so that `crowdsim evaluate` on them gives the same figures
    tracking = score_tracking(load_sequence(tmp / "groundtruth.csv"), load_sequence(tmp / "tracks.csv", False),
                              scenario["evaluation"]["threshold"])
    metrics = {
        "scenario": scenario["name"],
        "seed": scenario["seed"],
        "duration_s": duration,
        "frames": len(counts),  # tracking cycles (tracking.frames: those with any ground truth or track)
        "tracking": tracking,
        "groundtruth": {"mean_persons_in_range": float(np.mean(counts)) if counts else 0.0,
                        "max_persons_in_range": int(max(counts)) if counts else 0},
        # which renderer drew each camera: egl or osmesa (MuJoCo's OpenGL), or raycast where no GL context was had
        "cameras": {camera.name: camera.backend for camera in (*sim.depth_cameras, *sim.wall_cameras)},
        "timing": {
            "wall_s": timing.wall_s,
            "realtime_factor": duration / timing.wall_s if timing.wall_s > 0 else float("inf"),
            "tracker_hz": timing.tracker_cycles / timing.tracker_s if timing.tracker_s > 0 else float("inf"),
            "crowd_s": timing.crowd_s,
            "sensors_s": timing.sensors_s,
            "warmup_wall_s": warmup_s,
        },
    }
    (tmp / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    table = summary_table(metrics)
    (tmp / "summary.md").write_text(
        f"# {scenario['name']} (seed {scenario['seed']}, {duration:g} s)\n\n{table}\n\n"
        f"Persons within {scenario['evaluation']['max_range']:g} m of the robot: "
        f"{metrics['groundtruth']['mean_persons_in_range']:.1f} on average, "
        f"{metrics['groundtruth']['max_persons_in_range']} at most.{cameras_line(metrics, ' ')}\n\n"
        "![top-down view](topdown.png)\n")
    plot_run(tmp / "topdown.png", wall_segments(scenario), np.concatenate(gt_rows) if gt_rows else np.zeros((0, 7)),
             np.concatenate(track_rows) if track_rows else np.zeros((0, 7)), np.array(robot_path),
             np.array(odom), np.concatenate(crowd) if crowd else np.zeros((0, 3)),
             f"{scenario['name']}, seed {scenario['seed']}")
    return metrics
