"""Reading ground truth and tracks from the CSV layout ``crowdsim run`` writes, and MOTChallenge-style export.

A CSV has a header row naming its columns; ``frame``, ``id``, ``x`` and ``y`` are required, ``t`` is read when
there, any other column is allowed. A ground-truth file may add ``visible`` (1 where the person was not physically
occluded: its rows with 0 are ignored, unless occlusion handling is off), ``in_range`` (0: beyond the run's
evaluation range, ignored) and ``range`` (metres from the robot, for another range limit).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .sequence import Sequence

REQUIRED = ("frame", "id", "x", "y")


class EvaluationInputError(ValueError):
    pass


def read_table(path, required: tuple[str, ...] = REQUIRED) -> dict[str, np.ndarray]:
    """The columns of a CSV with a header row, as float arrays by name."""
    path = Path(path)
    try:
        with open(path) as f:
            header = f.readline().strip()
            names = [c.strip() for c in header.split(",")]
            rows = [line for line in f if line.strip()]
    except OSError as e:
        raise EvaluationInputError(f"{path}: cannot be read ({e.strerror})") from None
    missing = [c for c in required if c not in names]
    if missing:
        raise EvaluationInputError(f"{path}: header {header!r} lacks column(s) {', '.join(missing)}; expected a "
                                   f"header row with at least {', '.join(required)}")
    try:
        data = np.loadtxt(rows, delimiter=",", ndmin=2) if rows else np.zeros((0, len(names)))
    except ValueError as e:
        raise EvaluationInputError(f"{path}: {e}; expected {len(names)} numbers per row") from None
    if data.shape[1] != len(names):
        raise EvaluationInputError(f"{path}: rows have {data.shape[1]} values; expected {len(names)} numbers per "
                                   f"row, one per column the header names")
    return {name: data[:, k] for k, name in enumerate(names)}


def _integers(table: dict, column: str, path) -> np.ndarray:
    values = table[column]
    if not np.all(np.isfinite(values)) or np.any(values != np.round(values)):
        raise EvaluationInputError(f"{path}: column {column} must hold whole numbers")
    return values.astype(np.int64)


def load_sequence(path, occlusion: bool = True, visible_column: str = "visible",
                  max_range: float | None = None) -> Sequence:
    """A ground-truth or track file as a Sequence. Ignored rows: ``visible_column`` 0 (when the file has that
    column and ``occlusion``), ``in_range`` 0, and with ``max_range`` a ``range`` beyond it."""
    table = read_table(path)
    n = len(table["frame"])
    ignore = np.zeros(n, bool)
    if occlusion and visible_column in table:
        ignore |= table[visible_column] == 0
    elif occlusion and visible_column != "visible":
        raise EvaluationInputError(f"{path}: no column {visible_column!r} to take the visibility from")
    if "in_range" in table:
        ignore |= table["in_range"] == 0
    if max_range is not None:
        if "range" not in table:
            raise EvaluationInputError(f"{path}: --max-range needs a column 'range' (metres from the robot)")
        ignore |= table["range"] > max_range
    seq = Sequence.from_rows(_integers(table, "frame", path), _integers(table, "id", path),
                             np.column_stack([table["x"], table["y"]]), table.get("t"), ignore)
    dup = (np.diff(seq.frame) == 0) & (np.diff(seq.id) == 0) if n > 1 else np.zeros(0, bool)
    if dup.any():
        k = int(np.flatnonzero(dup)[0])
        raise EvaluationInputError(f"{path}: id {seq.id[k]} appears twice in frame {seq.frame[k]}; expected ids "
                                   f"unique within a frame")
    return seq


def write_motchallenge(path, seq: Sequence, groundtruth: bool, first_frame: int = 0) -> None:
    """MOTChallenge-style text for points in world coordinates, as its 3D convention (MOT15's 3D files) has it:
    ``frame, id, -1, -1, -1, -1, conf, x, y, z`` with ``first_frame`` as frame 1, z = 0. For ground truth, ``conf``
    is its "consider" flag: 0 for ignored rows (occluded or out of range), else 1; for tracks it is 1. Written to
    a temporary file beside ``path`` and moved into place, so a failure leaves nothing half-written."""
    path = Path(path)
    conf = (~seq.ignore).astype(float) if groundtruth else np.ones(len(seq))
    minus = -np.ones(len(seq))
    data = np.column_stack([seq.frame - first_frame + 1, seq.id, minus, minus, minus, minus, conf, seq.position,
                            np.zeros(len(seq))])
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        np.savetxt(tmp, data, fmt=["%d", "%d", "%d", "%d", "%d", "%d", "%g", "%.4f", "%.4f", "%g"], delimiter=",")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
