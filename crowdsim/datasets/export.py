"""``crowdsim dataset export``: a dataset's episodes in another tool's format, one module per format (export_drow,
export_mot, export_ros).

Each episode goes to ``OUT/<its split>/`` under its own id (DROW: ``OUT/DROWv2-data/<split>/``), so that the
tools' train/val/test folders come out as the dataset's splits. Everything is written into a temporary folder beside
OUT and moved into place when complete (crowdsim/outdir.py): a failed export leaves nothing, and an existing
non-empty OUT is refused, never touched. Episodes are read a frame or a block of scans at a time, so memory does not
grow with their length.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

from ..outdir import write_directory
from . import export_drow, export_mot, export_ros
from .layout import DatasetError
from .reader import Dataset

FORMATS = ("drow", "motchallenge", "rosbag2", "rosbag1")


def export_dataset(folder: Path, fmt: str, out: Path, split: str | None = None, laser: str | None = None) -> dict:
    """Export the episodes of ``split`` (all if None) of the dataset in ``folder`` as ``fmt`` into the new folder
    ``out``; ``laser`` picks DROW's laser (default: the first on DROW's beam grid). Returns a summary: the format,
    OUT, the episodes and the files written, and per format what it wrote (scans and labels, rows, messages)."""
    if fmt not in FORMATS:
        raise DatasetError(f"--format {fmt}: expected one of {', '.join(FORMATS)}")
    if laser is not None and fmt != "drow":
        raise DatasetError(f"--laser {laser}: only the drow format takes a laser; {fmt} exports every sensor")
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise DatasetError(f"--out {out}: already exists and is not empty; expected a new or empty folder "
                           "(nothing was written)")
    dataset = Dataset(folder)
    split_of = {e["id"]: e["split"] for e in dataset.manifest["episodes"]}
    episodes = [(ep, split_of[ep.folder.name]) for ep in dataset.episodes(split)]
    if not episodes:
        raise DatasetError(f"{folder}: no complete episode in split {split or 'any'}; expected at least one")
    try:
        if fmt == "drow":
            write = partial(export_drow.write, episodes, export_drow.check(episodes, laser))  # refused up front
        elif fmt == "motchallenge":
            write = partial(export_mot.write, episodes)
        else:
            write = partial(export_ros.write, episodes, ros=1 if fmt == "rosbag1" else 2)
        summary = write_directory(out, write)
    finally:
        for ep, _ in episodes:
            ep.close()
    files = [p for p in out.rglob("*") if p.is_file()]
    return {"format": fmt, "out": str(out), "episodes": len(episodes), "files": len(files),
            "bytes": sum(p.stat().st_size for p in files), **summary}
