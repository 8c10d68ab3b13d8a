"""The static-map filter (seed 000 Sec. V-C, SPENCER's "filter detections by static map"): a detection on the map's
walls and obstacles is no person, so it is dropped before fusion, whichever detector made it.

A real robot has the occupancy grid it localises in; here it is rasterised once from the scenario's walls and
obstacle polygons. Seed 000 rasterises a circle of 15 cm round each detection onto the grid and rejects the detection
when less than 90% of the circle's cells are free; the grid here holds that test's answer for every cell (the share
of occupied cells within ``inflation`` of its centre), so filtering a batch is one transform and one array lookup.
Detections are in the tracking frame (odom); the robot's localisation in the map (world_T_odom) places them on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scenarios.geometry import inside_polygon, wall_segments

from .compiled import kernel
from .frames import transform_points
from .params import param
from .types import DetectedPersons


def disc_counts(grid: np.ndarray, half_widths: np.ndarray) -> np.ndarray:
    """For every cell of ``grid`` [rows, cols], how many cells are set within the disc round it whose row dy = -r..r
    spans ``half_widths[dy + r]`` cells either side (off the grid: none), counted exactly: one prefix sum along each
    row of the grid, then per row of the disc the difference of two of them."""
    r = len(half_widths) // 2
    rows, cols = grid.shape
    padded = np.zeros((rows + 2 * r, cols + 2 * r + 1), np.int64)  # r rows above and below, r + 1 columns before
    padded[r:r + rows, r + 1:r + 1 + cols] = grid
    prefix = np.cumsum(padded, axis=1)
    out = np.zeros((rows, cols), np.int64)
    for k, w in enumerate(half_widths):  # cells x - w .. x + w of row y + k - r
        out += prefix[k:k + rows, r + 1 + w:r + 1 + w + cols] - prefix[k:k + rows, r - w:r - w + cols]
    return out


def occupancy_grid(walls: list, obstacles: list, resolution: float, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """The cells [rows (y), columns (x)] that ``walls`` (polylines) run through or ``obstacles`` (closed polygons,
    solid) cover, over the map's bounding box grown by at least ``margin``, and the grid's lower corner (world, m)."""
    segments = wall_segments({"map": {"walls": walls, "obstacles": obstacles}})
    ends = segments.reshape(-1, 2) if len(segments) else np.zeros((1, 2))
    # the lowest walls run through the middle of cells, not along their edges, where rounding would pick the side
    origin = ends.min(axis=0) - (np.ceil(margin / resolution) + 0.5) * resolution
    size = np.ceil((ends.max(axis=0) + margin - origin) / resolution).astype(int)  # columns, rows
    occupied = np.zeros(size[::-1], bool)
    # points a quarter cell apart along every segment mark the cells it crosses
    length = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)
    count = np.ceil(length / (resolution / 4)).astype(int) + 1
    seg = np.repeat(np.arange(len(segments)), count)
    step = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    t = step / np.repeat(np.maximum(count - 1, 1), count)
    points = segments[seg, 0] + t[:, None] * (segments[seg, 1] - segments[seg, 0])
    col, row = np.minimum(((points - origin) / resolution).astype(int), size - 1).T
    occupied[row, col] = True
    for poly in obstacles:  # an obstacle's inside too (a pillar is solid); once, when the grid is made
        poly = np.asarray(poly, float)
        lo = ((poly.min(axis=0) - origin) // resolution).astype(int)
        hi = np.minimum(np.ceil((poly.max(axis=0) - origin) / resolution).astype(int), size)
        cols, rows = np.meshgrid(np.arange(lo[0], hi[0]), np.arange(lo[1], hi[1]))
        centres = origin + (np.stack([cols.ravel(), rows.ravel()], 1) + 0.5) * resolution
        occupied[rows, cols] |= inside_polygon(centres, poly).reshape(rows.shape)
    return occupied, origin


@dataclass(eq=False)
class MapFilter:
    """Drops detections whose circle of radius ``inflation`` holds more than ``max_occupied`` of occupied cells
    (seed 000 Sec. V-C: a 15 cm circle, rejected when under 90% of it is free; ``max_occupied`` 0: any occupied
    cell within ``inflation`` rejects). Detections off the grid (beyond the map) are kept: nothing is known there.
    The map is a scenario's ``map``: ``walls`` (polylines) and its obstacles, ``polygons`` (closed), in the world
    frame; it is no parameter of the filter but the robot's map, given with it."""

    walls: list
    polygons: list
    resolution: float = param(0.05, "m, cell size of the occupancy grid made from the map (a common ROS map's; an "
                                    "assumption)", min=0.0, exclusive_min=True)
    inflation: float = param(0.15, "m, radius of the circle checked round each detection (seed 000: 15 cm)", min=0.0)
    max_occupied: float = param(0.1, "share of the circle's cells that may be occupied (seed 000: rejected when under "
                                     "90% free; 0: any occupied cell rejects)", min=0.0, max=1.0)
    obstacles: bool = param(True, "the map's obstacles block detections as its walls do (false: walls only, for a map "
                                  "that leaves out furniture, which moves)")

    def __post_init__(self):
        polygons = self.polygons if self.obstacles else []
        self.occupied, self.origin = occupancy_grid(self.walls, polygons, self.resolution,
                                                    self.inflation + self.resolution)
        r = int(np.floor(self.inflation / self.resolution + 1e-9))
        offsets = np.arange(-r, r + 1) * self.resolution
        disc = (np.hypot(*np.meshgrid(offsets, offsets)) <= self.inflation + 1e-9).astype(float)
        near = disc_counts(self.occupied, disc.sum(axis=1).astype(int) // 2)
        self.blocked = near > self.max_occupied * disc.sum() + 1e-9

    def keep(self, xy_world: np.ndarray) -> np.ndarray:
        """Which of the points [n, 2] (world) may be persons: off the blocked cells."""
        xy = np.ascontiguousarray(xy_world, np.float64).reshape(-1, 2)
        out = np.empty(len(xy), np.bool_)
        _off_blocked(xy, float(self.origin[0]), float(self.origin[1]), float(self.resolution), self.blocked, out)
        return out

    def filter(self, detections: DetectedPersons, world_T_odom: np.ndarray) -> DetectedPersons:
        """The detections (in odom) that are not on the map, placed on it through the localisation
        ``world_T_odom`` (x, y, yaw of odom in the world)."""
        keep = self.keep(transform_points(world_T_odom, detections.position[:, :2]))
        if keep.all():
            return detections
        d = detections
        originals = None if d.originals is None else {k: v[keep] for k, v in d.originals.items()}
        return DetectedPersons(d.stamp, d.frame, d.modality, d.detection_id[keep], d.position[keep],
                               d.covariance[keep], d.confidence[keep], originals)


@kernel
def _off_blocked(xy, ox, oy, resolution, blocked, out):
    """``MapFilter.keep``: each point's cell (floor of its offset from the grid's origin over the resolution), kept
    unless it is a blocked cell of the grid; points off the grid are kept."""
    rows, cols = blocked.shape
    for i in range(len(xy)):
        col, row = math.floor((xy[i, 0] - ox) / resolution), math.floor((xy[i, 1] - oy) / resolution)
        out[i] = not (0 <= col < cols and 0 <= row < rows and blocked[int(row), int(col)])
