"""``crowdsim evaluate``: any tracker's output scored from CSV files, a run's own files giving its metrics.json
exactly, the occlusion and range options, MOTChallenge export, and one clear error on bad input."""

import json

import numpy as np
import pytest

from crowdsim.cli import main
from test_cli import _tiny, one_error_line

GT = "frame,t,id,x,y,range,in_range,visible\n"
TRACKS = "frame,t,id,x,y,vx,vy\n"


def write(path, text):
    path.write_text(text)
    return str(path)


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("run")
    out = tmp / "out"
    assert main(["run", str(_tiny(tmp)), "--out", str(out), "--quiet"]) == 0
    return out


def test_evaluate_reproduces_the_runs_metrics_exactly(tiny_run, tmp_path, capsys):
    js = tmp_path / "m.json"
    assert main(["evaluate", "--gt", str(tiny_run / "groundtruth.csv"), "--tracks", str(tiny_run / "tracks.csv"),
                 "--json", str(js)]) == 0
    assert json.loads(js.read_text())["tracking"] == json.loads((tiny_run / "metrics.json").read_text())["tracking"]
    assert capsys.readouterr().out.startswith("| MOTA |")


def test_occlusion_range_and_threshold_options(tmp_path, capsys):
    # two frames; person 1 visible and tracked 0.5 m off; person 2 occluded in frame 0 and matched by track 20;
    # person 3 at 15 m from the robot, visible, untracked
    gt = write(tmp_path / "gt.csv", GT + "0,0,1,0,0,2,1,1\n0,0,2,5,0,5,1,0\n0,0,3,15,0,15,1,1\n"
                                         "1,0.1,1,0,0,2,1,1\n1,0.1,2,5,0,5,1,1\n1,0.1,3,15,0,15,1,1\n")
    tracks = write(tmp_path / "tr.csv", TRACKS + "0,0,10,0.5,0,0,0\n0,0,20,5,0,0,0\n1,0.1,10,0.5,0,0,0\n")

    def score(*extra):
        js = tmp_path / "s.json"
        js.unlink(missing_ok=True)
        assert main(["evaluate", "--gt", gt, "--tracks", tracks, "--json", str(js), *extra]) == 0
        return json.loads(js.read_text())["tracking"]

    s = score()
    # counted: 1 (twice), 3 (twice), 2 in frame 1 = 5; matches: 1 twice; track 20 matched the occluded person 2
    # in frame 0: no FP; misses: 3 twice and 2 in frame 1
    assert (s["gt"], s["matches"], s["fp"], s["fn"]) == (5, 2, 0, 3)
    s = score("--no-occlusion")  # person 2 counts in frame 0 too, matched by track 20
    assert (s["gt"], s["matches"], s["fp"], s["fn"]) == (6, 3, 0, 3)
    s = score("--max-range", "12")  # person 3 ignored
    assert (s["gt"], s["matches"], s["fn"]) == (3, 2, 1)
    s = score("--threshold", "0.3")  # 0.5 m off is no match any more
    assert (s["matches"], s["fp"], s["fn"]) == (0, 2, 5)
    assert s["threshold_m"] == 0.3


def test_motchallenge_export(tmp_path, capsys):
    gt = write(tmp_path / "gt.csv", GT + "4,0,1,1.5,-2,2,1,1\n5,0,1,1.5,-2,2,1,0\n")
    tracks = write(tmp_path / "tr.csv", TRACKS + "5,0.1,7,1.25,-2,0,0\n")
    assert main(["evaluate", "--gt", gt, "--tracks", tracks, "--motchallenge", str(tmp_path / "mot")]) == 0
    # frames from 1 at the first frame of either file; the consider flag 0 for the occluded row
    assert (tmp_path / "mot" / "gt.txt").read_text().splitlines() == [
        "1,1,-1,-1,-1,-1,1,1.5000,-2.0000,0", "2,1,-1,-1,-1,-1,0,1.5000,-2.0000,0"]
    assert (tmp_path / "mot" / "tracks.txt").read_text().splitlines() == ["2,7,-1,-1,-1,-1,1,1.2500,-2.0000,0"]


@pytest.mark.parametrize("content, expect", [
    ("frame,id,x\n0,1,2\n", "lacks column(s) y"),
    ("frame,id,x,y\n0,1,2\n", "expected 4 numbers per row"),
    ("frame,id,x,y,visible\n0,1,2,3,1\n0,1,4,5,1\n", "id 1 appears twice in frame 0"),
    ("frame,id,x,y\n0.5,1,2,3\n", "column frame must hold whole numbers"),
])
def test_bad_ground_truth_gets_one_clear_error(tmp_path, capsys, content, expect):
    gt = write(tmp_path / "gt.csv", content)
    tracks = write(tmp_path / "tr.csv", TRACKS)
    assert main(["evaluate", "--gt", gt, "--tracks", tracks]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert str(tmp_path / "gt.csv") in line and expect in line


def test_existing_json_is_not_overwritten_and_missing_columns_for_options_are_named(tmp_path, capsys):
    gt = write(tmp_path / "gt.csv", "frame,id,x,y\n0,1,0,0\n")
    tracks = write(tmp_path / "tr.csv", TRACKS)
    js = write(tmp_path / "mine.json", "keep me")
    assert main(["evaluate", "--gt", gt, "--tracks", tracks, "--json", js]) == 2
    assert "already exists" in one_error_line(capsys.readouterr().err)
    assert (tmp_path / "mine.json").read_text() == "keep me"
    assert main(["evaluate", "--gt", gt, "--tracks", tracks, "--max-range", "12"]) == 2
    assert "needs a column 'range'" in one_error_line(capsys.readouterr().err)
    assert main(["evaluate", "--gt", gt, "--tracks", tracks, "--visible-column", "visible_seed000"]) == 2
    assert "no column 'visible_seed000'" in one_error_line(capsys.readouterr().err)
    assert main(["evaluate", "--gt", str(tmp_path / "nope.csv"), "--tracks", tracks]) == 2
    assert "nope.csv: cannot be read" in one_error_line(capsys.readouterr().err)
    np.testing.assert_equal(sorted(p.name for p in tmp_path.iterdir()), ["gt.csv", "mine.json", "tr.csv"])


def test_runs_are_summed_up_as_mean_and_sample_standard_deviation(tmp_path, capsys):
    # run a: one person tracked in both frames (MOTA 1); run b: tracked in one of two frames (MOTA 0.5)
    for name, tracks in (("a", "0,0,10,0,0,0,0\n1,0.1,10,0,0,0,0\n"), ("b", "0,0,10,0,0,0,0\n")):
        (tmp_path / name).mkdir()
        write(tmp_path / name / "groundtruth.csv", GT + "0,0,1,0,0,2,1,1\n1,0.1,1,0,0,2,1,1\n")
        write(tmp_path / name / "tracks.csv", TRACKS + tracks)
    js = tmp_path / "runs.json"
    assert main(["evaluate", "--runs", str(tmp_path / "a"), str(tmp_path / "b"), "--json", str(js)]) == 0
    got = json.loads(js.read_text())
    # mean 0.75; sample sd sqrt((0.25^2 + 0.25^2) / (2 - 1))
    assert got["mean"]["mota"] == 0.75 and got["sd"]["mota"] == pytest.approx(np.sqrt(0.125), abs=1e-12)
    assert [r["mota"] for r in got["runs"]] == [1.0, 0.5]
    out = capsys.readouterr().out
    assert "| mean of 2 | 75.0 |" in out and "| sd | 35.4 |" in out
    assert main(["evaluate", "--runs", str(tmp_path / "a"), "--gt", "x.csv"]) == 2
    assert "expected either --gt" in one_error_line(capsys.readouterr().err)
