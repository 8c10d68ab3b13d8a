"""Reading ground truth and tracks from the CSV layout ``crowdsim run`` writes, in chunks of whole frames, and
MOTChallenge-style export.

A CSV is UTF-8 text (a leading byte order mark, as Excel writes one, is skipped) with a header row naming its
columns; ``frame``, ``id``, ``x`` and ``y`` are required, ``t`` is read when there, any other column is allowed.
Rows are sorted by frame (any order within a frame), as a run writes them and as MOTChallenge files are: that is
what lets a run of any length be read a chunk at a time, in constant memory. A ground-truth file may add
``visible`` (1 where the person was not physically occluded: its rows with 0 are ignored, unless occlusion handling
is off; ``crowdsim evaluate`` requires it while occlusion handling is on, see ``Ignored``), ``in_range`` (0: beyond
the run's evaluation range, ignored) and ``range`` (metres from the robot, for another range limit).

Strict on purpose: every column a reader uses must hold finite numbers, and ids, frame numbers and group numbers
(``WHOLE``) whole numbers a float64 holds exactly (|n| < 2^53), so that no NaN, inf or wrapped id is scored as if
it were data. Anything else is one EvaluationInputError naming the file, the line, the column and what was expected.
"""

from __future__ import annotations

import itertools
import os
from contextlib import contextmanager
from functools import cached_property
from pathlib import Path

import numpy as np

from scenarios.errors import Error

from . import decimals
from .columns import FLAGS, GROUNDTRUTH, SHARES, TRACKS, WHOLE
from .sequence import Sequence

REQUIRED = TRACKS.pick("frame", "id", "x", "y")  # of any ground truth or tracks file
CHUNK_ROWS = 1 << 14  # rows parsed at once (about 170 frames of the airport): a few MB, whatever the file's length
# ``WHOLE`` columns (ids and counts, whatever the file) hold whole numbers below 2^53 in size. Every value is parsed
# as a float64, which from 2^53 on rounds them (2^53 + 1 reads as 2^53, so two ids would merge silently); 1e20 would
# wrap to INT64_MIN. ``FLAGS`` hold 0 or 1, ``SHARES`` numbers in [0, 1] (evaluation/columns.py).
EXACT = 2.0 ** 53
HEADER_MAX = 1 << 16  # characters of a header line: a longer one is no CSV of ours (a binary file, /dev/zero)


class EvaluationInputError(Error):
    """Input the evaluation cannot score (a file, a column, a value): ``crowdsim.Error``, so the command line prints
    it as its one error line."""


def _header(path: Path, f, required: tuple[str, ...]) -> list[str]:
    header = f.readline(HEADER_MAX)
    if len(header) == HEADER_MAX and not header.endswith("\n"):
        raise EvaluationInputError(f"{path}: the first line is longer than {HEADER_MAX:,} characters; expected a "
                                   f"header row of column names")
    header = header.strip()
    names = [c.strip() for c in header.split(",")]
    missing = [c for c in required if c not in names]
    if missing:
        raise EvaluationInputError(f"{path}: header {header!r} lacks column(s) {', '.join(missing)}; expected a "
                                   f"header row with at least {', '.join(required)}")
    twice = sorted({c for c in names if names.count(c) > 1})
    if twice:
        raise EvaluationInputError(f"{path}: header {header!r} names column(s) {', '.join(twice)} twice; expected "
                                   f"each column once")
    return names


def _rows(lines: list[str]) -> list[str]:
    """The lines that are rows: not blank, not # comment lines. loadtxt is given these only, so that its k-th row
    is the k-th of them (it would skip a comment line, not a blank one)."""
    return [text for text in lines if text.strip() and text[0] != "#"]


def _number(field: str) -> bool:
    """Whether loadtxt reads ``field`` as a number (Python's float also takes 1_000; loadtxt does not)."""
    try:
        float(field)
    except ValueError:
        return False
    return "_" not in field


class _Chunk:
    """The raw lines of a chunk, to say where a bad value is: ``rows`` those given to loadtxt, ``start`` the file
    line of the first raw line."""

    def __init__(self, path: Path, names: list[str], raw: list[str], start: int):
        self.path, self.names, self.raw, self.start = path, names, raw, start

    @cached_property
    def rows(self) -> list[str]:
        return _rows(self.raw)

    def data(self) -> np.ndarray:
        """The chunk's numbers [rows, columns]: plain decimals parsed from their bytes (``decimals``), anything
        else by ``np.loadtxt``, whose failures name the line."""
        fast = decimals.parse("".join(self.raw), len(self.names)) if self.raw else None
        if fast is not None:
            return fast
        try:
            data = np.loadtxt(self.rows, delimiter=",", ndmin=2) if self.rows else np.zeros((0, len(self.names)))
        except ValueError as e:
            raise self.malformed(str(e)) from None
        if data.shape[1] != len(self.names):
            raise self.malformed(f"rows have {data.shape[1]} values")
        return data

    def line(self, row: int) -> int:
        """The file line of data row ``row``."""
        return self.start + [k for k, text in enumerate(self.raw) if _rows([text])][row]

    def malformed(self, error: str) -> EvaluationInputError:
        """The first row that is not one number per column (loadtxt failed, with ``error``, or got another width)."""
        for k, text in enumerate(self.raw):
            if not _rows([text]):
                continue
            fields = text.partition("#")[0].split(",")
            where = f"{self.path}: line {self.start + k}"
            if len(fields) != len(self.names):
                return EvaluationInputError(f"{where} has {len(fields)} values; expected {len(self.names)} numbers "
                                            f"per row, one per column the header names")
            for name, field in zip(self.names, fields):
                if not _number(field):
                    return EvaluationInputError(f"{where}, column {name}: {field.strip()!r} is not a number; "
                                                f"expected {len(self.names)} numbers per row")
        return EvaluationInputError(f"{self.path}: {error}; expected {len(self.names)} numbers per row")

    def check(self, data: np.ndarray, columns: list[int]) -> None:
        """The ``columns`` (indices) of ``data`` hold finite numbers, whole and exact ones where ``WHOLE``."""
        for k in columns:
            name, values = self.names[k], data[:, k]
            if name in WHOLE:
                ok, kind = (np.abs(values) < EXACT) & (values == np.round(values)), "whole numbers (below 2^53 in size)"
            elif name in FLAGS:
                ok, kind = (values == 0) | (values == 1), "0 or 1"
            elif name in SHARES:
                ok, kind = (values >= 0) & (values <= 1), "numbers from 0 to 1"
            else:
                ok, kind = np.isfinite(values), "finite numbers"
            if ok.all():
                continue
            row = int(np.flatnonzero(~ok)[0])
            field = self.rows[row].partition("#")[0].split(",")[k].strip()
            raise EvaluationInputError(f"{self.path}: line {self.line(row)}, column {self.names[k]} must hold "
                                       f"{kind}, got {field!r}")


def _not_utf8(path: Path) -> EvaluationInputError:
    """The first line of ``path`` that is not UTF-8, named (the text reader's error says only a byte offset)."""
    with open(path, "rb") as f:
        for n, line in enumerate(f, 1):
            try:
                line.decode("utf-8")
            except UnicodeDecodeError as e:
                return EvaluationInputError(f"{path}: line {n} is not UTF-8 text (byte 0x{line[e.start]:02x}, "
                                            f"{e.start + 1} bytes into the line); expected a file saved as UTF-8")
    return EvaluationInputError(f"{path}: not UTF-8 text; expected a file saved as UTF-8")


@contextmanager
def _reading(path: Path):
    """Reading ``path`` as text: a file that cannot be read, or is not UTF-8, is one EvaluationInputError."""
    try:
        yield
    except UnicodeDecodeError:
        raise _not_utf8(path) from None
    except OSError as e:
        raise EvaluationInputError(f"{path}: cannot be read ({e.strerror})") from None


def read_text(path) -> str:
    """A small text file (navigation.json, say) read as the CSVs are: UTF-8, a leading byte order mark skipped."""
    path = Path(path)
    with _reading(path):
        return path.read_text(encoding="utf-8-sig")


def table_chunks(path, required: tuple[str, ...] = REQUIRED, read: tuple[str, ...] = (),
                 chunk_rows: int = CHUNK_ROWS):
    """The columns of a CSV with a header row, as float arrays by name, ``chunk_rows`` rows at a time (blank lines
    and # comment lines skipped). The header is checked before the first chunk; a file without rows gives one empty
    chunk. The ``required`` columns and those of ``read`` the file has (what the caller uses) are checked in every
    chunk as the module docstring says; other columns need only be numbers."""
    path = Path(path)
    if path.exists() and not path.is_file():  # a folder, a device (/dev/zero reads forever), a pipe
        raise EvaluationInputError(f"{path}: not a regular file; expected a CSV file")
    with _reading(path), open(path, encoding="utf-8-sig") as f:
        names = _header(path, f, required)
        checked = [k for k, name in enumerate(names) if name in required or name in read]
        start, first = 2, True
        while True:
            raw = list(itertools.islice(f, chunk_rows))
            if not raw and not first:
                return
            first = False
            chunk = _Chunk(path, names, raw, start)
            start += len(raw)
            data = chunk.data()
            chunk.check(data, checked)
            yield {name: data[:, k] for k, name in enumerate(names)}


def read_table(path, required: tuple[str, ...] = REQUIRED) -> dict[str, np.ndarray]:
    """The whole CSV's columns as float arrays by name (for the small files of a run, robot.csv say), the
    ``required`` ones checked."""
    chunks = list(table_chunks(path, required))
    return {name: np.concatenate([c[name] for c in chunks]) for name in chunks[0]}


class Ignored:
    """Which ground-truth rows the evaluation ignores (called on a chunk's columns): ``visible_column`` 0 with
    ``occlusion``, ``in_range`` 0, and with ``max_range`` a ``range`` beyond it; ``columns``: those it reads.
    ``visible_column`` None takes ``visible`` where the file has one (a run's own files, library callers); a name
    (crowdsim evaluate's ``--visible-column``, ``visible`` by default) must be there, so that a ground truth
    without it, or a tracks file given as one, is refused rather than scored as all visible."""

    def __init__(self, occlusion: bool = True, visible_column: str | None = None, max_range: float | None = None):
        self.visible = (visible_column or "visible") if occlusion else None
        self.required = occlusion and visible_column is not None
        self.max_range = max_range
        self.columns = tuple(c for c in (self.visible, "in_range", None if max_range is None else "range") if c)

    def __call__(self, table: dict, path) -> np.ndarray:
        ignore = np.zeros(len(table["frame"]), bool)
        if self.max_range is not None:
            if "range" not in table:
                raise EvaluationInputError(f"{path}: --max-range needs a column 'range' (metres from the robot)")
            ignore |= table["range"] > self.max_range
        if self.visible in table:
            ignore |= table[self.visible] == 0
        elif self.required:
            raise EvaluationInputError(
                f"{path}: no column {self.visible!r} to tell occluded persons (0) from visible ones; expected a "
                f"ground truth as `crowdsim run` writes it (a tracks file has none), or --no-occlusion to score "
                f"every row as visible, or --visible-column NAME for another column")
        if "in_range" in table:
            ignore |= table["in_range"] == 0
        return ignore


def _sequence(rows: dict, path) -> Sequence:
    """Rows of whole frames as a Sequence sorted by frame and id; ids must be unique within a frame."""
    seq = Sequence.from_rows(rows["frame"], rows["id"], np.column_stack([rows["x"], rows["y"]]), rows.get("t"),
                             rows["ignore"], rows.get("group"))
    dup = (np.diff(seq.frame) == 0) & (np.diff(seq.id) == 0) if len(seq) > 1 else np.zeros(0, bool)
    if dup.any():
        k = int(np.flatnonzero(dup)[0])
        raise EvaluationInputError(f"{path}: id {seq.id[k]} appears twice in frame {seq.frame[k]}; expected ids "
                                   f"unique within a frame")
    return seq


def sequence_chunks(path, occlusion: bool = True, visible_column: str | None = None,
                    max_range: float | None = None, chunk_rows: int = CHUNK_ROWS, groups: bool = False):
    """A ground-truth or track file as Sequences of whole frames, in frame order: the rows of the frame a chunk
    ends in are held back and joined to the next chunk's. Ignored rows as ``Ignored`` says; with ``groups``, the
    ground truth's ``group`` column too (required)."""
    ignored = Ignored(occlusion, visible_column, max_range)
    held = None
    required = (*REQUIRED, *GROUNDTRUTH.pick("group")) if groups else REQUIRED
    for table in table_chunks(path, required, read=("t", *ignored.columns), chunk_rows=chunk_rows):
        rows = {"frame": table["frame"].astype(np.int64), "id": table["id"].astype(np.int64), "x": table["x"],
                "y": table["y"], "ignore": ignored(table, path)}
        if "t" in table:
            rows["t"] = table["t"]
        if groups:
            rows["group"] = table["group"].astype(np.int64)
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


def load_sequence(path, occlusion: bool = True, visible_column: str | None = None,
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
