"""``crowdsim dataset generate`` when things go wrong: what the fuzzer found (T07: --route-jitter on a robot without
a route; T08: an episode with an empty table), a frameless duration and an unusable --out refused before any work,
a full disk, an error or an interruption (SIGINT, SIGTERM, with one worker and with a pool): each leaves the folder
as ``kill -9`` would, tidied (the complete episodes and a manifest listing exactly them, no hidden temporary
folder, no worker left running), or as it was when no episode was complete. Short episodes of a small room."""

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml

import crowdsim.datasets.episode as episode_module
from crowdsim.cli import main
from crowdsim.datasets import Dataset
from crowdsim.datasets.episode import TRACKS_SCHEMA, EpisodeWriter, ParquetStream
from crowdsim.datasets.export import export_dataset
from crowdsim.datasets.generate import generate, vary
from crowdsim.datasets.layout import DatasetError, file_digest
from scenarios import load_scenario, scenario_from_dict
from scenarios.typed import plain
from test_dataset_generate import ROOM as GENERATE_ROOM

# test_dataset_generate's room, longer warm-up cut short and with one laser
ROOM = {**GENERATE_ROOM, "name": "robust_room", "warmup": 1.0, "duration": 1.0,
        "sensors": {"lasers": GENERATE_ROOM["sensors"]["lasers"][:1]}}
# the same room with a colour depth camera: an episode about ten times the bytes of one of ROOM
CAMERAS = {**ROOM, "name": "robust_room_cameras",
           "sensors": {**ROOM["sensors"], "depth_cameras": [{"name": "front_depth", "preset": "kinect_160",
                                                             "width": 64, "height": 48, "rate": 15.0, "rgb": True}]}}


@pytest.fixture(scope="module")
def room_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("scenario") / "robust_room.yaml"
    path.write_text(yaml.safe_dump(ROOM))
    return path


@pytest.fixture(scope="module")
def cameras_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("scenario") / "robust_room_cameras.yaml"
    path.write_text(yaml.safe_dump(CAMERAS))
    return path


def files_of(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def assert_tidy_dataset(folder, planned: int) -> list[str]:
    """The folder is what kill -9 would leave, tidied: a manifest listing exactly the episode folders there, every
    file of each as the manifest's checksums say, nothing hidden; returns the ids kept."""
    manifest = json.loads((folder / "manifest.json").read_text())
    kept = [e["id"] for e in manifest["episodes"]]
    assert sorted(p.name for p in folder.iterdir()) == sorted([*kept, "manifest.json"])  # no .tmp-* left
    for e in manifest["episodes"]:
        assert {p.name for p in (folder / e["id"]).iterdir()} == set(e["files"])
        for name, f in e["files"].items():
            assert file_digest(folder / e["id"] / name) == (f["size"], f["sha256"])
    assert manifest["episodes_planned"] == planned
    assert sorted(kept) == sorted(i for ids in manifest["splits"].values() for i in ids)
    return kept


def one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("crowdsim: error: "), err
    assert "Traceback" not in err
    return lines[0]


# --- T07: --route-jitter on a robot without a route -------------------------------------------------------------


def test_route_jitter_on_a_robot_without_a_route_moves_its_start_only(tmp_path, capsys):
    out = tmp_path / "T07"
    assert main(["dataset", "generate", "passers_by", "--episodes", "1", "--duration", "1", "--route-jitter", "0.1",
                 "--quiet", "--out", str(out)]) == 0
    assert_tidy_dataset(out, 1)
    entry = json.loads((out / "manifest.json").read_text())["episodes"][0]
    offsets = np.array(entry["variation"]["route_offsets"])
    assert offsets.shape == (1, 2) and 0 < np.hypot(*offsets[0]) <= 0.1  # the start's, and nothing else
    robot = json.loads((out / entry["id"] / "meta.json").read_text())["scenario"]["robot"]
    original = load_scenario("passers_by")["robot"]
    assert robot["start"][:2] == pytest.approx(np.add(original["start"][:2], offsets[0]))
    assert robot["start"][2] == original["start"][2]
    assert robot.get("route") is None and robot["goals"] == plain(original["goals"])  # its goals are its task: kept


def test_a_jittered_point_never_crosses_a_wall():
    sc = scenario_from_dict(ROOM, source="<test>")
    for seed in range(40):  # far jitters land outside the room or in it beyond a wall's reach: only the latter move
        varied, drawn = vary(sc, np.random.default_rng(seed), None, None, 20.0)
        points = np.array([varied["robot"]["start"][:2], *varied["robot"]["route"]])
        assert ((points > 0.725) & (points < np.array([14, 10]) - 0.725)).all()  # radius + clearance inside
        assert len(drawn["route_offsets"]) == 3


# --- T08: an empty table is a valid table -----------------------------------------------------------------------


@pytest.mark.parametrize("extra", [[], ["--density-scale", "2", "2"]], ids=["seed001_room_1", "density_scale_2"])
def test_an_episode_whose_tracks_table_is_empty_is_written_and_read_back(tmp_path, capsys, extra):
    out = tmp_path / "T08"
    assert main(["dataset", "generate", "seed001_room_1", "--episodes", "1", "--duration", "1", "--quiet", *extra,
                 "--out", str(out)]) == 0
    assert_tidy_dataset(out, 1)
    ep = Dataset(out).episodes()[0]
    tracks = pq.ParquetFile(ep.folder / "tracks.parquet")
    assert tracks.metadata.num_rows == 0 and tracks.num_row_groups == 0  # no track within a second
    assert tracks.schema_arrow.remove_metadata().equals(TRACKS_SCHEMA)  # the schema all the same
    assert ep.table("tracks").num_rows == 0 and ep.table("tracks").schema.names == TRACKS_SCHEMA.names
    frames = list(ep.iter_frames("tracks", ["id", "x"]))
    assert [f for f, _ in frames] == list(range(ep.frames)) and ep.frames > 0
    assert all(len(rows["id"]) == 0 and rows["x"].dtype == np.float64 for _, rows in frames)
    assert ep.table("persons").num_rows > 0  # the other tables as ever
    summary = export_dataset(out, "motchallenge", tmp_path / "mot")
    assert summary["rows"]["tracks"] == 0 and summary["rows"]["gt"] > 0
    assert (tmp_path / "mot" / "train" / "episode_00000" / "tracks.txt").read_text() == ""


def test_a_row_group_of_frames_without_rows_is_left_out(tmp_path, monkeypatch):
    monkeypatch.setattr(episode_module, "ROW_GROUP_FRAMES", 2)
    schema = pa.schema([("frame", pa.int32()), ("x", pa.float64())])
    stream = ParquetStream(tmp_path / "t.parquet", schema, "gzip")
    for frame, n in enumerate([1, 0, 0, 0, 2]):  # frames 2 and 3, a row group's worth, have no row
        stream.add({"frame": np.full(n, frame, np.int32), "x": np.arange(n, dtype=float)})
        stream.end_frame()
    stream.close()
    f = pq.ParquetFile(tmp_path / "t.parquet")
    assert f.num_row_groups == 2 and f.read().column("frame").to_pylist() == [0, 4, 4]


# --- checked before any work ------------------------------------------------------------------------------------


def test_a_duration_that_holds_no_frame_is_refused_before_any_work(room_file, tmp_path, capsys):
    out = tmp_path / "ds"
    assert main(["dataset", "generate", str(room_file), "--episodes", "2", "--duration", "0.01", "--quiet",
                 "--out", str(out)]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert "--duration 0.01" in line and "no frame" in line and "dt 0.04 s" in line
    assert not out.exists()


def test_a_variation_past_what_the_file_may_hold_is_refused_before_any_work(room_file, tmp_path, capsys):
    out = tmp_path / "ds"
    assert main(["dataset", "generate", str(room_file), "--episodes", "2", "--density-scale", "10", "10", "--quiet",
                 "--out", str(out)]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert line.startswith("crowdsim: error: --density-scale 10 10: robust_room as episode_00000 varies it: "
                           "standing[0].count: ")  # 3 standing persons times 10
    assert not out.exists()


def _unusable(tmp_path):
    a_file = tmp_path / "notes.txt"
    a_file.write_text("mine")
    cases = {"a_file": (a_file, "not a directory"), "under_a_file": (a_file / "ds", "is a file"),
             "name_too_long": (tmp_path / ("d" * 300), ""),
             "under_proc": (Path("/proc/crowdsim_dataset_test"), "")}
    return cases


@pytest.mark.parametrize("case", ["a_file", "under_a_file", "name_too_long", "under_proc"])
def test_an_unusable_out_is_one_error_naming_it_before_any_work(room_file, tmp_path, capsys, case):
    out, words = _unusable(tmp_path)[case]
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["dataset", "generate", str(room_file), "--episodes", "2", "--quiet", "--out", str(out)]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert line.startswith(f"crowdsim: error: --out {str(out)[:60]}") and words in line
    assert sorted(p.name for p in tmp_path.iterdir()) == before and (tmp_path / "notes.txt").read_text() == "mine"
    assert not os.path.lexists(out) or out.is_file()


@pytest.mark.parametrize("out, words", [("", "empty"), ("a\0b", "NUL")])
def test_an_empty_or_nul_out_is_refused(room_file, out, words):
    with pytest.raises(DatasetError, match=words):
        generate([load_scenario(room_file)], [str(room_file)], out, 1, progress=False)


# --- errors, a full disk and interruptions in this process ------------------------------------------------------


def _fail_in(monkeypatch, episode: str, exc: BaseException) -> None:
    """EpisodeWriter.write raises ``exc`` in ``episode``'s third frame."""
    write = EpisodeWriter.write

    def failing(self, frame):
        if self.out.name.startswith(f".tmp-{episode}-") and self.frames == 2:
            raise exc
        write(self, frame)

    monkeypatch.setattr(EpisodeWriter, "write", failing)


def _full_statvfs(monkeypatch, episode: str) -> None:
    """The disk full as soon as ``episode`` is being written."""
    real = os.statvfs

    def statvfs(path):
        if f".tmp-{episode}-" in str(path):
            return SimpleNamespace(f_bavail=10, f_frsize=4096)
        return real(path)

    monkeypatch.setattr(episode_module.os, "statvfs", statvfs)


@pytest.mark.parametrize("how", ["statvfs", "parquet_oserror", "hdf5_runtimeerror"])
def test_a_full_disk_is_one_error_keeping_the_complete_episodes(room_file, tmp_path, monkeypatch, how):
    if how == "statvfs":
        _full_statvfs(monkeypatch, "episode_00001")
    elif how == "parquet_oserror":  # pyarrow's own error
        _fail_in(monkeypatch, "episode_00001", OSError(errno.ENOSPC, "Error writing bytes to file. Detail: "
                                                                     "[errno 28] No space left on device"))
    else:  # HDF5's, as h5py raises it
        _fail_in(monkeypatch, "episode_00001", RuntimeError("Can't write data (file write failed: errno = 28, "
                                                            "error message = 'No space left on device')"))
    sc = [load_scenario(room_file)]
    out = tmp_path / "ds"
    with pytest.raises(DatasetError) as e:
        generate(sc, [str(room_file)], out, 3, seed=2, progress=False)
    assert str(e.value) == (f"--out {out}: No space left on device while writing episode_00001, whose partial "
                            f"files were removed; kept 1 of 3 episodes in {out}, each complete and listed in "
                            "manifest.json; the same command completes the dataset")
    assert assert_tidy_dataset(out, 3) == ["episode_00000"]
    monkeypatch.undo()
    generate(sc, [str(room_file)], out, 3, seed=2, progress=False)  # room again: the same command completes it
    whole = tmp_path / "whole"
    generate(sc, [str(room_file)], whole, 3, seed=2, progress=False)
    assert files_of(out) == files_of(whole)


@pytest.mark.parametrize("exc", [KeyboardInterrupt(), RuntimeError("boom")], ids=["interrupt", "error"])
def test_an_interruption_or_an_error_keeps_the_complete_episodes_and_says_so(room_file, tmp_path, monkeypatch,
                                                                              exc):
    _fail_in(monkeypatch, "episode_00001", exc)
    out = tmp_path / "ds"
    with pytest.raises(type(exc)) as e:
        generate([load_scenario(room_file)], [str(room_file)], out, 3, progress=False)
    assert e.value is exc  # the same exception goes on (the CLI's Stopped keeps its signal) ...
    assert exc.kept == (f"kept 1 of 3 episodes in {out}, each complete and listed in manifest.json; the same "
                        "command completes the dataset")  # ... with what was kept, for the CLI's line
    assert assert_tidy_dataset(out, 3) == ["episode_00000"]


@pytest.mark.parametrize("existing", [False, True], ids=["new_folder", "empty_folder"])
def test_with_no_complete_episode_the_folder_is_as_it_was(room_file, tmp_path, monkeypatch, existing):
    _fail_in(monkeypatch, "episode_00000", KeyboardInterrupt())
    out = tmp_path / "new" / "parent" / "ds"
    if existing:
        out.mkdir(parents=True)
    with pytest.raises(KeyboardInterrupt) as e:
        generate([load_scenario(room_file)], [str(room_file)], out, 2, progress=False)
    assert e.value.kept.startswith("no episode was complete, so nothing was kept")
    if existing:
        assert out.is_dir() and not any(out.iterdir())
    else:
        assert not (tmp_path / "new").exists()  # the folders it made are gone too


# --- a real process: a file size limit, SIGINT and SIGTERM ------------------------------------------------------


def _command(*args, workers: int = 1):
    return [sys.executable, "-m", "crowdsim.cli", "dataset", "generate", *map(str, args), "--quiet",
            "--workers", str(workers)]


def test_a_file_size_limit_in_a_real_process_is_one_error_keeping_the_complete_episodes(room_file, cameras_file,
                                                                                         tmp_path):
    import resource

    def limit():  # as `ulimit -f` would: a room episode's files fit, a camera episode's sensors.h5 does not
        resource.setrlimit(resource.RLIMIT_FSIZE, (600_000, 600_000))

    out = tmp_path / "ds"
    cmd = _command(room_file, cameras_file, "--episodes", 3, "--duration", 1, "--out", out)
    r = subprocess.run(cmd, preexec_fn=limit, capture_output=True, text=True, timeout=300)
    assert r.returncode == 2
    line = one_error_line(r.stderr)
    assert (f"--out {out}: File too large (over the file size limit, ulimit -f) while writing episode_00001, whose "
            f"partial files were removed; kept 1 of 3 episodes in {out}") in line
    assert assert_tidy_dataset(out, 3) == ["episode_00000"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)  # the same command, no limit
    assert r.returncode == 0, r.stderr
    assert len(assert_tidy_dataset(out, 3)) == 3


def _workers_of(pid: int) -> list[int]:
    """The pool workers (spawned interpreters) whose parent is ``pid``."""
    found = []
    for entry in os.listdir("/proc"):
        try:
            with open(f"/proc/{entry}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                spawned = b"spawn_main" in f.read()
        except (OSError, ValueError, IndexError):
            continue
        if ppid == pid and spawned:
            found.append(int(entry))
    return found


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _stop_halfway(room_file, tmp_path, signum: int, workers: int):
    """Start the command, wait for its first complete episode, send ``signum`` to its main process (only); return
    the finished process, the folder, the workers it had and the command."""
    out = tmp_path / "ds"
    cmd = _command(room_file, "--episodes", 8, "--duration", 2, "--out", out, workers=workers)
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    manifest = out / "manifest.json"
    deadline = time.monotonic() + 180
    try:
        while proc.poll() is None and time.monotonic() < deadline:
            try:
                if json.loads(manifest.read_text())["episodes"]:
                    break
            except (OSError, ValueError, KeyError):
                pass
            time.sleep(0.02)
        assert proc.poll() is None, proc.communicate()
        workers_seen = _workers_of(proc.pid)
        assert len(workers_seen) == (workers if workers > 1 else 0)
        os.kill(proc.pid, signum)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    deadline = time.monotonic() + 30
    while any(_alive(p) for p in workers_seen) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_alive(p) for p in workers_seen)  # the workers were ended
    return proc, err, out, cmd


@pytest.mark.parametrize("workers", [1, 2])
def test_sigint_stops_generate_keeping_the_complete_episodes(room_file, tmp_path, workers):
    proc, err, out, cmd = _stop_halfway(room_file, tmp_path, signal.SIGINT, workers)
    assert proc.returncode != 0, err
    kept = assert_tidy_dataset(out, 8)
    assert 1 <= len(kept) < 8
    if workers == 1:  # the same command completes what is left
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        assert len(assert_tidy_dataset(out, 8)) == 8


@pytest.mark.parametrize("workers", [1, 2])
def test_sigterm_stops_generate_keeping_the_complete_episodes_with_one_line(room_file, tmp_path, workers):
    proc, err, out, cmd = _stop_halfway(room_file, tmp_path, signal.SIGTERM, workers)
    # ended by the signal, as its caller expects
    assert proc.returncode in (-signal.SIGTERM, 128 + signal.SIGTERM), err
    kept = assert_tidy_dataset(out, 8)
    assert 1 <= len(kept) < 8
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("crowdsim: ")
    assert f"kept {len(kept)} of 8 episodes in {out}" in lines[0]
