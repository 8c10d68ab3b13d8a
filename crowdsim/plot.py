"""The top-down picture of a run: walls, ground-truth trajectories (thin grey), tracks (coloured by id), robot path.
The trajectories are line collections: one artist each, however many persons and tracks an hour-long run has."""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure  # drawn by Agg without pyplot: its figure manager and backends cost 0.15 s to import


def _trajectories(rows: np.ndarray):
    """(frame, id, x, y) rows as one [k, 2] path per id, in frame order."""
    order = np.lexsort((rows[:, 0], rows[:, 1]))
    cuts = np.flatnonzero(np.diff(rows[order, 1])) + 1
    return np.split(rows[order, 2:4], cuts), rows[order[np.r_[0, cuts]], 1] if len(rows) else np.zeros(0)


def _stack(parts: list[np.ndarray], columns: int) -> np.ndarray:
    return np.concatenate(parts) if parts else np.zeros((0, columns))


def plot_run(path, walls: np.ndarray, picture, title: str) -> None:
    """The run's top-down picture from what ``run.Picture`` kept (world frame): everyone, in range or not, faintly
    beneath the rest; ground truth thin grey; tracks coloured by id; the robot's path."""
    gt, tracks = _stack(picture.gt, 4), _stack(picture.tracks, 4)
    crowd, robot_path = _stack(picture.crowd, 3), np.array(picture.robot).reshape(-1, 3)
    fig = Figure(figsize=(9, 9))
    ax = fig.subplots()
    if len(crowd):
        ax.scatter(crowd[:, 1], crowd[:, 2], s=0.5, color="0.85", zorder=0)
    for seg in walls:
        ax.plot(seg[:, 0], seg[:, 1], color="0.2", lw=2)
    if len(gt):
        ax.add_collection(LineCollection(_trajectories(gt)[0], colors="0.6", linewidths=0.6))
    cmap = colormaps["tab20"]
    if len(tracks):
        paths, ids = _trajectories(tracks)
        ax.add_collection(LineCollection(paths, colors=cmap(ids.astype(int) % 20), linewidths=1.2))
    if len(robot_path):
        ax.plot(robot_path[:, 0], robot_path[:, 1], color="tab:blue", lw=3, alpha=0.5, label="robot")
        ax.plot(*robot_path[-1, :2], "o", color="tab:blue", ms=10)
    ax.scatter([], [], s=4, color="0.85", label="everyone (outside the robot's range too)")
    ax.plot([], [], color="0.6", lw=0.6, label="ground truth")
    ax.plot([], [], color=cmap(0), lw=1.2, label="tracks (colour = id)")
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
