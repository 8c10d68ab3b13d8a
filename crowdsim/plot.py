"""The top-down picture of a run: walls, ground-truth trajectories (thin grey), tracks (coloured by id), robot path."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def _to_world(rows: np.ndarray, world_T_odom: np.ndarray) -> np.ndarray:
    """x, y of CSV rows (frame, t, id, x, y, ...) moved from odom to world with each frame's transform."""
    w = world_T_odom[rows[:, 0].astype(int)]
    c, s = np.cos(w[:, 2]), np.sin(w[:, 2])
    x, y = rows[:, 3], rows[:, 4]
    return np.stack([w[:, 0] + c * x - s * y, w[:, 1] + s * x + c * y], 1)


def _trajectories(rows: np.ndarray, xy: np.ndarray):
    order = np.lexsort((rows[:, 0], rows[:, 2]))
    ids = rows[order, 2]
    cuts = np.flatnonzero(np.diff(ids)) + 1
    return zip(np.split(ids, cuts), np.split(xy[order], cuts))


def plot_run(path, walls: np.ndarray, gt: np.ndarray, tracks: np.ndarray, robot_path: np.ndarray,
             world_T_odom: np.ndarray, crowd: np.ndarray, title: str) -> None:
    """``crowd`` rows (id, x, y) in the world frame: everyone, in range or not, drawn faintly beneath the rest."""
    fig, ax = plt.subplots(figsize=(9, 9))
    if len(crowd):
        ax.scatter(crowd[:, 1], crowd[:, 2], s=0.5, color="0.85", zorder=0)
    for seg in walls:
        ax.plot(seg[:, 0], seg[:, 1], color="0.2", lw=2)
    if len(gt):
        for _, xy in _trajectories(gt, _to_world(gt, world_T_odom)):
            ax.plot(xy[:, 0], xy[:, 1], color="0.6", lw=0.6)
    cmap = plt.get_cmap("tab20")
    if len(tracks):
        for ids, xy in _trajectories(tracks, _to_world(tracks, world_T_odom)):
            ax.plot(xy[:, 0], xy[:, 1], color=cmap(int(ids[0]) % 20), lw=1.2)
    if len(robot_path):
        ax.plot(robot_path[:, 0], robot_path[:, 1], color="tab:blue", lw=3, alpha=0.5, label="robot")
        ax.plot(*robot_path[-1, :2], "o", color="tab:blue", ms=10)
    ax.scatter([], [], s=4, color="0.85", label="everyone (outside the robot's range too)")
    ax.plot([], [], color="0.6", lw=0.6, label="ground truth")
    ax.plot([], [], color=cmap(0), lw=1.2, label="tracks (colour = id)")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
