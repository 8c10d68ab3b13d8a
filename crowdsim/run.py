"""``crowdsim run``: simulate a scenario, score the tracker, and write the run directory.

Outputs are written into a temporary directory moved into place only when complete (crowdsim/outdir.py), so an
interrupted or failed run leaves nothing half-written, and an existing non-empty directory is never touched. The
run's memory does not grow with its length: its CSVs stream to disk as the frames come, they are scored from disk in
chunks (evaluation/score.py), and the top-down picture keeps at most ``PICTURE_SECONDS`` worth of cycles.

A scenario whose robot drives to goals or follows a person (``robot.driver``) also writes what the navigation
metrics need (docs/navigation-metrics.md): persons.csv, navigation.json and, for following, following.csv, streamed
like the other CSVs; the run ends at the last goal, and its navigation metrics, scored from those files as
``crowdsim evaluate-nav`` scores them, join metrics.json. What the navigation metrics read (robot.csv, persons.csv,
following.csv) is written at full precision (``EXACT``), so that the figures are those ``crowdsim navigate`` computes
from the same values in memory: acceleration and jerk are second and third differences, which rounding to a tenth of
a millimetre and a hundredth of a second would swamp.
"""

from __future__ import annotations

import gc
import json
import math
import time
from pathlib import Path

import numpy as np
import yaml
from tqdm import tqdm

from evaluation.columns import (DETECTIONS, FLAGS, FOLLOWING, GROUNDTRUTH, GROUPS, PERSONS, RELATIONS, ROBOT,
                                TRACKS, VISIBILITY, WHOLE, Columns)
from evaluation.decimals import format_rows, plain_decimals
from evaluation.heap import release_memory
from evaluation.navigation import navigation_metrics, read_nav_run
from evaluation.navigation_report import json_safe
from evaluation.group_score import GroupScore, groups_table
from evaluation.score import score_tracking, tracking_table
from evaluation.stream import CsvPair
from pipeline.compiled import kernel
from pipeline.frames import compose, inverse
from scenarios.typed import Scenario, as_written

from .loop import Simulation
from .outdir import write_directory

# the group stage's output (odom): the relations between tracks within RELATIONS_WRITTEN of each other (farther pairs
# are past the gates, strength 0.1, and a pair of persons the group scores look at, within 3 m, has its tracks within
# 3 m + twice the 1 m matching threshold), and one row per member of each group of two or more, with the group's
# centroid and age. Each file's columns: evaluation/columns.py.
RELATIONS_FORMAT = ["%d", "%.2f", "%d", "%d", "%.6f"]
RELATIONS_WRITTEN = 5.0  # m
# a number in full: Python's str of a float is the shortest decimal that reads back as the very same float64 (1.5008,
# not 1.5007999999999999), for the files the navigation metrics read, whose derivatives amplify any rounding
EXACT = "%s"
# visibility.csv: t is the sensor frame's own time, frame the tracking cycle that delivered it
VISIBILITY_FORMAT = ["%d", "%.2f", "%d", "%s", "%.4g", "%d", "%d"]
CROWD_EVERY = 5  # tracking cycles between the crowd snapshots drawn in the top-down picture
# the top-down picture draws every cycle of a run this long or shorter, and every k-th cycle of a run k times as
# long, so it holds at most this much of the run
PICTURE_SECONDS = 120.0
BLOCK_ROWS = 1 << 12  # rows a CSV gathers before they are written


def _rows(frame_index: int, stamp: float, persons) -> np.ndarray:
    n = len(persons)
    return np.column_stack([np.full(n, frame_index), np.full(n, stamp), persons.track_id, persons.position,
                            persons.velocity])


def csv_format(columns: Columns, real: str = "%.4f", t: str = "%.2f") -> list[str]:
    """A CSV's column formats: frame and the whole-number and flag columns whole, t with ``t``, the other columns
    with ``real`` (by default positions to a tenth of a millimetre, times to a hundredth of a second)."""
    return ["%d", t] + ["%d" if name in WHOLE or name in FLAGS else real for name in columns[2:]]


# the files the navigation metrics read (evaluation/navigation.py read_nav_run), every number as it was
ROBOT_FORMAT = csv_format(ROBOT, EXACT, EXACT)
PERSONS_FORMAT = csv_format(PERSONS, EXACT, EXACT)
FOLLOWING_FORMAT = csv_format(FOLLOWING, EXACT, EXACT)


def _row_of(ids: np.ndarray, query: np.ndarray) -> np.ndarray:
    """The row of each of ``query`` in ``ids`` (unique, any order; every query among them)."""
    order = np.argsort(ids)
    return order[np.searchsorted(ids[order], query)]


def _relation_rows(frame) -> np.ndarray:
    r, tracks = frame.relations, frame.tracks
    near = _near(tracks.track_id, tracks.position, r.track_a, r.track_b, RELATIONS_WRITTEN)
    n = int(near.sum())
    return np.column_stack([np.full(n, frame.index), np.full(n, frame.stamp), r.track_a[near], r.track_b[near],
                            r.strength[near]])


@kernel
def _near(ids, position, a, b, reach):
    """Which relations (track ids a, b; all among ``ids``) join tracks within ``reach`` of each other (m)."""
    order = np.argsort(ids)
    by_id = ids[order]
    near = np.empty(len(a), np.bool_)
    for k in range(len(a)):
        i, j = order[np.searchsorted(by_id, a[k])], order[np.searchsorted(by_id, b[k])]
        near[k] = math.hypot(position[i, 0] - position[j, 0], position[i, 1] - position[j, 1]) <= reach
    return near


def _group_rows(frame) -> np.ndarray:
    g = frame.groups
    k = _row_of(g.group_id, g.member_group)
    n = len(k)
    return np.column_stack([np.full(n, frame.index), np.full(n, frame.stamp), g.member_group, g.member_track,
                            g.centroid[k], g.age[k]])


def _detection_rows(frame) -> np.ndarray:
    d = frame.detections
    return np.column_stack([np.full(len(d), frame.index), np.full(len(d), frame.stamp), d.detection_id,
                            d.position[:, :2], d.confidence])


def _robot_row(frame) -> np.ndarray:
    odom_pose = compose(inverse(frame.world_T_odom), frame.robot_pose)
    return np.array([[frame.index, frame.stamp, *frame.robot_pose, *odom_pose]])


def _person_rows(frame) -> np.ndarray:
    a = frame.agents
    n = len(a.id)
    return np.column_stack([np.full(n, frame.index), np.full(n, frame.stamp), a.id, a.position, a.velocity,
                            a.radius])


def navigation_spec(scenario: Scenario, target_id: int) -> dict:
    """navigation.json's content (docs/navigation-metrics.md): the task of the scenario's driver, the time limit
    (the scenario's duration), the robot's radius and the walls. A goals driver's task is its last goal."""
    robot = scenario.robot
    spec = {"robot_radius": robot.radius, "time_limit": scenario.duration,
            "walls": scenario.map.segments.reshape(-1, 4).tolist()}
    if robot.driver == "goals":
        return {"task": "goal", "goal": list(robot.goals[-1]), "goal_radius": robot.goal_radius, **spec}
    return {"task": "follow", "target_id": int(target_id), "band": list(robot.follow.band), **spec}


def _gt_rows(frame) -> np.ndarray:
    """Ground-truth rows with their range and occlusion tags."""
    tags = frame.gt_tags
    return np.column_stack([_rows(frame.index, frame.stamp, frame.groundtruth), tags.range, tags.in_range,
                            tags.beams, tags.visible, tags.visible_seed000, frame.groundtruth.group_id])


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


class CsvWriter:
    """A CSV of ``columns`` in ``folder``, written as its rows come, a block at a time (the bytes are those
    ``np.savetxt`` of all rows at once would write). ``fmt``: the columns' formats, ``csv_format(columns)`` by
    default. ``names``: for a column of indices, the names written in their place. The rows gather in one buffer
    made once: a long run's small arrays, kept between blocks, would scatter over the heap and grow it."""

    def __init__(self, folder: Path, columns: Columns, fmt: list[str] | None = None,
                 names: dict[int, list[str]] = None):
        self.file = open(Path(folder) / columns.file, "w")
        self.file.write(columns.header + "\n")
        self.fmt = fmt or csv_format(columns)
        self.names = {column: np.array(values, object) for column, values in (names or {}).items()}
        self.decimals = None if self.names else plain_decimals(self.fmt)  # written by the kernel when all plain
        self.buffer = np.empty((BLOCK_ROWS, len(self.fmt)))
        self.rows = 0

    def write(self, rows: np.ndarray) -> None:
        while len(rows):
            n = min(len(rows), BLOCK_ROWS - self.rows)
            self.buffer[self.rows:self.rows + n] = rows[:n]
            self.rows += n
            rows = rows[n:]
            if self.rows == BLOCK_ROWS:
                self.flush()

    def flush(self) -> None:
        table = self.buffer[:self.rows]
        text = None if self.decimals is None else format_rows(table, self.decimals)
        if text is None:
            if self.names:
                table = table.astype(object)
                for column, names in self.names.items():
                    table[:, column] = names[table[:, column].astype(int)]
            # one format over the whole block: the text ``np.savetxt`` writes row by row, in one string
            text = (",".join(self.fmt) + "\n") * len(table) % tuple(table.ravel().tolist())
        try:
            self.file.write(text)
        except OSError as e:  # a full disk, say: the error names the file
            raise OSError(e.errno, e.strerror, self.file.name) from None
        self.rows = 0

    def close(self) -> None:
        self.flush()
        self.file.close()


class Picture:
    """What the top-down picture draws, kept for every ``stride``-th cycle: ground truth and tracks as world-frame
    rows (frame, id, x, y), the robot's path, and every few cycles the whole crowd (id, x, y); in single precision
    (positions to micrometres and ids up to 16 million exactly, in half the memory)."""

    def __init__(self, stride: int):
        self.stride = stride
        self.gt, self.tracks, self.robot, self.crowd = [], [], [], []

    def add(self, frame) -> None:
        if frame.index % self.stride:
            return
        self.gt.append(_world_rows(frame.index, frame.groundtruth, frame.world_T_odom).astype(np.float32))
        self.tracks.append(_world_rows(frame.index, frame.tracks, frame.world_T_odom).astype(np.float32))
        self.robot.append(frame.robot_pose)
        if frame.index % (CROWD_EVERY * self.stride) == 0:  # everyone, in range or not
            self.crowd.append(np.column_stack([frame.agents.id, frame.agents.position]).astype(np.float32))


def _world_rows(index: int, persons, world_T_odom: np.ndarray) -> np.ndarray:
    """(frame, id, x, y) of persons in odom, moved to the world with the cycle's true transform."""
    world = compose(world_T_odom, np.column_stack([persons.position, np.zeros(len(persons))]))
    return np.column_stack([np.full(len(persons), index), persons.track_id, world[:, :2]])


def navigation_tables(figures: dict) -> str:
    """One run's navigation metrics as the two tables of ``crowdsim evaluate-nav``."""
    from evaluation.navigation_report import OUTCOME_COLUMNS, SOCIAL_COLUMNS, nav_table

    return "\n\n".join(_one_row(nav_table(["this run"], [figures], columns)) for columns in (OUTCOME_COLUMNS,
                                                                                            SOCIAL_COLUMNS))


def _one_row(table: str) -> str:
    """The table without its mean and sd rows (one run: its own figures)."""
    return "\n".join(table.splitlines()[:3])


def summary_table(metrics: dict) -> str:
    """The tracking table and, below it, the groups table."""
    tm = metrics["timing"]
    return (tracking_table(metrics["tracking"], {"tracker Hz": f"{tm['tracker_hz']:.0f}",
                                                 "real-time factor": f"{tm['realtime_factor']:.2f}x"})
            + "\n\n" + groups_table(metrics["groups"], {"groups ms/cycle": f"{tm['groups_ms_per_cycle']:.2f}"}))


def cameras_line(metrics: dict, before: str = "") -> str:
    """Which renderer drew the cameras, as a sentence ("" for a run without cameras)."""
    by_renderer = {}
    for name, backend in metrics["cameras"].items():
        by_renderer.setdefault(backend, []).append(name)
    return "".join(f"{before}Cameras rendered by {backend}: {', '.join(names)}."
                   for backend, names in by_renderer.items())


def run(scenario: Scenario, out: Path, rrd: bool = False, progress: bool = True) -> dict:
    """Simulate, score and write ``out``; return metrics.json's content."""
    return write_directory(out, lambda tmp: _simulate(scenario, tmp, rrd, progress))


def _simulate(scenario: Scenario, tmp: Path, rrd: bool, progress: bool) -> dict:
    sim = Simulation(scenario)
    start = time.perf_counter()
    sim.warm_up()
    warmup_s = time.perf_counter() - start
    gc.freeze()  # what the imports and the world hold lives as long as the run: out of every collection
    recording = None
    if rrd:
        from .recording import Recording  # rerun, imported only for a recording: 50 MB of memory

        recording = Recording(tmp / "recording.rrd", scenario.map.segments, sim)
    sensors = [laser.name for laser in sim.lasers] + [camera.name for camera in (*sim.depth_cameras,
                                                                                 *sim.wall_cameras)]
    csv = {"groundtruth": CsvWriter(tmp, GROUNDTRUTH), "tracks": CsvWriter(tmp, TRACKS),
           "detections": CsvWriter(tmp, DETECTIONS), "relations": CsvWriter(tmp, RELATIONS, RELATIONS_FORMAT),
           "groups": CsvWriter(tmp, GROUPS), "robot": CsvWriter(tmp, ROBOT, ROBOT_FORMAT),
           "visibility": CsvWriter(tmp, VISIBILITY, VISIBILITY_FORMAT, {3: sensors})}
    navigating = sim.driver.name in ("goals", "follow")
    if navigating:
        csv["persons"] = CsvWriter(tmp, PERSONS, PERSONS_FORMAT)
    if sim.driver.name == "follow":
        csv["following"] = CsvWriter(tmp, FOLLOWING, FOLLOWING_FORMAT)
    duration = scenario.duration
    picture = Picture(max(1, math.ceil(duration / PICTURE_SECONDS - 1e-9)))
    written: dict[str, float] = {}
    frames, persons, most = 0, 0, 0  # tracking cycles; persons in range summed over them, and at most
    bar = tqdm(total=round(duration, 2), unit="sim s", disable=not progress, desc=scenario.name,
               bar_format="{l_bar}{bar}| {n:.1f}/{total:.0f} sim s [{elapsed}<{remaining}, {rate_fmt}]")
    t0 = sim.crowd.t
    try:
        for frame in sim.frames(duration):
            csv["groundtruth"].write(_gt_rows(frame))
            csv["tracks"].write(_rows(frame.index, frame.stamp, frame.tracks))
            csv["detections"].write(_detection_rows(frame))
            csv["relations"].write(_relation_rows(frame))
            csv["groups"].write(_group_rows(frame))
            csv["robot"].write(_robot_row(frame))
            for rows in _visibility_rows(frame, written):
                csv["visibility"].write(rows)
            if navigating:
                csv["persons"].write(_person_rows(frame))
            if sim.driver.name == "follow":
                csv["following"].write(np.array([[frame.index, frame.stamp, frame.target_track,
                                                  frame.target_visible]]))
            in_range = int(frame.gt_tags.in_range.sum())
            frames, persons, most = frames + 1, persons + in_range, max(most, in_range)
            picture.add(frame)
            if recording:
                recording.log(frame)
                recording.log_images(frame)
            bar.update(round(frame.stamp - t0, 2) - bar.n)
    finally:
        bar.close()
        for writer in csv.values():
            writer.close()
    if recording:
        recording.close()
    timing = sim.timing
    if navigating:
        # the time recorded: the run ends early at the last goal
        duration = sim.crowd.t - t0
        (tmp / "navigation.json").write_text(json.dumps(navigation_spec(scenario, sim.target_id), indent=1) + "\n")
    cameras = {camera.name: camera.backend for camera in (*sim.depth_cameras, *sim.wall_cameras)}
    # the scenario as run, every default filled in: a scenario file that runs again as it is
    resolved = {key: value for key, value in as_written(scenario).items() if key != "source"}
    (tmp / "scenario.yaml").write_text(f"# resolved from {scenario.source}\n"
                                       + yaml.safe_dump(resolved, sort_keys=False))
    # the simulation is done with: what it held goes back before the scoring needs memory
    del sim, recording
    release_memory()
    # scored from the files as written, so that `crowdsim evaluate` on them gives the same figures
    group_score = GroupScore(tmp / RELATIONS.file, tmp / GROUPS.file)
    tracking = score_tracking(CsvPair(tmp / GROUNDTRUTH.file, tmp / TRACKS.file, groups=True),
                              scenario.evaluation.threshold, group_score.add)
    groups = group_score.result()
    release_memory()  # and the scoring's memory before the drawing's
    from .plot import plot_run  # matplotlib, imported once the scoring is done: 20 MB less at its peak

    plot_run(tmp / "topdown.png", scenario.map.segments, picture, f"{scenario.name}, seed {scenario.seed}")
    navigation = navigation_metrics(read_nav_run(tmp)) if navigating else None
    metrics = {
        "scenario": scenario.name,
        "seed": scenario.seed,
        "duration_s": duration,
        "frames": frames,  # tracking cycles (tracking.frames: those with any ground truth or track)
        "tracking": tracking,
        "groups": groups,
        "groundtruth": {"mean_persons_in_range": persons / frames if frames else 0.0,
                        "max_persons_in_range": most},
        # which renderer drew each camera: egl or osmesa (MuJoCo's OpenGL), or raycast where no GL context was had
        "cameras": cameras,
        "timing": {
            "wall_s": timing.wall_s,
            "realtime_factor": duration / timing.wall_s if timing.wall_s > 0 else float("inf"),
            "tracker_hz": timing.tracker_cycles / timing.tracker_s if timing.tracker_s > 0 else float("inf"),
            "groups_ms_per_cycle": 1e3 * timing.groups_s / max(timing.tracker_cycles, 1),
            "crowd_s": timing.crowd_s,
            "sensors_s": timing.sensors_s,
            "warmup_wall_s": warmup_s,
        },
    }
    if navigation is not None:
        metrics["navigation"] = json_safe(navigation)  # JSON has no NaN or inf: null (for min TTC, inf)
    (tmp / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    table = summary_table(metrics)
    if navigation is not None:
        table += "\n\n" + navigation_tables(navigation)
        metrics["navigation"] = navigation  # the caller gets the figures, NaN and inf as they are
    (tmp / "summary.md").write_text(
        f"# {scenario.name} (seed {scenario.seed}, {duration:g} s)\n\n{table}\n\n"
        f"Persons within {scenario.evaluation.max_range:g} m of the robot: "
        f"{metrics['groundtruth']['mean_persons_in_range']:.1f} on average, "
        f"{metrics['groundtruth']['max_persons_in_range']} at most.{cameras_line(metrics, ' ')}\n\n"
        "![top-down view](topdown.png)\n")
    return metrics
