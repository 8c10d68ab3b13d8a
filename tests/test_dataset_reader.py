"""Reading a dataset (crowdsim/datasets/reader.py) on a tiny one generated here: sample counts, the scan window,
the persons in the laser's frame against the beams that hit them, and samples read in spawned processes."""

import math
import pickle
import subprocess
import sys
from multiprocessing import get_context
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml

from crowdsim.datasets import Dataset, FrameSamples, collate
from crowdsim.datasets.generate import generate
from crowdsim.datasets.layout import DatasetError
from scenarios import load_scenario

LASER = "front_laser"


def scenario() -> dict:
    """A 14 m x 10 m room: the robot drives back and forth on a 3 m line with drifting odometry, two standing
    persons in front, one far away (few beams), one behind, walkers crossing."""
    return {"name": "dataset_room", "seed": 3, "warmup": 2.0, "duration": 2.0, "crowd": {"random_force": 0.0},
            "map": {"walls": [[[0, 0], [14, 0], [14, 10], [0, 10], [0, 0]]]},
            "waypoints": {"east": {"position": [12.5, 5.0], "radius": 1.0}},
            "routes": {"across": {"waypoints": ["east"]}},
            "sources": [{"position": [3.0, 7.5], "size": [1.0, 1.0], "rate": 1.5, "routes": {"across": 1.0}}],
            "standing": [{"position": [6.0, 3.0], "count": 2}, {"position": [12.8, 8.8]}, {"position": [0.8, 4.0]}],
            "robot": {"start": [2.0, 5.0, 0.0], "route": [[5.0, 5.0], [2.0, 5.0]], "odometry": {"yaw_drift": 0.05}},
            "sensors": {"lasers": [{"name": "front_laser", "mount": [0.25, 0, 0]},
                                   {"name": "rear_laser", "mount": [-0.25, 0, math.pi]}]}}


def make_dataset(root: Path) -> Path:
    """Three 2 s episodes of ``scenario()`` (train, val, test) in ``root``/ds."""
    path = root / "room.yaml"
    path.write_text(yaml.safe_dump(scenario()))
    generate([load_scenario(str(path))], [str(path)], root / "ds", episodes=3, progress=False)
    return root / "ds"


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    return make_dataset(tmp_path_factory.mktemp("reader"))


def scan_counts(folder: Path, ids: list[str]) -> list[int]:
    counts = []
    for i in ids:
        with h5py.File(folder / i / "sensors.h5", "r") as f:
            counts.append(f[f"lasers/{LASER}/ranges"].shape[0])
    return counts


def test_len_is_the_scan_count_of_the_split(dataset):
    ds = Dataset(dataset)
    for split in ("train", "val", "test", "mini", None):
        assert len(FrameSamples(dataset, LASER, split)) == sum(scan_counts(dataset, ds.ids(split))), split
    assert len(ds.ids()) == 3 and len(FrameSamples(dataset, LASER)) == 150


def test_the_window_repeats_the_first_scan_at_an_episode_start_and_is_the_h5_rows_after(dataset):
    samples = FrameSamples(dataset, LASER, window=3)
    counts = scan_counts(dataset, Dataset(dataset).ids())
    start = 0
    for e, n in enumerate(counts):
        with h5py.File(dataset / f"episode_{e:05d}" / "sensors.h5", "r") as f:
            ranges, pid, frames = (f[f"lasers/{LASER}/{k}"][()] for k in ("ranges", "person_id", "frame"))
        for k, rows in ((0, [0, 0, 0]), (1, [0, 0, 1]), (2, [0, 1, 2]), (n - 1, [n - 3, n - 2, n - 1])):
            s = samples[start + k]
            assert s["episode"] == e and s["frame"] == frames[k]
            np.testing.assert_array_equal(s["scans"], ranges[rows])
            np.testing.assert_array_equal(s["person_id"], pid[k])
        start += n
    with pytest.raises(IndexError):
        samples[len(samples)]


@pytest.mark.parametrize("laser", ["front_laser", "rear_laser"])
def test_persons_in_the_laser_frame_sit_where_the_beams_carrying_their_id_hit(dataset, laser):
    """A beam point lies on a body's surface, so the mean of a person's beam points is within about their radius
    (0.25 m, plus range noise) of their centre, and nearer the laser than the centre. The rear laser looks back
    (mount yaw pi); the robot drives, with drifting odometry, which the true pose leaves out."""
    samples = FrameSamples(dataset, laser)
    angles = Dataset(dataset).episode("episode_00000").laser_angles(laser)
    checked = 0
    for i in range(0, len(samples), 5):
        s = samples[i]
        r = s["scans"][-1]
        points = np.column_stack([r * np.cos(angles), r * np.sin(angles)])
        for pid, xy, beams in zip(s["person_ids"], s["person_xy"], s["person_beams"]):
            hit = s["person_id"] == pid
            assert hit.sum() == beams
            if beams >= 3:
                mean = points[hit].mean(axis=0)
                assert np.hypot(*(mean - xy)) < 0.35 and np.hypot(*mean) < np.hypot(*xy), (i, pid)
                checked += 1
    assert checked >= 20


def _read(blob: bytes, indices: list[int]) -> list[dict]:
    samples = pickle.loads(blob)
    return [samples[i] for i in indices]


def assert_same_sample(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_a_used_frame_samples_pickles_and_reads_the_same_in_two_spawned_processes(dataset):
    samples = FrameSamples(dataset, LASER, split="mini", window=2)
    indices = [0, 1, 49, 50, 51, 99, 100, 149]
    expected = [samples[i] for i in indices]  # its episodes now hold open HDF5 handles
    blob = pickle.dumps(samples)
    with get_context("spawn").Pool(2) as pool:
        halves = pool.starmap(_read, [(blob, indices[0::2]), (blob, indices[1::2])])
    got = [None] * len(indices)
    got[0::2], got[1::2] = halves
    for a, b in zip(expected, got):
        assert_same_sample(a, b)


def test_a_handle_opened_in_another_process_is_replaced_and_collate_batches(dataset):
    samples = FrameSamples(dataset, LASER, split="test")
    ep = samples.episodes[0]
    inherited = ep.h5
    ep._pid = -1  # what a forked DataLoader worker sees: the handle was opened by its parent
    assert ep.h5 is not inherited and not inherited.id.valid and ep.h5.id.valid
    a, b = samples[0], samples[7]
    assert all(v.flags.writeable for v in a.values() if isinstance(v, np.ndarray))  # torch.as_tensor warns else
    batch = collate([a, b])
    assert batch["scans"].shape == (2, 1, len(a["person_id"])) and batch["frame"].tolist() == [0, 7]
    assert [len(x) for x in batch["person_xy"]] == [len(a["person_ids"]), len(b["person_ids"])]


def test_bad_input_is_one_dataset_error_naming_it(dataset, tmp_path):
    for call, words in ((lambda: FrameSamples(dataset, "side_laser"), ("no laser 'side_laser'", "front_laser")),
                        (lambda: FrameSamples(dataset, LASER, "holdout"), ("split 'holdout'", "train, val, test")),
                        (lambda: FrameSamples(dataset, LASER, window=0), ("window", "at least 1")),
                        (lambda: FrameSamples(tmp_path, LASER), (str(tmp_path), "expected a dataset folder"))):
        with pytest.raises(DatasetError) as info:
            call()
        assert all(w in str(info.value) for w in words), str(info.value)


def test_importing_the_package_reads_no_dataset_library():
    code = "import sys, crowdsim.datasets as d; assert 'h5py' not in sys.modules; d.FrameSamples; " \
           "assert 'h5py' in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)
