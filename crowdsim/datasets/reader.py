"""Reading a dataset: one episode's files (``Episode``), the whole folder (``Dataset``), and a map-style dataset of
(episode, scan) samples of one laser (``FrameSamples``) for PyTorch's DataLoader.

Files are opened lazily, on first use in the process that uses them, and never pickled: a ``FrameSamples`` handed to
DataLoader workers opens its own HDF5 handles in each worker, whether the workers are spawned (the handles are left
out of the pickle) or forked (a handle inherited from the parent is closed and reopened: HDF5 handles must not be
shared across a fork). No torch import here: samples are dicts of numpy arrays; ``collate`` batches them.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import h5py
import numpy as np
import pyarrow.parquet as pq

from pipeline.frames import compose, to_frame

from .layout import MANIFEST, DatasetError

TABLES = ("persons", "detections", "tracks")
PER_PERSON = ("person_ids", "person_xy", "person_beams")  # the sample fields with one entry per person of the frame


class Episode:
    """One episode folder: ``meta`` (meta.json), ``h5`` (sensors.h5, opened on first use), and its tables."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        try:
            self.meta = json.loads((self.folder / "meta.json").read_text())
        except (OSError, ValueError):
            raise DatasetError(f"{self.folder}: no readable meta.json; expected an episode folder of a dataset "
                               "(crowdsim dataset generate)") from None
        self._h5: h5py.File | None = None
        self._pid = os.getpid()

    def __getstate__(self):
        return {**self.__dict__, "_h5": None}

    def __setstate__(self, state):
        self.__dict__.update(state, _pid=os.getpid())

    @property
    def h5(self) -> h5py.File:
        """sensors.h5, read-only, opened in this process (a handle inherited through a fork is replaced)."""
        if self._pid != os.getpid():
            self.close()
            self._pid = os.getpid()
        if self._h5 is None:
            self._h5 = h5py.File(self.folder / "sensors.h5", "r")
        return self._h5

    def close(self) -> None:
        if self._h5 is not None:
            self._h5.close()
            self._h5 = None

    @property
    def frames(self) -> int:
        return int(self.meta["frames"])

    @property
    def lasers(self) -> list[str]:
        return list(self.meta["calibration"]["lasers"])

    @property
    def cameras(self) -> list[str]:
        c = self.meta["calibration"]
        return [*c["depth_cameras"], *c["wall_cameras"]]

    def laser_angles(self, laser: str) -> np.ndarray:
        """Each beam's angle (rad) in the laser's frame, in the order of the rows of ranges and person_id."""
        c = self.meta["calibration"]["lasers"][laser]
        return c["angle_min"] + c["angle_increment"] * np.arange(c["n_beams"])

    def robot(self) -> dict[str, np.ndarray]:
        """Per frame: stamp, the true pose (world), the odometry pose (odom) and world_T_odom, each [F] or [F, 3]."""
        return {name: self.h5["robot"][name][()] for name in ("stamp", "pose", "odom", "world_T_odom")}

    def sensor(self, name: str) -> h5py.Group:
        """A laser's or camera's group: its datasets (stamp, frame, ranges / person_id, depth / segmentation / rgb)
        read lazily, row by row or in slices."""
        for kind in ("lasers", "cameras"):
            if f"{kind}/{name}" in self.h5:
                return self.h5[f"{kind}/{name}"]
        raise DatasetError(f"{self.folder}: no sensor {name!r}; expected one of "
                           f"{', '.join(self.lasers + self.cameras)}")

    def _parquet(self, name: str) -> Path:
        if name not in TABLES:
            raise DatasetError(f"table {name!r}: expected one of {', '.join(TABLES)}")
        return self.folder / f"{name}.parquet"

    def table(self, name: str, columns: list[str] | None = None, frames: tuple[int, int] | None = None):
        """persons, detections or tracks as a pyarrow Table; ``frames`` (first, last + 1) filters on the frame
        column as the file is read (row groups outside are skipped)."""
        filters = None if frames is None else [("frame", ">=", frames[0]), ("frame", "<", frames[1])]
        return pq.read_table(self._parquet(name), columns=columns, filters=filters)

    def iter_frames(self, name: str, columns: list[str] | None = None):
        """(frame, {column: array}) for every frame 0 .. frames - 1 of a table in order, frames without a row
        included (empty arrays), read one row group at a time (episode.py writes whole frames to a row group), so
        that memory stays bounded whatever the episode's length."""
        f = pq.ParquetFile(self._parquet(name))
        cols = list(dict.fromkeys(["frame", *(f.schema_arrow.names if columns is None else columns)]))
        empty = {c: v.to_numpy(zero_copy_only=False) for c, v in zip(cols, f.schema_arrow.empty_table().select(cols)
                                                                      .columns)}
        nxt = 0
        for g in range(f.num_row_groups):
            t = f.read_row_group(g, columns=cols)
            data = {c: t.column(c).to_numpy(zero_copy_only=False) for c in cols}
            frame = data["frame"]
            if not len(frame):
                continue
            starts = np.flatnonzero(np.r_[True, frame[1:] != frame[:-1]])
            for a, b in zip(starts, np.r_[starts[1:], len(frame)]):
                for nxt in range(nxt, int(frame[a])):  # frames without a row
                    yield nxt, empty
                yield int(frame[a]), {c: v[a:b] for c, v in data.items()}
                nxt = int(frame[a]) + 1
        for nxt in range(nxt, self.frames):
            yield nxt, empty

    def detectors(self) -> set[str]:
        """The detector names in detections.parquet (sensor names, "fusion"), read a row group at a time."""
        f = pq.ParquetFile(self._parquet("detections"), read_dictionary=["detector"])
        return {name for g in range(f.num_row_groups)
                for name in f.read_row_group(g, columns=["detector"]).column(0).unique().to_pylist()}


class Dataset:
    """A dataset folder: its manifest and episodes, by split (train, val, test, or mini)."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        try:
            self.manifest = json.loads((self.folder / MANIFEST).read_text())
        except (OSError, ValueError):
            raise DatasetError(f"{self.folder}: no readable {MANIFEST}; expected a dataset folder (crowdsim dataset "
                               "generate)") from None

    def ids(self, split: str | None = None) -> list[str]:
        """The episode ids of ``split`` (all of them for None), in order."""
        if split is None:
            return [e["id"] for e in self.manifest["episodes"]]
        if split == "mini":
            return list(self.manifest["mini"])
        if split not in self.manifest["splits"]:
            raise DatasetError(f"{self.folder}: split {split!r}: expected one of "
                               f"{', '.join([*self.manifest['splits'], 'mini'])}")
        return list(self.manifest["splits"][split])

    def episode(self, episode_id: str) -> Episode:
        return Episode(self.folder / episode_id)

    def episodes(self, split: str | None = None) -> list[Episode]:
        return [self.episode(i) for i in self.ids(split)]


class FrameSamples:
    """Map-style samples of one laser over the episodes of a split: sample i is (episode, scan), in episode then
    scan order, with

    - ``scans`` [window, beams]: the ``window`` scans up to it, oldest first, the first scan of the episode repeated
      where the episode has fewer (as DR-SPAAM's temporal input takes them);
    - ``person_id`` [beams]: the person each beam of the last scan hit (-1: none);
    - ``person_ids``, ``person_xy`` [n, 2], ``person_beams``: every person of that frame, their position in the
      laser's frame (from the true robot pose) and how many beams hit them (filter on it: DR-SPAAM's rule is 6);
    - ``episode``, ``frame``, ``stamp``.

    ``len`` and indexing read only the manifest and the scan counts up front; a sample reads its rows then."""

    def __init__(self, folder: Path, laser: str, split: str | None = None, window: int = 1):
        if window < 1:
            raise DatasetError(f"window: expected at least 1 scan, got {window}")
        self.laser, self.window = laser, window
        self.episodes = Dataset(folder).episodes(split)
        counts = []
        for ep in self.episodes:
            if laser not in ep.lasers:
                raise DatasetError(f"{ep.folder}: no laser {laser!r}; expected one of {', '.join(ep.lasers)}")
            counts.append(ep.sensor(laser)["stamp"].shape[0])
            ep.close()  # no handle is carried into workers
        self.offsets = np.r_[0, np.cumsum(counts, dtype=np.int64)]

    def __len__(self) -> int:
        return int(self.offsets[-1])

    def __getitem__(self, i: int) -> dict:
        if not 0 <= i < len(self):
            raise IndexError(i)
        e = int(np.searchsorted(self.offsets, i, side="right") - 1)
        k = int(i - self.offsets[e])
        ep = self.episodes[e]
        group = ep.sensor(self.laser)
        first = max(k - self.window + 1, 0)
        rows = np.maximum(np.arange(k - self.window + 1, k + 1), 0) - first
        frame = int(group["frame"][k])
        persons = ep.table("persons", ["id", "x", "y", f"{self.laser}.beams"], (frame, frame + 1))
        ids, x, y, beams = (c.to_numpy().copy() for c in persons.columns)  # copies: writable, as torch wants them
        cal = ep.meta["calibration"]["lasers"][self.laser]
        return {"episode": e, "frame": frame, "stamp": float(group["stamp"][k]),
                "scans": group["ranges"][first:k + 1][rows], "person_id": group["person_id"][k], "person_ids": ids,
                "person_xy": to_sensor(np.column_stack([x, y]), ep.h5["robot"]["pose"][frame],
                                       (cal["x"], cal["y"], cal["yaw"])),
                "person_beams": beams}


def collate(samples: list[dict]) -> dict:
    """A batch of ``FrameSamples`` samples (DataLoader's ``collate_fn``): the fixed-size fields stacked along a new
    first axis, the per-person ones (PER_PERSON: a different count each frame) as lists."""
    return {k: [s[k] for s in samples] if k in PER_PERSON else np.stack([np.asarray(s[k]) for s in samples])
            for k in samples[0]}


def to_sensor(xy: np.ndarray, robot_pose: np.ndarray, mount: tuple[float, float, float]) -> np.ndarray:
    """World points [n, 2] in the frame of a sensor mounted at ``mount`` (x, y, yaw in base_link) on a robot at
    ``robot_pose`` (world)."""
    return to_frame(compose(robot_pose, mount), xy)
