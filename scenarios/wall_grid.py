"""A uniform grid over a map's wall segments, built once, and the compiled queries that read it: which walls lie near
a point, which move crosses a wall.

Why: every step each person of a crowd needs the walls within a couple of metres of them, and a building has
thousands of segments. A query reads only the segments of the cells its box touches, so thousands of segments cost
about what the airport's forty do, and the loops are compiled because a step asks a few per person.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.compiled import kernel

CELL = 2.0  # m: the crowd's wall reach (its default wall_interaction_range), so a query touches about 4 cells


@dataclass(frozen=True, eq=False)
class WallGrid:
    """Segments [m, 2, 2] binned into square cells ``cell`` wide from ``origin``, ``columns`` x ``rows`` of them:
    the segments whose bounding box touches cell c = row * columns + column are ``members[start[c]:start[c + 1]]``
    (ascending)."""

    walls: np.ndarray
    origin: np.ndarray
    cell: float
    columns: int
    rows: int
    start: np.ndarray
    members: np.ndarray

    @classmethod
    def of(cls, walls: np.ndarray, cell: float = CELL) -> "WallGrid":
        walls = np.ascontiguousarray(walls, float).reshape(-1, 2, 2)
        if len(walls) == 0:
            return cls(walls, np.zeros(2), cell, 1, 1, np.zeros(2, np.int64), np.zeros(0, np.int64))
        lo, hi = walls.min(axis=1), walls.max(axis=1)
        origin = lo.min(axis=0)
        first = np.floor((lo - origin) / cell).astype(np.int64)
        last = np.floor((hi - origin) / cell).astype(np.int64)
        columns, rows = (int(k) + 1 for k in last.max(axis=0))
        span = last - first + 1
        count = span[:, 0] * span[:, 1]  # cells each segment's box covers
        seg = np.repeat(np.arange(len(walls)), count)
        k = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        at = (first[seg, 1] + k // span[seg, 0]) * columns + first[seg, 0] + k % span[seg, 0]
        order = np.lexsort((seg, at))
        start = np.searchsorted(at[order], np.arange(columns * rows + 1))
        return cls(walls, origin, float(cell), columns, rows, start.astype(np.int64), seg[order])

    def crossed(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """For moves ``starts`` -> ``ends`` [n, 2]: True where the move crosses (or touches) a wall."""
        return crossed(np.ascontiguousarray(starts, float), np.ascontiguousarray(ends, float), *self.arrays())

    def arrays(self) -> tuple:
        """The grid as the kernels take it: walls, origin, cell, columns, rows, start, members."""
        return self.walls, self.origin, self.cell, self.columns, self.rows, self.start, self.members


@kernel
def near_walls(x, y, reach, walls, origin, cell, columns, rows, start, members, seen, query, out):
    """The walls whose bounding boxes, grown by ``reach``, hold the point (x, y), each once, written to ``out``;
    returns their count. ``seen`` [m] is the caller's scratch, marked with ``query``: a number no earlier query
    into the same ``seen`` used."""
    c0 = max(int(math.floor((x - reach - origin[0]) / cell)), 0)
    c1 = min(int(math.floor((x + reach - origin[0]) / cell)), columns - 1)
    r0 = max(int(math.floor((y - reach - origin[1]) / cell)), 0)
    r1 = min(int(math.floor((y + reach - origin[1]) / cell)), rows - 1)
    count = 0
    for r in range(r0, r1 + 1):
        for c in range(c0, c1 + 1):
            at = r * columns + c
            for k in range(start[at], start[at + 1]):
                s = members[k]
                if seen[s] == query:
                    continue
                seen[s] = query
                ax, ay, bx, by = walls[s, 0, 0], walls[s, 0, 1], walls[s, 1, 0], walls[s, 1, 1]
                if min(ax, bx) - reach <= x <= max(ax, bx) + reach and min(ay, by) - reach <= y <= max(ay, by) + reach:
                    out[count] = s
                    count += 1
    return count


@kernel
def away_from_wall(x, y, walls, s):
    """The vector from wall s's closest point to (x, y), and its length."""
    ax, ay = walls[s, 0, 0], walls[s, 0, 1]
    abx, aby = walls[s, 1, 0] - ax, walls[s, 1, 1] - ay
    apx, apy = x - ax, y - ay
    t = min(max((apx * abx + apy * aby) / max(abx * abx + aby * aby, 1e-12), 0.0), 1.0)
    wx, wy = apx - t * abx, apy - t * aby
    return wx, wy, math.sqrt(wx * wx + wy * wy)


@kernel
def crossed(starts, ends, walls, origin, cell, columns, rows, start, members):
    """``WallGrid.crossed``: the walls near each move's midpoint, within half its length, tested for an
    intersection (parameters t along the move and u along the wall both in [0, 1])."""
    out = np.zeros(len(starts), np.bool_)
    seen, near = np.full(len(walls), -1, np.int64), np.empty(len(walls), np.int64)
    for i in range(len(starts)):
        dx, dy = ends[i, 0] - starts[i, 0], ends[i, 1] - starts[i, 1]
        count = near_walls((starts[i, 0] + ends[i, 0]) / 2, (starts[i, 1] + ends[i, 1]) / 2,
                           math.sqrt(dx * dx + dy * dy) / 2 + 1e-9, walls, origin, cell, columns, rows, start, members,
                           seen, i, near)
        for k in range(count):
            s = near[k]
            ax, ay = walls[s, 0, 0], walls[s, 0, 1]
            ex, ey = walls[s, 1, 0] - ax, walls[s, 1, 1] - ay
            denom = dx * ey - dy * ex
            if abs(denom) <= 1e-12:
                continue
            ox, oy = ax - starts[i, 0], ay - starts[i, 1]
            t, u = (ox * ey - oy * ex) / denom, (ox * dy - oy * dx) / denom
            if 0.0 <= t <= 1.0 and 0.0 <= u <= 1.0:
                out[i] = True
                break
    return out
