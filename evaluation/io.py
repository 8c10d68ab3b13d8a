"""Reading ground truth and tracks from the CSV layout ``crowdsim run`` writes, in chunks of whole frames, and
MOTChallenge-style export.

A CSV has a header row naming its columns; ``frame``, ``id``, ``x`` and ``y`` are required, ``t`` is read when
there, any other column is allowed. Rows are sorted by frame (any order within a frame), as a run writes them and as
MOTChallenge files are: that is what lets a run of any length be read a chunk at a time, in constant memory. A
ground-truth file may add ``visible`` (1 where the person was not physically occluded: its rows with 0 are ignored,
unless occlusion handling is off), ``in_range`` (0: beyond the run's evaluation range, ignored) and ``range``
(metres from the robot, for another range limit).
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path

import numpy as np

from .sequence import Sequence

REQUIRED = ("frame", "id", "x", "y")
CHUNK_ROWS = 1 << 14  # rows parsed at once (about 170 frames of the airport): a few MB, whatever the file's length


class EvaluationInputError(ValueError):
    pass


def _header(path: Path, f, required: tuple[str, ...]) -> list[str]:
    header = f.readline().strip()
    names = [c.strip() for c in header.split(",")]
    missing = [c for c in required if c not in names]
    if missing:
        raise EvaluationInputError(f"{path}: header {header!r} lacks column(s) {', '.join(missing)}; expected a "
                                   f"header row with at least {', '.join(required)}")
    return names


def table_chunks(path, required: tuple[str, ...] = REQUIRED, chunk_rows: int = CHUNK_ROWS):
    """The columns of a CSV with a header row, as float arrays by name, ``chunk_rows`` rows at a time (blank lines
    skipped). The header is checked before the first chunk; a file without rows gives one empty chunk."""
    path = Path(path)
    try:
        with open(path) as f:
            names = _header(path, f, required)
            first = True
            while True:
                raw = list(itertools.islice(f, chunk_rows))
                if not raw and not first:
                    return
                first = False
                lines = [line for line in raw if line.strip()]
                try:
                    data = np.loadtxt(lines, delimiter=",", ndmin=2) if lines else np.zeros((0, len(names)))
                except ValueError as e:
                    raise EvaluationInputError(f"{path}: {e}; expected {len(names)} numbers per row") from None
                if data.shape[1] != len(names):
                    raise EvaluationInputError(f"{path}: rows have {data.shape[1]} values; expected {len(names)} "
                                               f"numbers per row, one per column the header names")
                yield {name: data[:, k] for k, name in enumerate(names)}
    except OSError as e:
        raise EvaluationInputError(f"{path}: cannot be read ({e.strerror})") from None


def read_table(path, required: tuple[str, ...] = REQUIRED) -> dict[str, np.ndarray]:
    """The whole CSV's columns as float arrays by name (for the small files of a run, robot.csv say)."""
    chunks = list(table_chunks(path, required))
    return {name: np.concatenate([c[name] for c in chunks]) for name in chunks[0]}


def _integers(table: dict, column: str, path) -> np.ndarray:
    values = table[column]
    if not np.all(np.isfinite(values)) or np.any(values != np.round(values)):
        raise EvaluationInputError(f"{path}: column {column} must hold whole numbers")
    return values.astype(np.int64)


def _ignore(table: dict, path, occlusion: bool, visible_column: str, max_range: float | None) -> np.ndarray:
    """Rows the evaluation ignores: ``visible_column`` 0 (when the file has that column and ``occlusion``),
    ``in_range`` 0, and with ``max_range`` a ``range`` beyond it."""
    ignore = np.zeros(len(table["frame"]), bool)
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
    return ignore


def _sequence(rows: dict, path) -> Sequence:
    """Rows of whole frames as a Sequence sorted by frame and id; ids must be unique within a frame."""
    seq = Sequence.from_rows(rows["frame"], _integers(rows, "id", path), np.column_stack([rows["x"], rows["y"]]),
                             rows.get("t"), rows["ignore"])
    dup = (np.diff(seq.frame) == 0) & (np.diff(seq.id) == 0) if len(seq) > 1 else np.zeros(0, bool)
    if dup.any():
        k = int(np.flatnonzero(dup)[0])
        raise EvaluationInputError(f"{path}: id {seq.id[k]} appears twice in frame {seq.frame[k]}; expected ids "
                                   f"unique within a frame")
    return seq


def sequence_chunks(path, occlusion: bool = True, visible_column: str = "visible", max_range: float | None = None,
                    chunk_rows: int = CHUNK_ROWS):
    """A ground-truth or track file as Sequences of whole frames, in frame order: the rows of the frame a chunk
    ends in are held back and joined to the next chunk's. Ignored rows as ``_ignore`` says."""
    held = None
    for table in table_chunks(path, chunk_rows=chunk_rows):
        rows = {"frame": _integers(table, "frame", path), "id": table["id"], "x": table["x"], "y": table["y"],
                "ignore": _ignore(table, path, occlusion, visible_column, max_range)}
        if "t" in table:
            rows["t"] = table["t"]
        if held is not None:
            rows = {name: np.concatenate([held[name], rows[name]]) for name in rows}
        frame = rows["frame"]
        back = np.flatnonzero(np.diff(frame) < 0)
        if back.size:
            k = int(back[0])
            raise EvaluationInputError(f"{path}: frame {frame[k + 1]} comes after frame {frame[k]}; expected rows "
                                       f"sorted by frame (as a run writes them)")
        cut = int(np.searchsorted(frame, frame[-1])) if len(frame) else 0
        held = {name: column[cut:] for name, column in rows.items()}
        if cut:
            yield _sequence({name: column[:cut] for name, column in rows.items()}, path)
    if held is not None and len(held["frame"]):
        yield _sequence(held, path)


def load_sequence(path, occlusion: bool = True, visible_column: str = "visible",
                  max_range: float | None = None) -> Sequence:
    """A whole ground-truth or track file as one Sequence (see ``sequence_chunks``)."""
    return Sequence.join(list(sequence_chunks(path, occlusion, visible_column, max_range)))


def write_motchallenge(path, chunks, groundtruth: bool, first_frame: int = 0) -> None:
    """MOTChallenge-style text for points in world coordinates, as its 3D convention (MOT15's 3D files) has it:
    ``frame, id, -1, -1, -1, -1, conf, x, y, z`` with ``first_frame`` as frame 1, z = 0. For ground truth, ``conf``
    is its "consider" flag: 0 for ignored rows (occluded or out of range), else 1; for tracks it is 1. ``chunks``:
    Sequences in frame order, written as they come to a temporary file beside ``path`` and moved into place, so a
    failure leaves nothing half-written."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with open(tmp, "w") as f:
            for seq in chunks:
                conf = (~seq.ignore).astype(float) if groundtruth else np.ones(len(seq))
                minus = -np.ones(len(seq))
                data = np.column_stack([seq.frame - first_frame + 1, seq.id, minus, minus, minus, minus, conf,
                                        seq.position, np.zeros(len(seq))])
                np.savetxt(f, data, fmt=["%d", "%d", "%d", "%d", "%d", "%d", "%g", "%.4f", "%.4f", "%g"],
                           delimiter=",")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
