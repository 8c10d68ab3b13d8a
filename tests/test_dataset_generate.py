"""``crowdsim dataset generate``: the same bytes whatever the workers or the engine, resuming after a crash or a
corrupt file, the refusals, the per-episode variations, and the labels checked against the raw data. A small room,
a few people, short episodes."""

import json
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml

from crowdsim.cli import main
from crowdsim.datasets.generate import generate, plan, vary
from crowdsim.datasets.layout import DatasetError, episode_seeds, file_digest, split_of
from scenarios import load_scenario

ROOM = {
    "name": "dataset_room", "seed": 4, "warmup": 3.0, "duration": 0.6,
    "map": {"walls": [[[0, 0], [14, 0], [14, 10], [0, 10], [0, 0]]]},
    "waypoints": {"east": {"position": [12, 5], "radius": 1.0}},
    "routes": {"across": {"waypoints": ["east"]}},
    "sources": [{"position": [2, 5], "size": [1, 4], "rate": 2.0, "routes": {"across": 1.0}}],
    "standing": [{"position": [7, 8], "count": 3}],
    "robot": {"start": [6, 2, 1.5708], "route": [[6, 6], [9, 6]]},
    "sensors": {"lasers": [{"name": "front_laser", "mount": [0.25, 0, 0]},
                           {"name": "rear_laser", "mount": [-0.25, 0, 3.14159]}],
                "depth_cameras": [{"name": "front_depth", "preset": "kinect_160", "width": 32, "height": 24,
                                   "rate": 15.0, "rgb": True}],
                "wall_cameras": [{"name": "corner_cam", "position": [0.3, 0.3, 2.8], "yaw": 0.6, "pitch": 0.45,
                                  "width": 32, "height": 24}]},
}


@pytest.fixture(scope="module")
def room_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("scenario") / "dataset_room.yaml"
    path.write_text(yaml.safe_dump(ROOM))
    return path


@pytest.fixture(scope="module")
def dataset(room_file, tmp_path_factory):
    """Three episodes with one worker: the reference the other tests compare with."""
    out = tmp_path_factory.mktemp("ds") / "reference"
    generate([load_scenario(room_file)], [str(room_file)], out, 3, seed=7, progress=False)
    return out


def files_of(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_the_manifest_lists_every_episode_with_its_split_seed_and_checksums(dataset, room_file):
    m = json.loads((dataset / "manifest.json").read_text())
    assert m["format_version"] == "1.0" and m["root_seed"] == 7
    assert m["command"] == f"crowdsim dataset generate {room_file} --episodes 3 --seed 7"
    assert [e["id"] for e in m["episodes"]] == ["episode_00000", "episode_00001", "episode_00002"]
    assert m["splits"] == {"train": ["episode_00000"], "val": ["episode_00001"], "test": ["episode_00002"]}
    assert m["mini"] == ["episode_00000", "episode_00001", "episode_00002"]
    for k, e in enumerate(m["episodes"]):
        # the k-th child of SeedSequence(7), as spawn() would give it
        child = np.random.SeedSequence(7).spawn(3)[k]
        assert e["seed"] == int(child.generate_state(1, np.uint32)[0]) == episode_seeds(7, k)[0]
        assert e["frames"] == 15  # 0.6 s at the lasers' 25 Hz
        assert e["status"] == "complete"
        for name, f in e["files"].items():
            assert file_digest(dataset / e["id"] / name) == (f["size"], f["sha256"])
        meta = json.loads((dataset / e["id"] / "meta.json").read_text())
        assert meta["seed"] == e["seed"] and meta["scenario"]["seed"] == e["seed"]
    assert {p.name for p in dataset.iterdir()} == {"manifest.json", "episode_00000", "episode_00001",
                                                   "episode_00002"}


def test_two_workers_write_the_same_bytes(dataset, room_file, tmp_path):
    out = tmp_path / "two"
    assert main(["dataset", "generate", str(room_file), "--episodes", "3", "--seed", "7", "--out", str(out),
                 "--workers", "2", "--quiet"]) == 0
    assert files_of(out) == files_of(dataset)


def test_ray_writes_the_same_bytes(dataset, room_file, tmp_path):
    out = tmp_path / "ray"
    generate([load_scenario(room_file)], [str(room_file)], out, 3, seed=7, workers=2, ray_address="local",
             progress=False)
    assert files_of(out) == files_of(dataset)


def test_a_rerun_redoes_only_what_is_missing_or_corrupt(dataset, room_file, tmp_path):
    import shutil

    out = tmp_path / "resumed"
    shutil.copytree(dataset, out)
    shutil.rmtree(out / "episode_00001")  # lost
    h5 = out / "episode_00002" / "sensors.h5"
    data = bytearray(h5.read_bytes())
    data[len(data) // 2] ^= 0xFF  # one flipped byte
    h5.write_bytes(bytes(data))
    (out / ".tmp-episode_00001-999").mkdir()  # a worker killed mid-episode
    kept = (out / "episode_00000" / "sensors.h5").stat().st_mtime_ns
    generate([load_scenario(room_file)], [str(room_file)], out, 3, seed=7, progress=False)
    assert files_of(out) == files_of(dataset)
    assert (out / "episode_00000" / "sensors.h5").stat().st_mtime_ns == kept  # verified, not redone


def test_kill_9_halfway_then_rerun_equals_an_uninterrupted_run(room_file, tmp_path):
    cmd = [sys.executable, "-m", "crowdsim.cli", "dataset", "generate", str(room_file), "--episodes", "4",
           "--seed", "3", "--duration", "1.2", "--quiet"]
    whole = tmp_path / "whole"
    subprocess.run([*cmd, "--out", str(whole)], check=True, capture_output=True)
    cut = tmp_path / "cut"
    proc = subprocess.Popen([*cmd, "--out", str(cut)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    manifest = cut / "manifest.json"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if manifest.exists() and len(json.loads(manifest.read_text())["episodes"]) >= 2:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = json.loads(manifest.read_text())["episodes"]
    assert 2 <= len(done) < 4  # killed halfway: some episodes complete, not all
    subprocess.run([*cmd, "--out", str(cut)], check=True, capture_output=True)
    assert files_of(cut) == files_of(whole)


def test_a_folder_of_something_else_or_another_command_is_refused(dataset, room_file, tmp_path, capsys):
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    assert main(["dataset", "generate", str(room_file), "--episodes", "3", "--out", str(other), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"--out {other}: not empty and holds no manifest.json" in err
    assert (other / "notes.txt").read_text() == "mine" and len(list(other.iterdir())) == 1
    before = files_of(dataset)
    assert main(["dataset", "generate", str(room_file), "--episodes", "4", "--seed", "7", "--out", str(dataset),
                 "--quiet"]) == 2
    assert "a dataset of another command" in capsys.readouterr().err
    assert files_of(dataset) == before
    for bad, message in ((["--episodes", "0"], "--episodes: expected at least 1, got 0"),
                         (["--episodes", "2", "--rate-scale", "2", "1"], "--rate-scale: expected LO HI with 0 <= LO "
                                                                         "<= HI, got 2 1"),
                         (["--episodes", "2", "--route-jitter", "-1"], "--route-jitter: expected a distance")):
        assert main(["dataset", "generate", str(room_file), *bad, "--out", str(tmp_path / "x"), "--quiet"]) == 2
        assert message in capsys.readouterr().err
        assert not (tmp_path / "x").exists()


def test_variations_are_drawn_per_episode_and_recorded(room_file):
    sc = load_scenario(room_file)
    jobs = plan([sc], 3, seed=1, duration=None, rate=(0.5, 1.5), density=(2.0, 2.0), route_jitter=0.5)
    factors = [j["variation"]["rate_scale"] for j in jobs]
    assert len(set(factors)) == 3 and all(0.5 <= f <= 1.5 for f in factors)
    for job, f in zip(jobs, factors):
        assert job["spec"]["sources"][0]["rate"] == pytest.approx(2.0 * f)
        assert job["spec"]["standing"][0]["count"] == 6  # 3 x 2
        offsets = np.array(job["variation"]["route_offsets"])
        assert offsets.shape == (3, 2) and (np.hypot(*offsets.T) <= 0.5).all() and (offsets != 0).any()
        assert np.allclose(np.array(job["spec"]["robot"]["route"]), np.array(sc["robot"]["route"]) + offsets[1:])
    # the rate draw comes first and alone decides it: adding other options leaves it as it was
    alone = plan([sc], 3, seed=1, duration=None, rate=(0.5, 1.5), density=None, route_jitter=0.0)
    assert [j["variation"]["rate_scale"] for j in alone] == factors
    # a waypoint that would come too near a wall stays where it was
    near = sc.replace(robot=sc.robot.replace(start=[0.5, 5.0, 0.0]))
    rng = np.random.default_rng(0)
    varied, drawn = vary(near, rng, None, None, 0.2)
    assert varied["robot"]["start"][:2] == (0.5, 5.0) and drawn["route_offsets"][0] == [0.0, 0.0]
    assert [split_of(k) for k in range(10)].count("train") == 8


def test_the_labels_agree_with_the_raw_data(dataset):
    ep = dataset / "episode_00000"
    persons = pq.read_table(ep / "persons.parquet").to_pydict()
    frame = np.array(persons["frame"])
    with h5py.File(ep / "sensors.h5", "r") as h5:
        scans = h5["lasers/front_laser"]
        assert scans["ranges"].shape == (15, 381) and scans["ranges"].dtype == np.float32
        assert scans["ranges"].chunks == (1, 381) and scans["ranges"].compression == "gzip"
        for k in range(15):
            ids = scans["person_id"][k]
            f = int(scans["frame"][k])
            rows = np.flatnonzero(frame == f)
            # the beams column counts, per person, the beams whose label is that person
            counts = {i: int((ids == i).sum()) for i in np.array(persons["id"])[rows]}
            assert [persons["front_laser.beams"][r] for r in rows] == [counts[persons["id"][r]] for r in rows]
        depth = h5["cameras/front_depth"]
        assert depth["depth"].shape[1:] == (24, 32) and depth["rgb"].shape[1:] == (24, 32, 3)
        assert depth["stamp"].shape[0] == 10  # 15 Hz over 0.6 s: k / 15 <= 0.6 s for k = 0 .. 9
        seg = depth["segmentation"][()]
    # a person the depth camera shows has a visible box around exactly their pixels, in the latest image
    last = int(np.flatnonzero(frame == frame.max())[0])
    shown = [i for i in np.unique(seg[-1]) if i >= 0]
    rows = {persons["id"][r]: r for r in range(last, len(frame))}
    for i in shown:
        v, u = np.nonzero(seg[-1] == i)
        box = [persons[f"front_depth.box_{c}"][rows[i]] for c in ("u0", "v0", "u1", "v1")]
        assert box == [u.min(), v.min(), u.max() + 1, v.max() + 1]
