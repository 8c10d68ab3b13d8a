"""The top-down picture of an episode (``render_mode="rgb_array"``): the room, the persons (the target in orange),
the robot with its heading, its goal, and, when tracks are observed, the pipeline's tracks as rings; drawn with numpy
at ``PIXELS_PER_M``."""

from __future__ import annotations

import numpy as np

from pipeline.frames import transform_points

PIXELS_PER_M = 25
FLOOR, WALL, PERSON, TARGET, ROBOT, GOAL, TRACK = (np.array(c, np.uint8) for c in (
    (245, 245, 240), (60, 60, 60), (70, 110, 200), (230, 150, 30), (200, 40, 40), (40, 160, 60), (20, 20, 20)))


def top_down(episodes, k: int) -> np.ndarray:
    """World k as an [h, w, 3] uint8 image, y up."""
    w = episodes.worlds
    width, height = w.size
    px, py = int(round(width * PIXELS_PER_M)) + 2, int(round(height * PIXELS_PER_M)) + 2
    image = np.empty((py, px, 3), np.uint8)
    image[:] = WALL
    image[1:-1, 1:-1] = FLOOR
    u = (np.arange(px) - 0.5) / PIXELS_PER_M  # pixel centres in metres
    v = (py - 1 - np.arange(py) - 0.5) / PIXELS_PER_M

    def disc(x, y, r, colour, ring=False):
        inside = (u[None, :] - x) ** 2 + (v[:, None] - y) ** 2 <= r * r
        if ring:
            inside &= (u[None, :] - x) ** 2 + (v[:, None] - y) ** 2 >= (r - 1.5 / PIXELS_PER_M) ** 2
        image[inside] = colour

    if episodes.config.task == "navigate":
        disc(*w.goal[k], 0.3, GOAL)
    for i in range(w.N):
        disc(w.x[k, i], w.y[k, i], w.radius[k, i], TARGET if episodes.config.task == "follow" and i == 0 else PERSON)
    pose = w.robot_pose[k]
    disc(pose[0], pose[1], w.robot_radius, ROBOT)
    for s in np.linspace(0.0, w.robot_radius, 8):  # the heading
        disc(pose[0] + s * np.cos(pose[2]), pose[1] + s * np.sin(pose[2]), 0.05, FLOOR)
    tracks = episodes.tracks[k]
    if tracks is not None and len(tracks):
        world = transform_points(episodes.start[k], tracks.position)  # odom -> world (exact odometry)
        for x, y in world:
            disc(x, y, 0.3, TRACK, ring=True)
    return image
