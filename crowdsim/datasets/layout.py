"""What a dataset directory holds and where (docs/dataset-format.md): the format version, the file names, the splits,
each episode's seed, and the calibration of every sensor as meta.json gives it.

Everything here is a pure function of the command's arguments, so that the same command names the same episodes,
seeds and splits whatever the workers, the engine or the order in which episodes finish.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np

from pipeline.frames import optical_rotation
from pipeline.params import declared
from scenarios.typed import Scenario, plain

from ..errors import Error

FORMAT_VERSION = "1.0"
MANIFEST = "manifest.json"
EPISODE_FILES = ("meta.json", "sensors.h5", "persons.parquet", "detections.parquet", "tracks.parquet")
SPLITS = ("train", "val", "test")
# the splits go by episode index, ten at a time: 8 of every 10 train, one val, one test (index 1 and 2 of each ten),
# so that a dataset of 3 episodes has all three and a longer one keeps the first episodes' splits
SPLIT_OF_INDEX = ("train", "val", "test", "train", "train", "train", "train", "train", "train", "train")
FUSED = "fusion"  # detections.parquet's detector name for the fused detections, the tracker's input
MINI_EPISODES = {"train": 2, "val": 1, "test": 1}  # the first episodes of each split that make up `mini`


class DatasetError(Error):
    """A dataset command that cannot go on: names the folder, option or file, and what was expected (a
    ``crowdsim.Error``, so the command line prints it as one line)."""


def episode_id(index: int) -> str:
    return f"episode_{index:05d}"


def split_of(index: int) -> str:
    return SPLIT_OF_INDEX[index % len(SPLIT_OF_INDEX)]


def in_mini(index: int) -> bool:
    """Whether the episode belongs to the small `mini` subset: the first of each split (tests, quick looks)."""
    split = split_of(index)
    earlier = sum(split_of(k) == split for k in range(index))
    return earlier < MINI_EPISODES[split]


def episode_seeds(root: int, index: int) -> tuple[int, np.random.Generator]:
    """The episode's simulation seed and its generator for the per-episode variations, both from the ``index``-th
    child of ``SeedSequence(root)`` (what ``SeedSequence(root).spawn(...)[index]`` gives), so that an episode's
    content depends on its index alone."""
    child = np.random.SeedSequence(root, spawn_key=(index,))
    seed = int(child.generate_state(1, np.uint32)[0])
    return seed, np.random.default_rng(child.spawn(1)[0])


def scenario_digest(scenario: Scenario) -> str:
    """sha256 of the scenario as resolved (every default and base file filled in; its source path left out), so
    that a change to a file it builds on shows."""
    data = {k: v for k, v in plain(scenario).items() if k != "source"}
    return hashlib.sha256(json.dumps(data, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def file_digest(path) -> tuple[int, str]:
    """(size in bytes, sha256) of a file, read in blocks."""
    h, size = hashlib.sha256(), 0
    with open(path, "rb") as f:
        while block := f.read(1 << 20):
            h.update(block)
            size += len(block)
    return size, h.hexdigest()


def camera_matrix(width: int, height: int, fovy_deg: float) -> list[list[float]]:
    """K of MuJoCo's pinhole (sensors/camera.py): square pixels, f = (h / 2) / tan(fovy / 2), centre (w / 2, h / 2);
    pixel (u, v) covers [u, u + 1) x [v, v + 1)."""
    f = height / 2 / np.tan(np.radians(fovy_deg) / 2)
    return [[f, 0.0, width / 2], [0.0, f, height / 2], [0.0, 0.0, 1.0]]


def calibration(scenario: Scenario, lasers, depth_cameras, wall_cameras) -> dict:
    """Every sensor's calibration: its parent frame and mount, and for a laser its beam angles and range limits, for a
    camera its intrinsics, image size and units. Transforms are parent_T_sensor: a laser's (x, y, yaw) in base_link
    at its height; a camera's position and the rotation whose columns are its optical axes."""
    out = {"lasers": {}, "depth_cameras": {}, "wall_cameras": {}}
    for laser in lasers:
        out["lasers"][laser.name] = {
            "parent": "base_link", "x": float(laser.mount[0]), "y": float(laser.mount[1]),
            "yaw": float(laser.mount[2]), "z": float(laser.height), "n_beams": int(laser.n_beams),
            "angle_min": float(laser.angle_min), "angle_increment": float(laser.angle_increment),
            "angle_max": float(laser.angles[-1]), "range_min": float(laser.range_min),
            "range_max": float(laser.range_max), "rate_hz": float(laser.rate), "no_return": laser.no_return,
            "model": {k: v for k, v in declared(laser).items() if k not in ("name", "mount")}}
    for kind, cameras, parent in (("depth_cameras", depth_cameras, "base_link"), ("wall_cameras", wall_cameras, "world")):
        for camera in cameras:
            k = camera.intrinsics
            entry = {"parent": parent, "position": [float(v) for v in camera.position],
                     "rotation": optical_rotation(camera.yaw, camera.pitch).tolist(),
                     "optical_axes": "x right, y down, z forward", "width": int(k.width), "height": int(k.height),
                     "fovy_deg": float(k.fovy_deg),
                     "K": camera_matrix(k.width, k.height, k.fovy_deg), "rate_hz": float(camera.rate),
                     "rgb": bool(camera.rgb), "renderer": camera.backend,
                     "segmentation": "int32 person id per pixel, -1 none"}
            if kind == "depth_cameras":
                entry.update(depth="float32 z-depth in m along the optical axis, NaN where nothing was measured",
                             range_min=float(camera.range_min), range_max=float(camera.range_max),
                             noise=camera.noise)
            out[kind][camera.name] = entry
    return out
