"""``crowdsim report``: a run's metrics as tables and pictures people can look at.

From the files a run writes (groundtruth.csv, tracks.csv, detections.csv, robot.csv; groups.csv where the run has
one, older runs have none), re-scored here frame by frame: report.md with the tracking tables (seed 000's set at the
run's threshold, seed 001's at 0.3 m, identity and trajectory measures), a top-down picture of what happened (ground
truth thin, tracks coloured by id, ID switches and false positives marked), the per-frame counts, the metrics over
time, and an animated SVG top-down view (evaluation/svg.py), with the tracked groups where there is groups.csv.
Everything is drawn in the tracking frame (odom); walls are moved there with the first cycle's true odom pose.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pipeline.frames import compose, inverse, to_frame  # noqa: E402

from .clearmot import ClearMot, evaluate  # noqa: E402
from .columns import DETECTIONS, GROUNDTRUTH, GROUPS, ROBOT, TRACKS  # noqa: E402
from .io import load_sequence, read_table  # noqa: E402
from .score import SEED001_COLUMNS, pct, score_tracking, seeds_table, tracking_table  # noqa: E402
from .sequence import Sequence  # noqa: E402
from .stream import CsvPair  # noqa: E402
from .svg import write_svg  # noqa: E402

TRACK_COLUMNS = TRACKS.pick(*TRACKS)  # and the ground truth's first columns
GROUP_COLUMNS = GROUPS.pick("frame", "t", "group", "id", "x", "y")  # age is not drawn
ROBOT_COLUMNS = ROBOT.pick(*ROBOT)
SEED001_THRESHOLD = 0.3  # m, seed 001 Sec. 4: "within a 30 cm radius of the ground truth"


def _events(gt: Sequence, tracks: Sequence, threshold: float) -> dict:
    """Per frame: stamp and counts; and where the ID switches (at the person) and false positives happened."""
    cm = ClearMot(threshold)
    frames, counts, switches, false = [], [], [], []
    stamp_of = dict(zip(gt.frame.tolist(), gt.stamp.tolist())) if gt.stamp is not None else {}
    if tracks.stamp is not None:
        stamp_of.update(zip(tracks.frame.tolist(), tracks.stamp.tolist()))
    for f, r in cm.scored_frames(gt, tracks):
        frames.append(f)
        counts.append((r.gt, r.matches, r.fp, r.fn, r.id_switches, float(r.distances.sum())))
        if r.id_switches:
            rows = np.flatnonzero((gt.frame == f) & np.isin(gt.id, r.switched_gt_ids))
            switches.append(gt.position[rows])
        if r.fp:
            lo, hi = np.searchsorted(tracks.frame, [f, f + 1])
            ids = tracks.id[lo:hi]
            fp = ~np.isin(ids, r.matched_hyp_ids) & ~np.isin(ids, r.excused_hyp_ids)
            false.append(tracks.position[lo:hi][fp])
    return {"frame": np.array(frames), "stamp": np.array([stamp_of.get(f, np.nan) for f in frames]),
            "counts": np.array(counts).reshape(-1, 6),
            "switches": np.concatenate(switches) if switches else np.zeros((0, 2)),
            "false_positives": np.concatenate(false) if false else np.zeros((0, 2))}


def _paths(seq: Sequence):
    """(id, [k, 2] positions in frame order) per id (none for an empty sequence)."""
    if not len(seq):
        return []
    order = np.lexsort((seq.frame, seq.id))
    ids, xy = seq.id[order], seq.position[order]
    cuts = np.flatnonzero(np.diff(ids)) + 1
    return zip(np.split(ids, cuts), np.split(xy, cuts))


def _to_odom(walls: np.ndarray, robot: dict) -> np.ndarray:
    """World wall segments [k, 2, 2] in the odom frame of the first cycle (world_T_odom = true pose composed with
    the inverse of the odometry pose)."""
    if not len(robot["frame"]) or not len(walls):
        return np.asarray(walls, float).reshape(-1, 2, 2)
    true = np.array([robot["x"][0], robot["y"][0], robot["yaw"][0]])
    odom = np.array([robot["odom_x"][0], robot["odom_y"][0], robot["odom_yaw"][0]])
    return to_frame(compose(true, inverse(odom)), np.asarray(walls, float).reshape(-1, 2)).reshape(-1, 2, 2)


def _topdown(path, walls, gt, tracks, events, robot, title) -> None:
    fig, ax = plt.subplots(figsize=(10, 10))
    for seg in walls:
        ax.plot(seg[:, 0], seg[:, 1], color="0.2", lw=2)
    for _, xy in _paths(gt.select(~gt.ignore)):
        ax.plot(xy[:, 0], xy[:, 1], color="0.65", lw=0.5)
    hidden = gt.position[gt.ignore]
    ax.scatter(hidden[:, 0], hidden[:, 1], s=0.3, color="0.85", zorder=0)
    cmap = plt.get_cmap("tab20")
    for ids, xy in _paths(tracks):
        ax.plot(xy[:, 0], xy[:, 1], color=cmap(int(ids[0]) % 20), lw=1.1)
    if len(robot["frame"]):
        ax.plot(robot["odom_x"], robot["odom_y"], color="0.3", lw=3, alpha=0.4, label="robot (odometry)")
    fp, sw = events["false_positives"], events["switches"]
    ax.scatter(fp[:, 0], fp[:, 1], s=4, color="red", alpha=0.5, zorder=3, label=f"false positives ({len(fp)})")
    ax.scatter(sw[:, 0], sw[:, 1], s=60, marker="x", color="black", zorder=4, label=f"ID switches ({len(sw)})")
    ax.plot([], [], color="0.65", lw=0.5, label="ground truth")
    ax.scatter([], [], s=4, color="0.85", label="ground truth ignored (occluded or out of range)")
    ax.plot([], [], color=cmap(0), lw=1.1, label="tracks (colour = id)")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (odom)")
    ax.set_ylabel("y [m] (odom)")
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _counts(path, events) -> None:
    t, c = events["stamp"], events["counts"]
    fig, ax = plt.subplots(figsize=(11, 4))
    for k, (name, colour) in enumerate((("GT", "0.3"), ("TP", "tab:green"), ("FP", "tab:red"), ("FN", "tab:orange"))):
        ax.plot(t, c[:, k], color=colour, lw=0.9, label=name)
    ids = np.flatnonzero(c[:, 4])
    ax.scatter(t[ids], np.zeros(len(ids)), marker="|", s=80, color="black", label="ID switch")
    ax.set_xlabel("simulated time [s]")
    ax.set_ylabel("persons per frame")
    ax.legend(loc="upper left", fontsize=8, ncol=5)
    ax.set_title("per frame: ground truth that counts, matches, false positives, misses")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _over_time(path, events) -> None:
    t, c = events["stamp"], np.cumsum(events["counts"], axis=0)
    gt, tp, fp, fn, ids, dist = c.T
    with np.errstate(divide="ignore", invalid="ignore"):
        mota = np.where(gt > 0, 1 - (fp + fn + ids) / gt, np.nan)
        motp = np.where(tp > 0, dist / tp, np.nan)
    fig, axes = plt.subplots(3, 1, figsize=(11, 7), sharex=True)
    for ax, y, label in zip(axes, (100 * mota, motp, ids), ("MOTA so far [%]", "MOTP so far [m]", "ID switches")):
        ax.plot(t, y, lw=1.2)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("simulated time [s]")
    axes[0].set_title("the metrics as the run went on (accumulated from its start)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _columns(path: Path, names: tuple[str, ...]) -> np.ndarray | None:
    """The named columns of a run's CSV as rows, or None where the run has no such file."""
    if not path.exists():
        return None
    table = read_table(path, names)
    return np.column_stack([table[name] for name in names])


def _metres(v) -> str:
    return "n/a" if v is None else f"{v:.3f} m"


def write_report(out: Path, run_dir: Path, walls: np.ndarray, threshold: float, title: str) -> dict:
    """Write report.md and its figures into ``out`` from the run in ``run_dir``; return the tracking figures."""
    out, run_dir = Path(out), Path(run_dir)
    gt = load_sequence(run_dir / GROUNDTRUTH.file)
    tracks = load_sequence(run_dir / TRACKS.file, occlusion=False)
    robot = read_table(run_dir / ROBOT.file, ROBOT_COLUMNS) if (run_dir / ROBOT.file).exists() \
        else {"frame": np.zeros(0)}
    tracking = score_tracking(CsvPair(run_dir / GROUNDTRUTH.file, run_dir / TRACKS.file), threshold)
    seed001 = evaluate(gt, tracks, SEED001_THRESHOLD)
    events = _events(gt, tracks, threshold)
    walls = _to_odom(walls, robot)
    _topdown(out / "topdown_tracking.png", walls, gt, tracks, events, robot, title)
    _counts(out / "counts.png", events)
    _over_time(out / "over_time.png", events)
    write_svg(out / "topdown.svg", tracks=_columns(run_dir / TRACKS.file, TRACK_COLUMNS),
              groundtruth=_columns(run_dir / GROUNDTRUTH.file, TRACK_COLUMNS),
              detections=_columns(run_dir / DETECTIONS.file, DETECTIONS.pick("frame", "t", "id", "x", "y")),
              robot=np.column_stack([robot["t"], robot["odom_x"], robot["odom_y"]]) if len(robot["frame"]) else None,
              walls=walls, groups=_columns(run_dir / GROUPS.file, GROUP_COLUMNS), title=title)
    ignored = int(gt.ignore.sum())
    lines = [
        f"# Tracking report: {title}", "",
        f"{tracking['frames']} frames; ground truth {len(gt)} rows, of which {ignored} ignored (physically occluded "
        f"or out of range: neither a miss nor, when a track matches them, a false positive).", "",
        f"## CLEAR-MOT at {threshold:g} m (seed 000's set)", "", tracking_table(tracking), "",
        "| MT | PT | ML | persons | fragmentations | IDF1 | IDP | IDR | id swaps | re-initialisations |",
        "|---|---|---|---|---|---|---|---|---|---|",
        f"| {tracking['mt']} | {tracking['pt']} | {tracking['ml']} | {tracking['persons']} | "
        f"{tracking['fragmentations']} | {pct(tracking['idf1'])} | {pct(tracking['idp'])} | "
        f"{pct(tracking['idr'])} | {tracking['id_swaps']} | {tracking['reinitialisations']} |", "",
        "| HOTA | DetA | AssA | LocA | OSPA | localisation | cardinality | OSPA-T |",
        "|---|---|---|---|---|---|---|---|",
        f"| {pct(tracking['hota'])} | {pct(tracking['deta'])} | {pct(tracking['assa'])} | {pct(tracking['loca'])} | "
        f"{_metres(tracking['ospa_m'])} | {_metres(tracking['ospa_localisation_m'])} | "
        f"{_metres(tracking['ospa_cardinality_m'])} | {_metres(tracking['ospa_t_m'])} |", "",
        "HOTA after Luiten et al. 2021 for points (similarity max(0, 1 - d / 2 m), alpha 0.05-0.95); OSPA after "
        "Schuhmacher et al. 2008 with c = 1 m, p = 1, and OSPA-T's labelling term (Ristic et al. 2011).", "",
        f"## Seed 001's set at {SEED001_THRESHOLD:g} m", "", seeds_table([seed001], SEED001_COLUMNS), "",
        "## What happened", "",
        "![top-down view: ground truth thin grey, tracks coloured by id, ID switches as crosses at the person, "
        "false positives as red dots](topdown_tracking.png)", "",
        "![per-frame counts](counts.png)", "", "![metrics over time](over_time.png)", "",
        "[topdown.svg](topdown.svg): the run animated, to open in a browser and zoom into (detections as diamonds "
        "with their id and time, tracks with velocity arrows every second, the robot's odometry in grey"
        + (", each tracked group's members joined to its centroid, labelled G and its id"
           if (run_dir / GROUPS.file).exists() else "") + ").", "",
    ]
    (out / "report.md").write_text("\n".join(lines))
    (out / "tracking.json").write_text(json.dumps({"tracking": tracking, "seed001": seed001}, indent=2) + "\n")
    return tracking
