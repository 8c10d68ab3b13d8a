"""MOTChallenge export: ground truth, the tracker's input and its tracks as MOTChallenge ground-plane files.

Per episode, ``OUT/<split>/<episode>/`` holds ``gt/gt.txt`` (every person of every frame), ``det/det.txt`` (the fused
detections the tracker got), ``tracks.txt`` (the tracks) and ``seqinfo.ini``. The rows follow MOT15's 3D convention
as motchallenge.net's instructions give it and ``crowdsim evaluate --motchallenge`` writes it
(evaluation/io.py ``write_motchallenge``): ``frame, id, -1, -1, -1, -1, conf, x, y, z``, frame 1-based, the image
box unused (-1), x and y in m in the world frame, z = 0; the MOT devkit (``evaluateTracking.m``) matches at 1 m in
the ground plane. conf is, for the ground truth, MOT's "consider" flag: 1 where at least one laser beam hit the
person that frame (a run's ``visible``), else 0; for detections the detector's confidence (and id -1, as MOT's
det.txt has it); for tracks 1. ``seqinfo.ini`` gives name, frameRate and seqLength, which newer MOT tools read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from .layout import FUSED

FMT = ["%d", "%d", "%d", "%d", "%d", "%d", "%g", "%.4f", "%.4f", "%d"]
BATCH = 1 << 16  # rows read at once


def write(episodes, out: Path) -> dict:
    """Every episode's sequence folder under ``out/<split>/``; the rows written per file kind."""
    rows = {"gt": 0, "det": 0, "tracks": 0}
    for ep, split in episodes:
        seq = out / split / ep.folder.name
        (seq / "gt").mkdir(parents=True)
        (seq / "det").mkdir()
        rows["gt"] += _write(seq / "gt" / "gt.txt", _groundtruth(ep))
        rows["det"] += _write(seq / "det" / "det.txt", _detections(ep))
        rows["tracks"] += _write(seq / "tracks.txt", _tracks(ep))
        stamp = ep.h5["robot"]["stamp"][:2]
        rate = 1 / (stamp[1] - stamp[0]) if len(stamp) == 2 else 0.0
        (seq / "seqinfo.ini").write_text(f"[Sequence]\nname={ep.folder.name}\nframeRate={rate:g}\n"
                                         f"seqLength={ep.frames}\n")
    return {"rows": rows}


def _batches(ep, table: str, columns: list[str]):
    for batch in pq.ParquetFile(ep.folder / f"{table}.parquet").iter_batches(BATCH, columns=columns):
        yield {c: batch.column(c).to_numpy(zero_copy_only=False) for c in columns}


def _groundtruth(ep):
    """(frame, id, consider, x, y): consider where a laser beam hit the person."""
    beams = [f"{name}.beams" for name in ep.lasers]
    for b in _batches(ep, "persons", ["frame", "id", "x", "y", *beams]):
        seen = np.zeros(len(b["id"]), bool) if beams else np.ones(len(b["id"]), bool)
        for column in beams:
            seen |= b[column] > 0
        yield b["frame"], b["id"], seen, b["x"], b["y"]


def _detections(ep):
    """(frame, -1, confidence, x, y) of the fused detections, the tracker's input."""
    for b in _batches(ep, "detections", ["frame", "detector", "confidence", "world_x", "world_y"]):
        fused = b["detector"] == FUSED
        yield b["frame"][fused], -1, b["confidence"][fused], b["world_x"][fused], b["world_y"][fused]


def _tracks(ep):
    for b in _batches(ep, "tracks", ["frame", "id", "world_x", "world_y"]):
        yield b["frame"], b["id"], 1, b["world_x"], b["world_y"]


def _write(path: Path, batches) -> int:
    """MOT rows from (frame, id, conf, x, y) column batches (scalars broadcast); the number of rows."""
    n = 0
    with open(path, "w") as f:
        for frame, ids, conf, x, y in batches:
            k = len(frame)
            minus = np.full(k, -1)
            np.savetxt(f, np.column_stack([frame + 1, np.broadcast_to(ids, k), minus, minus, minus, minus,
                                           np.broadcast_to(conf, k), x, y, np.zeros(k)]), fmt=FMT, delimiter=",")
            n += k
    return n
