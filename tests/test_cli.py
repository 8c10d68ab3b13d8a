"""The ``crowdsim`` command: one clear error line and exit code 2 on bad input, nothing half-written, nothing of
the user's overwritten, and a complete run directory on success."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from crowdsim.cli import main
from crowdsim.outdir import RunDirError
from crowdsim.run import run
from evaluation.columns import GROUNDTRUTH, TRACKS
from scenarios import bundled_scenarios, load_scenario

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

# A 12 m x 10 m room, one source walking people across it, a standing pair (so every frame has ground truth), a
# parked robot with two lasers; 2 s of warm-up and 2 s recorded.
TINY = """\
name: tiny_room
description: a short smoke-test run
seed: 3
warmup: 2
duration: 2
map:
  walls:
    - [[0, 0], [12, 0], [12, 10], [0, 10], [0, 0]]
waypoints:
  a: {position: [2, 5]}
  b: {position: [10, 5]}
routes:
  r: {waypoints: [a, b]}
sources:
  - {position: [2, 5], rate: 2.0, routes: {r: 1.0}}
standing:
  - {position: [6, 7.5], count: 2}
robot:
  start: [6, 2, 1.5707963]
sensors:
  lasers:
    - {name: front_laser, mount: [0.25, 0, 0]}
    - {name: rear_laser, mount: [-0.25, 0, 3.141592653589793]}
"""


def crowdsim_command() -> list[str]:
    beside = Path(sys.executable).parent / "crowdsim"
    if beside.is_file():
        return [str(beside)]
    found = shutil.which("crowdsim")
    return [found] if found else [sys.executable, "-m", "crowdsim.cli"]


def listing(path: Path) -> set[str]:
    return {p.name for p in path.iterdir()}


def one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("crowdsim: error: "), err
    return lines[0]


def test_scenarios_lists_bundled_with_description():
    result = subprocess.run(crowdsim_command() + ["scenarios"], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    lines = {line.split()[0]: line for line in result.stdout.splitlines() if line.strip()}
    description = bundled_scenarios()["airport_disembarkation"]
    assert description.startswith("Passengers leave an aircraft through a jet bridge")
    assert "airport_disembarkation" in lines
    assert lines["airport_disembarkation"].split(None, 1)[1] == description


def test_run_bad_yaml_exits_2_and_writes_nothing(tmp_path, monkeypatch, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(TINY + "crowd:\n  radiuss: 0.3\n")
    out = tmp_path / "out"
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(bad), "--out", str(out), "--quiet"]) == 2
    captured = capsys.readouterr()
    line = one_error_line(captured.err)
    assert str(bad) in line and "crowd.radiuss" in line and "unknown key" in line and "expected one of" in line
    assert captured.out == ""
    assert not out.exists()
    # without --out neither: no default runs/ directory appears
    assert main(["run", str(bad), "--quiet"]) == 2
    one_error_line(capsys.readouterr().err)
    assert listing(tmp_path) == {"bad.yaml"}


def test_run_into_non_empty_dir_is_refused_and_untouched(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    target = tmp_path / "results"
    target.mkdir()
    mine = target / "notes.txt"
    mine.write_text("my precious notes\n")
    before = mine.stat()
    assert main(["run", "airport_disembarkation", "--out", str(target), "--quiet"]) == 2
    captured = capsys.readouterr()
    line = one_error_line(captured.err)
    assert str(target) in line and "not empty" in line
    assert captured.out == ""
    assert listing(target) == {"notes.txt"}
    assert mine.read_text() == "my precious notes\n"
    assert (mine.stat().st_mtime_ns, mine.stat().st_size) == (before.st_mtime_ns, before.st_size)
    assert listing(tmp_path) == {"results"}  # no temporary directory beside it


def test_run_onto_an_existing_file_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    target = tmp_path / "results"
    target.write_text("not a directory\n")
    assert main(["run", "airport_disembarkation", "--out", str(target), "--quiet"]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert str(target) in line
    assert target.read_text() == "not a directory\n"
    assert listing(tmp_path) == {"results"}


def test_run_function_refuses_non_empty_dir_before_writing(tmp_path):
    # the library entry point checks as well, before it makes its temporary directory
    target = tmp_path / "results"
    target.mkdir()
    (target / "keep").write_text("x")
    with pytest.raises(RunDirError, match="not empty"):
        run(load_scenario("airport_disembarkation"), target, progress=False)
    assert listing(tmp_path) == {"results"} and listing(target) == {"keep"}


def test_run_unknown_scenario_names_the_bundled_ones(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "NOT_A_SCENARIO"]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert "NOT_A_SCENARIO" in line and "bundled" in line
    for name in bundled_scenarios():
        assert name in line
    assert listing(tmp_path) == set()


def test_run_negative_seed_names_seed(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "airport_disembarkation", "--seed", "-3"]) == 2
    line = one_error_line(capsys.readouterr().err)
    # the flag is at fault, not the file (the bundled file's own seed is fine)
    assert "--seed -3: " in line and "at least 0" in line and "airport_disembarkation.yaml" not in line
    assert listing(tmp_path) == set()


def _tiny(tmp_path) -> Path:
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    return path


def test_short_run_writes_a_complete_run_directory(tmp_path, capsys):
    scenario = _tiny(tmp_path)
    out = tmp_path / "out"
    assert main(["run", str(scenario), "--out", str(out), "--quiet"]) == 0
    captured = capsys.readouterr()
    assert listing(tmp_path) == {"tiny.yaml", "out"}  # the temporary directory was moved, not left behind
    assert {"metrics.json", "groundtruth.csv", "tracks.csv", "detections.csv", "robot.csv", "scenario.yaml",
            "summary.md", "topdown.png", "visibility.csv", "relations.csv", "groups.csv"} <= listing(out)
    # the resolved scenario is a scenario file that loads to the same scenario
    again, first = load_scenario(str(out / "scenario.yaml")), load_scenario(str(scenario))
    assert again.source != first.source and again.replace(source=first.source) == first
    robot = np.loadtxt(out / "robot.csv", delimiter=",", skiprows=1)
    assert (out / "robot.csv").read_text().startswith("frame,t,x,y,yaw,odom_x,odom_y,odom_yaw\n")
    # perfect odometry: the odometry pose is the true pose relative to the start, (6, 2) facing +y
    np.testing.assert_allclose(robot[:, 5], robot[:, 3] - 2.0, atol=2e-4)
    np.testing.assert_allclose(robot[:, 6], -(robot[:, 2] - 6.0), atol=2e-4)
    detections = np.loadtxt(out / "detections.csv", delimiter=",", skiprows=1)
    assert detections.shape[1] == 6 and len(detections) > 0 and set(detections[:, 0]) <= set(robot[:, 0])
    assert "recording.rrd" not in listing(out)
    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o777 & ~umask  # an ordinary directory, not mkdtemp's private 0700

    metrics = json.loads((out / "metrics.json").read_text())
    assert {"scenario", "seed", "duration_s", "frames", "tracking", "timing"} <= set(metrics)
    assert {"mota", "motp_m", "fp", "fn", "id_switches", "gt", "fp_rate", "miss_rate"} <= set(metrics["tracking"])
    assert {"wall_s", "realtime_factor", "tracker_hz"} <= set(metrics["timing"])
    assert metrics["scenario"] == "tiny_room" and metrics["seed"] == 3 and metrics["duration_s"] == 2.0
    assert metrics["frames"] == 50  # 2 s of two 25 Hz lasers scanning together
    assert metrics["cameras"] == {} and "Cameras" not in captured.out
    assert metrics["tracking"]["gt"] > 0

    for columns in (GROUNDTRUTH, TRACKS):
        lines = (out / columns.file).read_text().splitlines()
        assert lines[0] == columns.header
        assert all(len(row.split(",")) == len(columns) for row in lines[1:])
    assert GROUNDTRUTH.header == "frame,t,id,x,y,vx,vy,range,in_range,beams,visible,visible_seed000,group"
    assert TRACKS.header == "frame,t,id,x,y,vx,vy"
    gt_rows = [[float(v) for v in r.split(",")] for r in (out / "groundtruth.csv").read_text().splitlines()[1:]]
    # visible is 1 exactly where at least one beam hit the person; in_range where within the 20 m range
    assert all((r[9] > 0) == (r[10] == 1) and (r[7] <= 20.0) == (r[8] == 1) for r in gt_rows)
    assert len({r[0] for r in gt_rows}) == metrics["frames"]
    # the two standing persons are a static group; the walkers from the source walk alone (no group sizes given)
    # (odom: 5.5 m ahead of the robot's start, which faces +y from (6, 2))
    grouped = {(r[2], r[12]) for r in gt_rows if r[12] >= 0}
    assert len(grouped) == 2 and len({g for _, g in grouped}) == 1
    assert all(abs(r[3] - 5.5) < 1.0 and abs(r[4]) < 1.0 for r in gt_rows if r[12] >= 0)
    # the rows that count: in range and visible
    assert sum(r[8] == 1 and r[10] == 1 for r in gt_rows) == metrics["tracking"]["gt"]
    stamps = [r[1] for r in gt_rows]
    assert 2.0 < min(stamps) and max(stamps) <= 4.0 + 1e-6  # recorded after the 2 s warm-up only
    # per sensor frame, each person in the laser's view or hit by it, with the beams that hit them; the ground
    # truth's beams are their sum over the lasers (the rear one faces the empty strip behind the robot)
    lines = (out / "visibility.csv").read_text().splitlines()
    assert lines[0] == "frame,t,id,sensor,amount,in_view,occluded"
    seen = [line.split(",") for line in lines[1:]]
    assert {r[3] for r in seen} == {"front_laser"} and {int(r[0]) for r in seen} == set(range(50))
    beams = {}
    for frame, _, pid, _, amount, in_view, occluded in seen:
        beams[frame, pid] = beams.get((frame, pid), 0) + int(amount)
        assert occluded == str(int(in_view == "1" and amount == "0"))
    assert all(beams.get((f"{r[0]:.0f}", f"{r[2]:.0f}"), 0) == r[9] for r in gt_rows)
    assert sum(beams.values()) == sum(r[9] for r in gt_rows) > 0

    assert (out / "summary.md").read_text().startswith("# tiny_room")
    png = (out / "topdown.png").read_bytes()
    assert png[:8] == PNG_MAGIC and len(png) > 1000

    header = next(line for line in captured.out.splitlines() if line.startswith("|"))
    columns = [c.strip() for c in header.strip("|").split("|")]
    assert columns[0] == "MOTA"
    assert str(out) in captured.out


def test_short_run_with_rrd_writes_a_recording(tmp_path, capsys):
    scenario = _tiny(tmp_path)
    out = tmp_path / "out"
    assert main(["run", str(scenario), "--out", str(out), "--quiet", "--rrd", "--duration", "1"]) == 0
    capsys.readouterr()
    rrd = out / "recording.rrd"
    assert rrd.is_file() and rrd.stat().st_size > 0
    assert json.loads((out / "metrics.json").read_text())["duration_s"] == 1.0
    assert listing(tmp_path) == {"tiny.yaml", "out"}


@pytest.mark.parametrize("gl", ["as chosen", "disable"])
def test_a_camera_run_says_which_renderer_drew_the_cameras(gl, tmp_path, monkeypatch, capsys):
    scenario = tmp_path / "cams.yaml"
    scenario.write_text(TINY + """\
  depth_cameras:
    - {name: front_depth, preset: kinect_160}
  wall_cameras:
    - {name: corner_cam, position: [0.3, 0.3, 2.8], yaw: 0.6, pitch: 0.45}
""")
    import sensors  # noqa: F401 (it chooses MuJoCo's GL backend: egl, else osmesa)

    backend = os.environ["MUJOCO_GL"]
    if gl == "disable":  # no GL context: the cameras fall back to ray casting
        monkeypatch.setenv("MUJOCO_GL", gl)
        backend = "raycast"
    assert main(["run", str(scenario), "--out", str(tmp_path / "out"), "--quiet", "--duration", "0.2"]) == 0
    line = f"Cameras rendered by {backend}: front_depth, corner_cam."
    assert line in capsys.readouterr().out.splitlines()
    assert json.loads((tmp_path / "out" / "metrics.json").read_text())["cameras"] == {"front_depth": backend,
                                                                                      "corner_cam": backend}
    assert line in (tmp_path / "out" / "summary.md").read_text()
    # each camera's ground truth at its own images' times: due every 1/15 and 1/10 s from the end of the 2 s
    # warm-up, taken at the first 0.04 s tick at or after
    rows = [r.split(",") for r in (tmp_path / "out" / "visibility.csv").read_text().splitlines()[1:]]
    assert sorted({r[1] for r in rows if r[3] == "front_depth"}) == ["2.04", "2.08", "2.16", "2.20"]
    assert sorted({r[1] for r in rows if r[3] == "corner_cam"}) == ["2.04", "2.12", "2.20"]
    assert all(0 <= float(r[4]) <= 1 for r in rows if r[3] in ("front_depth", "corner_cam"))


def test_run_into_an_existing_empty_dir_is_allowed(tmp_path, capsys):
    scenario = _tiny(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    assert main(["run", str(scenario), "--out", str(out), "--quiet", "--duration", "0.4"]) == 0
    capsys.readouterr()
    assert "metrics.json" in listing(out)
    assert listing(tmp_path) == {"tiny.yaml", "out"}
    assert os.path.isdir(out)


@pytest.mark.parametrize("exc", [RuntimeError("boom"), KeyboardInterrupt()], ids=["error", "interrupt"])
def test_failed_run_leaves_nothing_half_written(tmp_path, monkeypatch, exc):
    def fail_midway(scenario, tmp, rrd, progress):
        (tmp / "groundtruth.csv").write_text(TRACKS.header + "\n")  # something half-written
        raise exc

    monkeypatch.setattr("crowdsim.run._simulate", fail_midway)
    out = tmp_path / "deep" / "er" / "out"  # parents the run creates go too
    with pytest.raises(type(exc)):
        run(load_scenario(str(_tiny(tmp_path))), out, progress=False)
    assert not out.exists()
    assert listing(tmp_path) == {"tiny.yaml"}


def test_validate_scenario_says_what_it_holds_or_names_the_fault(tmp_path, capsys):
    assert main(["validate-scenario", "airport_disembarkation"]) == 0
    out = capsys.readouterr().out
    assert "valid scenario 'airport_disembarkation'" in out and "2 laser(s), 0 depth camera(s)" in out
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nrobot: {start: [1, 1, 0]}\nsensors: {lasers: [{name: a, mount: [0, 0, 0]}]}\n"
                   "sources: [{position: [2, 2], rate: -1, routes: {}}]\n")
    assert main(["validate-scenario", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"crowdsim: error: {bad}: sources[0].rate: expected a value at least 0.0")


def test_pedsim_warnings_print_as_one_line_naming_file_and_line(tmp_path, capsys):
    path = tmp_path / "lift.xml"
    path.write_text('<?xml version="1.0"?>\n<scenario>\n'
                    '  <obstacle x1="0" y1="0" x2="20" y2="0"/>\n'
                    '  <elevator id="lift" x="1" y="1"/>\n'
                    '  <agent x="5" y="5" n="1" dx="0" dy="0" type="2"><addwaypoint id="a"/></agent>\n'
                    '  <waypoint id="a" x="15" y="5" r="1"/>\n'
                    '</scenario>\n')
    assert main(["validate-scenario", str(path)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [f"crowdsim: warning: {path}:4: <elevator id='lift'> is not a PedSim scenario element; ignored"]
