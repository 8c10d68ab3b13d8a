"""The evaluation's input: a sequence of 2D points over frames, for the ground truth or for one tracker's output.

Rows are sorted by frame (then by id); ``ignore`` marks ground-truth rows that count neither as a miss nor, when a
hypothesis matches them, as a false positive: the person was physically occluded or beyond the range limit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Sequence:
    frame: np.ndarray  # [n] int64, non-decreasing
    id: np.ndarray  # [n] int64, unique within a frame
    position: np.ndarray  # [n, 2] float64, metres, one frame of reference for the whole sequence
    stamp: np.ndarray | None = None  # [n] float64, seconds (optional)
    ignore: np.ndarray = field(default=None)  # [n] bool
    group: np.ndarray | None = None  # [n] int64, the ground truth's group of each row (optional: the group metrics)

    def __post_init__(self):
        n = len(self.frame)
        if self.ignore is None:
            object.__setattr__(self, "ignore", np.zeros(n, bool))
        for name, value in (("id", self.id), ("position", self.position), ("ignore", self.ignore),
                            ("group", self.group)):
            if value is not None and len(value) != n:
                raise ValueError(f"Sequence.{name} has {len(value)} rows, frame has {n}")
        if n and (np.diff(self.frame) < 0).any():
            raise ValueError("Sequence rows must be sorted by frame")

    @classmethod
    def from_rows(cls, frame, ids, position, stamp=None, ignore=None, group=None) -> "Sequence":
        """Rows in any order, sorted here by frame and id."""
        frame = np.asarray(frame, np.int64).reshape(-1)
        ids = np.asarray(ids, np.int64).reshape(-1)
        order = np.lexsort((ids, frame))
        pick = (lambda a, dtype: None if a is None else np.asarray(a, dtype)[order])  # noqa: E731
        return cls(frame[order], ids[order], np.asarray(position, np.float64).reshape(-1, 2)[order],
                   pick(stamp, np.float64), pick(ignore, bool), pick(group, np.int64))

    @classmethod
    def join(cls, chunks: list["Sequence"]) -> "Sequence":
        """Chunks of consecutive frames (each later one's frames after the earlier's) as one sequence."""
        if not chunks:
            return cls(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 2)))
        def optional(name):
            parts = [getattr(c, name) for c in chunks]
            return None if any(p is None for p in parts) else np.concatenate(parts)

        return cls(*(np.concatenate([getattr(c, name) for c in chunks]) for name in ("frame", "id", "position")),
                   optional("stamp"), np.concatenate([c.ignore for c in chunks]), optional("group"))

    def __len__(self) -> int:
        return len(self.frame)

    def select(self, rows: np.ndarray) -> "Sequence":
        """The sequence of the given rows (a boolean mask or sorted indices)."""
        return Sequence(self.frame[rows], self.id[rows], self.position[rows],
                        None if self.stamp is None else self.stamp[rows], self.ignore[rows],
                        None if self.group is None else self.group[rows])

    def bounds(self, frames: np.ndarray) -> np.ndarray:
        """Row ranges [len(frames) + 1]: frame ``frames[k]``'s rows are ``bounds[k]:bounds[k + 1]``, for sorted
        ``frames`` that include every frame of the sequence."""
        return np.searchsorted(self.frame, np.append(frames, np.iinfo(np.int64).max), side="left")


def frames_of(*sequences: Sequence) -> np.ndarray:
    """Every frame that any of the sequences has a row in, sorted."""
    return np.unique(np.concatenate([s.frame for s in sequences])) if sequences else np.zeros(0, np.int64)
