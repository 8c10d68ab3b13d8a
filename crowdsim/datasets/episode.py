"""One dataset episode: the scenario simulated at one seed and written frame by frame into a directory.

Files (docs/dataset-format.md): ``meta.json``, ``sensors.h5`` (raw sensor data with per-beam and per-pixel person
ids, the robot's true pose and odometry), ``persons.parquet`` (the ground truth per frame and person, with what each
sensor saw of them), ``detections.parquet`` (each detector's output and the fused detections) and ``tracks.parquet``.

Memory stays flat over an episode of any length: HDF5 datasets grow a chunk at a time, and the Parquet tables are
written a row group at a time. The bytes depend on the scenario and seed alone: HDF5 is written without object
timestamps, JSON with a fixed key order, and nothing records when or where it was made.
"""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import h5py
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from evaluation.navigation_report import json_safe
from pipeline.frames import compose, inverse, rotate, transform_points
from scenarios.typed import Scenario, as_written

from ..loop import Frame, Simulation
from .layout import FORMAT_VERSION, FUSED, calibration

ROW_GROUP_FRAMES = 250  # tracking cycles a Parquet row group holds (10 s at 25 Hz)
COMPRESSIONS = ("gzip", "lzf", "none")


try:
    import resource
except ImportError:  # Windows: no file size limit to heed
    resource = None


class Room:
    """Keeps sensors.h5 from meeting a full disk or the file size limit (``ulimit -f``). HDF5 cannot take a failed
    write: it reports it late or not at all, and the process crashes when the file is closed. So every block of rows
    is checked before HDF5 sees it, against what the file could still take: the block, what HDF5 may still hold to
    write later (its chunk cache, CACHE a dataset; its dirty metadata, METADATA a chunk up to METADATA_CACHE), and
    SLACK for the file's own structure; the disk must hold that beyond RESERVE, for the episode's tables and
    meta.json. The tables are checked too, so that they never take the room sensors.h5 needs to be closed. A block
    that does not fit is an OSError (ENOSPC, or EFBIG for the file size limit) before anything of it is written, and
    the file, every block before it checked, can still be closed. (Only another process filling the disk between
    two checks can still catch HDF5 out.)"""

    CACHE = 1 << 20  # h5py's chunk cache per dataset (rdcc_nbytes), written out as chunks are evicted or at close
    METADATA = 96  # bytes of chunk index and other metadata a chunk may add, written at close ...
    METADATA_CACHE = 32 << 20  # ... or once HDF5's metadata cache (32 MiB at most by default) is full
    SLACK = 256 << 10  # the superblock, groups, dataset headers
    RESERVE = 4 << 20  # bytes kept free on the disk for the tables, meta.json and other writers

    def __init__(self, path: Path):
        self.path = path
        self.written: dict[str, int] = {}  # dataset -> raw bytes given to HDF5
        self.chunks = 0

    def pending(self, written: dict[str, int] | None = None, chunks: int | None = None) -> int:
        """Bytes HDF5 may still write to the file from what it was given (all of it, at worst, at close)."""
        written = self.written if written is None else written
        chunks = self.chunks if chunks is None else chunks
        return (sum(min(self.CACHE, n) for n in written.values()) + min(self.METADATA * chunks, self.METADATA_CACHE)
                + self.SLACK)

    def check_h5(self, blocks: dict[str, tuple[int, int]]) -> None:
        """Before giving HDF5 ``blocks`` (dataset -> (raw bytes, chunks)); they count as given once this passes."""
        written = dict(self.written)
        for name, (nbytes, _) in blocks.items():
            written[name] = written.get(name, 0) + nbytes
        chunks = self.chunks + sum(c for _, c in blocks.values())
        need = sum(n for n, _ in blocks.values()) + self.pending(written, chunks)
        try:
            size = os.stat(self.path).st_size
        except FileNotFoundError:
            size = 0
        if resource is not None:
            limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
            if limit != resource.RLIM_INFINITY and size + need > limit:
                raise OSError(errno.EFBIG, os.strerror(errno.EFBIG), str(self.path))
        self._check_disk(need)
        self.written, self.chunks = written, chunks

    def check_table(self, nbytes: int) -> None:
        """Before writing ``nbytes`` to a table: room for it beside what sensors.h5 still needs."""
        self._check_disk(nbytes + self.pending())

    def _check_disk(self, need: int) -> None:
        if hasattr(os, "statvfs"):
            st = os.statvfs(self.path.parent)
            if st.f_bavail * st.f_frsize < need + self.RESERVE:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self.path.parent))


class H5Stream:
    """Datasets of one HDF5 group that grow by one row per ``append``, chunked one row per chunk (a frame read alone
    reads one chunk), compressed per ``compression``; rows wait in a small buffer and go to disk in blocks, each
    checked first against the ``room`` left."""

    BLOCK = 32

    def __init__(self, group: h5py.Group, compression: str, room: Room | None = None):
        self.group, self.compression, self.room = group, compression, room
        self.rows: dict[str, list] = {}
        self.written = 0

    def append(self, **values) -> None:
        for name, value in values.items():
            value = np.asarray(value)
            if name not in self.group:
                kw = {} if self.compression == "none" else {"compression": self.compression, "shuffle": True}
                if self.compression == "gzip":
                    kw["compression_opts"] = 4
                self.group.create_dataset(name, shape=(0, *value.shape), maxshape=(None, *value.shape),
                                          dtype=value.dtype, chunks=(1, *value.shape) if value.shape else (1024,),
                                          track_times=False, **kw)
                self.rows[name] = []
            self.rows[name].append(value)
        if len(next(iter(self.rows.values()))) >= self.BLOCK:
            self.flush()

    def flush(self) -> None:
        if self.room is not None:
            blocks = {}
            for name, rows in self.rows.items():
                if rows:  # (raw bytes, chunks): a row a chunk, scalars 1024 to a chunk
                    blocks[f"{self.group.name}/{name}"] = (sum(r.nbytes for r in rows), len(rows) if rows[0].shape
                                                           else 1)
            if blocks:
                self.room.check_h5(blocks)
        for name, rows in self.rows.items():
            if rows:
                data = self.group[name]
                data.resize(self.written + len(rows), axis=0)
                data[self.written:] = np.stack(rows)
        self.written += len(next(iter(self.rows.values()), []))
        for rows in self.rows.values():
            rows.clear()


class ParquetStream:
    """A Parquet file written a row group at a time, from column blocks (dicts of equal-length arrays)."""

    def __init__(self, path: Path, schema: pa.Schema, compression: str, room: Room | None = None):
        self.path, self.schema, self.room = path, schema, room
        self.writer = pq.ParquetWriter(path, schema, compression=None if compression == "none" else "zstd")
        self.blocks: list[dict] = []
        self.frames = 0

    def add(self, columns: dict) -> None:
        self.blocks.append(columns)

    def end_frame(self) -> None:
        self.frames += 1
        if self.frames % ROW_GROUP_FRAMES == 0:
            self.flush()

    def flush(self) -> None:
        """The waiting blocks as one row group; none when they hold no row (frames without a person, a detection
        or a track: the reader gives those frames empty arrays). A table without a row is a valid table: the
        schema and no row group."""
        if any(len(b["frame"]) for b in self.blocks):
            table = pa.table({name: np.concatenate([b[name] for b in self.blocks])
                              for name in self.schema.names}, schema=self.schema)
            if self.room is not None:
                self.room.check_table(table.nbytes)
            self.writer.write_table(table, row_group_size=len(table))
        self.blocks.clear()

    def close(self) -> None:
        self.flush()
        self.writer.close()


def _box_columns(prefix: str) -> list[tuple[str, pa.DataType]]:
    return [(f"{prefix}.{kind}_{c}", pa.float32()) for kind in ("box", "full_box") for c in ("u0", "v0", "u1", "v1")]


def persons_schema(lasers: list[str], cameras: list[str]) -> pa.Schema:
    fields = [("frame", pa.int32()), ("t", pa.float64()), ("id", pa.int64()), ("group_id", pa.int64()),
              ("agent_type", pa.string()), ("x", pa.float64()), ("y", pa.float64()), ("vx", pa.float64()),
              ("vy", pa.float64()), ("heading", pa.float64()), ("radius", pa.float64())]
    for name in lasers:
        fields += [(f"{name}.beams", pa.int32()), (f"{name}.in_view", pa.bool_()), (f"{name}.occluded", pa.bool_())]
    for name in cameras:
        fields += [(f"{name}.visible", pa.float32()), (f"{name}.in_view", pa.bool_()),
                   (f"{name}.occluded", pa.bool_()), *_box_columns(name)]
    return pa.schema(fields)


DETECTIONS_SCHEMA = pa.schema([
    ("frame", pa.int32()), ("t", pa.float64()), ("detector", pa.string()), ("modality", pa.string()),
    ("id", pa.int64()), ("x", pa.float64()), ("y", pa.float64()), ("z", pa.float64()), ("confidence", pa.float64()),
    ("cov_xx", pa.float64()), ("cov_xy", pa.float64()), ("cov_yy", pa.float64()),
    ("world_x", pa.float64()), ("world_y", pa.float64())])
TRACKS_SCHEMA = pa.schema([
    ("frame", pa.int32()), ("t", pa.float64()), ("id", pa.int64()), ("x", pa.float64()), ("y", pa.float64()),
    ("vx", pa.float64()), ("vy", pa.float64()), ("cov_xx", pa.float64()), ("cov_xy", pa.float64()),
    ("cov_yy", pa.float64()), ("is_matched", pa.bool_()), ("is_occluded", pa.bool_()), ("detection_id", pa.int64()),
    ("age", pa.float64()), ("world_x", pa.float64()), ("world_y", pa.float64()), ("world_vx", pa.float64()),
    ("world_vy", pa.float64())])


class EpisodeWriter:
    """Writes the frames of one simulation into ``out`` (an empty directory)."""

    def __init__(self, sim: Simulation, out: Path, compression: str = "gzip"):
        self.sim, self.out = sim, Path(out)
        self.lasers = [laser.name for laser in sim.lasers]
        self.depth = [c.name for c in sim.depth_cameras]
        self.wall = [c.name for c in sim.wall_cameras]
        self.types = np.array(list(sim.scenario.crowd.agent_types), dtype=object)
        room = Room(self.out / "sensors.h5")
        room.check_h5({})  # room for the file's structure before HDF5 writes any of it
        self.h5 = h5py.File(self.out / "sensors.h5", "w", track_order=False)
        self.h5.attrs["format_version"] = FORMAT_VERSION
        self.streams = {"robot": H5Stream(self.h5.create_group("robot"), compression, room)}
        for name in self.lasers:
            self.streams[name] = H5Stream(self.h5.create_group(f"lasers/{name}"), compression, room)
        for name in self.depth + self.wall:
            self.streams[name] = H5Stream(self.h5.create_group(f"cameras/{name}"), compression, room)
        self.persons = ParquetStream(self.out / "persons.parquet",
                                     persons_schema(self.lasers, self.depth + self.wall), compression, room)
        self.detections = ParquetStream(self.out / "detections.parquet", DETECTIONS_SCHEMA, compression, room)
        self.tracks = ParquetStream(self.out / "tracks.parquet", TRACKS_SCHEMA, compression, room)
        self.boxes: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}  # camera -> its latest ids and boxes
        self.frames = 0

    def write(self, frame: Frame) -> None:
        odom = _odom_pose(frame)
        self.streams["robot"].append(stamp=frame.stamp, pose=frame.robot_pose, odom=odom,
                                     world_T_odom=frame.world_T_odom)
        for scan in frame.scans:
            self.streams[scan.frame].append(stamp=scan.stamp, frame=np.int32(frame.index),
                                            ranges=scan.ranges.astype(np.float32),
                                            person_id=scan.person_id.astype(np.int32))
        for image in frame.depth_frames:
            extra = {} if image.rgb is None else {"rgb": image.rgb}
            self.streams[image.frame].append(stamp=image.stamp, frame=np.int32(frame.index), depth=image.depth,
                                             segmentation=image.person_id.astype(np.int32), **extra)
        for image in frame.camera_frames:
            extra = {} if image.rgb is None else {"rgb": image.rgb}
            self.streams[image.frame].append(stamp=image.stamp, frame=np.int32(frame.index),
                                             segmentation=image.person_id.astype(np.int32), **extra)
        for image in (*frame.depth_frames, *frame.camera_frames):
            self.boxes[image.frame] = (image.ids, image.boxes, image.full_boxes)
        self.persons.add(self._person_columns(frame))
        for name, batch in (*frame.detector_outputs.items(), (FUSED, frame.detections)):
            self.detections.add(_detection_columns(frame, name, batch))
        self.tracks.add(_track_columns(frame))
        for table in (self.persons, self.detections, self.tracks):
            table.end_frame()
        self.frames += 1

    def _person_columns(self, frame: Frame) -> dict:
        a, v = frame.agents, frame.visibility
        n = len(a.id)
        columns = {"frame": np.full(n, frame.index, np.int32), "t": np.full(n, frame.stamp), "id": a.id,
                   "group_id": a.group_id, "agent_type": self.types[a.kind], "x": a.position[:, 0],
                   "y": a.position[:, 1], "vx": a.velocity[:, 0], "vy": a.velocity[:, 1],
                   # the way the body faces as drawn and ray-cast (sensors/scene.py): along the velocity
                   "heading": np.arctan2(a.velocity[:, 1], a.velocity[:, 0]), "radius": a.radius}
        occluded = v.occluded
        for k, name in enumerate(v.sensors):
            amount = v.amount[:, k]
            if name in self.lasers:
                columns[f"{name}.beams"] = np.nan_to_num(amount).astype(np.int32)
            else:
                columns[f"{name}.visible"] = amount.astype(np.float32)
                boxes = np.full((n, 8), np.nan, np.float32)
                if name in self.boxes:
                    ids, box, full = self.boxes[name]
                    rows = np.searchsorted(a.id, ids)
                    keep = rows < n
                    keep[keep] = a.id[rows[keep]] == ids[keep]
                    boxes[rows[keep]] = np.hstack([box, full])[keep]
                for j, column in enumerate(_box_columns(name)):
                    columns[column[0]] = boxes[:, j]
            columns[f"{name}.in_view"] = v.in_view[:, k]
            columns[f"{name}.occluded"] = occluded[:, k]
        return columns

    def close(self, complete: bool) -> None:
        """Flush and close every file; with ``complete``, write meta.json last. An incomplete episode (an error, an
        interruption) is closed without flushing what waits, every file closed whatever fails, and the folder is
        the caller's to remove."""
        if complete:
            try:
                for stream in self.streams.values():
                    stream.flush()
                self.h5.close()
                for table in (self.persons, self.detections, self.tracks):
                    table.close()
                self._write_meta()
                return
            except BaseException:
                self.close(False)
                raise
        for close in (self.h5.close, *(t.writer.close for t in (self.persons, self.detections, self.tracks))):
            try:
                close()
            except Exception:  # noqa: BLE001 - the error that stopped the episode is the one to report
                pass

    def _write_meta(self) -> None:
        sim = self.sim
        scenario = {k: v for k, v in as_written(sim.scenario).items() if k != "source"}
        meta = {"format_version": FORMAT_VERSION, "seed": sim.seed, "frames": self.frames,
                "frame_stamps": "each frame is a tracking cycle (a laser scan); t in s of simulated time from the "
                                "crowd's start, warm-up included",
                "frames_of_reference": {"world": "the map's frame, z up", "odom": "where the robot's odometry "
                                        "started (the pipeline's frame: detections and tracks)", "base_link":
                                        "the robot, x forward, y left"},
                "agent_types": list(self.types),
                "calibration": calibration(sim.scenario, sim.lasers, sim.depth_cameras, sim.wall_cameras),
                "scenario": scenario}
        # strict JSON: a source's endless stop (inf) is null
        (self.out / "meta.json").write_text(json.dumps(json_safe(meta), indent=1, allow_nan=False) + "\n")


def _odom_pose(frame: Frame) -> np.ndarray:
    """The robot's odometry pose in odom: the true pose brought through the inverse of the true world_T_odom."""
    return compose(inverse(frame.world_T_odom), frame.robot_pose)


def _detection_columns(frame: Frame, name: str, d) -> dict:
    n = len(d)
    world = transform_points(frame.world_T_odom, d.position[:, :2])
    return {"frame": np.full(n, frame.index, np.int32), "t": np.full(n, d.stamp), "detector": np.full(n, name, object),
            "modality": np.full(n, d.modality, object), "id": d.detection_id, "x": d.position[:, 0],
            "y": d.position[:, 1], "z": d.position[:, 2], "confidence": d.confidence,
            "cov_xx": d.covariance[:, 0, 0], "cov_xy": d.covariance[:, 0, 1], "cov_yy": d.covariance[:, 1, 1],
            "world_x": world[:, 0], "world_y": world[:, 1]}


def _track_columns(frame: Frame) -> dict:
    t = frame.tracks
    n = len(t)
    world, world_v = transform_points(frame.world_T_odom, t.position), rotate(frame.world_T_odom, t.velocity)
    return {"frame": np.full(n, frame.index, np.int32), "t": np.full(n, frame.stamp), "id": t.track_id,
            "x": t.position[:, 0], "y": t.position[:, 1], "vx": t.velocity[:, 0], "vy": t.velocity[:, 1],
            "cov_xx": t.position_covariance[:, 0, 0], "cov_xy": t.position_covariance[:, 0, 1],
            "cov_yy": t.position_covariance[:, 1, 1], "is_matched": t.is_matched, "is_occluded": t.is_occluded,
            "detection_id": t.detection_id, "age": t.age, "world_x": world[:, 0], "world_y": world[:, 1],
            "world_vx": world_v[:, 0], "world_vy": world_v[:, 1]}


def write_episode(scenario: Scenario, seed: int, duration: float, out: Path, compression: str = "gzip",
                  on_frame=None) -> int:
    """Simulate ``scenario`` at ``seed`` for ``duration`` s (after its warm-up) into the empty directory ``out``;
    return the number of frames. ``on_frame(stamp)`` is called after each frame (progress)."""
    sim = Simulation(scenario)
    sim.reset(seed)
    sim.warm_up()
    writer = EpisodeWriter(sim, out, compression)
    complete = False
    try:
        for frame in sim.frames(duration):
            writer.write(frame)
            if on_frame is not None:
                on_frame(frame.stamp)
        complete = True
    finally:
        writer.close(complete)
    return writer.frames
