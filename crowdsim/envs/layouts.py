"""Where an environment's episode starts: the room, the robot's start and goal, and each person's start and route.

Every layout places N persons in O(N), with no rejection loop: the places are cells of a fixed grid (or evenly spaced
slots on a circle) drawn without replacement, jittered by less than half the gap between them, so no two bodies
overlap at the start and no one starts on the robot. People walk their routes round and round (a crossing person
back and forth), so an episode's crowd stays as dense as it started.

* ``passers_by``: seed 001's A-to-B run across people's paths (Sec. 7, Fig. 11): a 12 m x 8 m room, the robot from
  (1.5, 4) to (10.5, 4), the people crossing its path back and forth between the long walls.
* ``circle_crossing``: CrowdNav's (Chen et al. 2019): people on a circle of radius 4 m, each walking to the opposite
  point and back; the robot from the circle's bottom to its top. Here inside a 14 m x 14 m room.
* ``following``: a 14 m x 14 m room; person 0 (the target, walking at a pace the robot can keep) starts 1.5 m ahead
  of the robot and walks a random tour of places in the room; the others cross the room back and forth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import Error

CELL = 0.8  # m, grid spacing of start places (two body diameters and a margin)
JITTER = 0.15  # m, +- uniform on each axis of a grid place (less than half the margin between bodies)
CLEAR = 1.5  # m, no one starts nearer than this to the robot's start or the target's
TOUR = 8  # places in the target's tour
TARGET_SPEED = 0.45  # m/s: the target walks slower than the robot's 0.6 m/s top speed, or it could not be followed


@dataclass
class Layout:
    """One episode's start, in the world frame."""

    size: tuple[float, float]  # m, the room [0, w] x [0, h]
    robot_start: np.ndarray  # (x, y, yaw)
    robot_goal: np.ndarray  # (x, y); for following, where the robot would go with no target
    start: np.ndarray  # [n, 2] persons' positions
    route: np.ndarray  # [n, R, 2] places each walks through, round and round (rows padded by repeating)
    route_length: np.ndarray  # [n] places in each route
    speed: np.ndarray | None  # [n] desired speeds fixed by the layout (NaN: drawn from the agent type), or None


def room_walls(size: tuple[float, float]) -> np.ndarray:
    """The room's four walls as segments [4, 2, 2]."""
    w, h = size
    corners = np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]])
    return np.stack([corners, np.roll(corners, -1, axis=0)], axis=1)


def _grid(lo: tuple[float, float], hi: tuple[float, float]) -> np.ndarray:
    """Cell centres [m, 2] of a CELL grid over the box lo..hi."""
    xs = np.arange(lo[0] + CELL / 2, hi[0] - CELL / 2 + 1e-9, CELL)
    ys = np.arange(lo[1] + CELL / 2, hi[1] - CELL / 2 + 1e-9, CELL)
    return np.stack(np.meshgrid(xs, ys, indexing="ij"), -1).reshape(-1, 2)


def _places(cells: np.ndarray, keep_clear: np.ndarray, n: int, rng: np.random.Generator, name: str) -> np.ndarray:
    """``n`` distinct jittered cells, none within CLEAR of a point of ``keep_clear`` [k, 2]."""
    free = cells[(np.linalg.norm(cells[:, None] - keep_clear[None], axis=2) >= CLEAR).all(axis=1)]
    if n > len(free):
        raise Error(f"people: layout {name!r} has room for at most {len(free)} persons, got {n}")
    chosen = free[rng.choice(len(free), n, replace=False)]
    return chosen + rng.uniform(-JITTER, JITTER, chosen.shape)


def _crossing(start: np.ndarray, y_range: tuple[float, float], rng: np.random.Generator) -> np.ndarray:
    """Routes [n, 2, 2] across the room along y at each person's x: first to the far end of their heading, then back."""
    up = rng.random(len(start)) < 0.5
    ends = np.where(up, y_range[1], y_range[0]), np.where(up, y_range[0], y_range[1])
    return np.stack([np.stack([start[:, 0], ends[0]], 1), np.stack([start[:, 0], ends[1]], 1)], axis=1)


def passers_by(n: int, rng: np.random.Generator) -> Layout:
    size = (12.0, 8.0)
    robot = np.array([1.5, 4.0, 0.0])
    goal = np.array([10.5, 4.0])
    start = _places(_grid((2.5, 0.4), (9.5, 7.6)), np.stack([robot[:2], goal]), n, rng, "passers_by")
    route = _crossing(start, (0.6, 7.4), rng)
    return Layout(size, robot, goal, start, route, np.full(n, 2), None)


def circle_crossing(n: int, rng: np.random.Generator, radius: float = 4.0) -> Layout:
    size = (14.0, 14.0)
    centre = np.array([7.0, 7.0])
    robot = np.array([7.0, 7.0 - radius, np.pi / 2])
    goal = np.array([7.0, 7.0 + radius])
    # slots evenly spaced on the circle outside an arc of CLEAR about the robot's start (angle -pi/2)
    gap = CLEAR / radius
    span = 2 * np.pi - 2 * gap
    spacing = span / max(n, 1)
    if n and spacing * radius < CELL:
        raise Error(f"people: layout 'circle_crossing' has room for at most {int(span * radius / CELL)} "
                         f"persons, got {n}")
    jitter = rng.uniform(-0.25, 0.25, n) * (spacing - CELL / radius)
    angle = -np.pi / 2 + gap + (np.arange(n) + 0.5) * spacing + jitter
    start = centre + radius * np.stack([np.cos(angle), np.sin(angle)], 1)
    route = np.stack([2 * centre - start, start], axis=1)  # to the opposite point, then back
    return Layout(size, robot, goal, start, route, np.full(n, 2), None)


def following(n: int, rng: np.random.Generator) -> Layout:
    if n < 1:
        raise Error(f"people: layout 'following' needs at least 1 person (the target), got {n}")
    size = (14.0, 14.0)
    robot = np.array([2.0, 2.0, 0.0])
    target = np.array([[3.5, 2.0]])
    tour = _grid((1.0, 1.0), (13.0, 13.0))
    tour = tour[rng.choice(len(tour), TOUR, replace=False)]
    others = _places(_grid((0.4, 0.4), (13.6, 13.6)), np.concatenate([[robot[:2]], target]), n - 1, rng, "following")
    start = np.concatenate([target, others])
    route = np.zeros((n, TOUR, 2))
    route[0] = tour
    route[1:] = np.tile(_crossing(others, (0.6, 13.4), rng), (1, TOUR // 2, 1))
    length = np.full(n, 2)
    length[0] = TOUR
    speed = np.full(n, np.nan)
    speed[0] = TARGET_SPEED
    return Layout(size, robot, tour[0].copy(), start, route, length, speed)


LAYOUTS = {"passers_by": passers_by, "circle_crossing": circle_crossing, "following": following}
