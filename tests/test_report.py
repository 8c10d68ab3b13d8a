"""``crowdsim report``: the report of a run holds its metrics exactly, marks every ID switch and false positive
the evaluation counted, writes its figures, and refuses to overwrite."""

import json

from crowdsim.cli import main
from evaluation.io import load_sequence
from evaluation.report import _events
from test_cli import PNG_MAGIC, _tiny, one_error_line


def test_report_of_a_run(tmp_path, capsys):
    run = tmp_path / "run"
    assert main(["run", str(_tiny(tmp_path)), "--out", str(run), "--quiet"]) == 0
    assert main(["report", str(run)]) == 0
    report = run / "report"
    metrics = json.loads((run / "metrics.json").read_text())["tracking"]
    figures = json.loads((report / "tracking.json").read_text())
    assert figures["tracking"] == metrics
    assert figures["seed001"]["threshold_m"] == 0.3
    text = (report / "report.md").read_text()
    assert f"| {100 * metrics['mota']:.1f}% |" in text and "## Seed 001's set at 0.3 m" in text
    for name in ("topdown_tracking.png", "counts.png", "over_time.png"):
        png = (report / name).read_bytes()
        assert png[:8] == PNG_MAGIC and len(png) > 10000
        assert f"]({name})" in text
    svg = (report / "topdown.svg").read_text()
    assert svg.startswith("<svg") and "<animateMotion" in svg and "](topdown.svg)" in text
    # a second report into the same place is refused, the first left as it was
    before = (report / "report.md").read_bytes()
    assert main(["report", str(run)]) == 2
    assert "not empty" in one_error_line(capsys.readouterr().err)
    assert (report / "report.md").read_bytes() == before


def test_the_report_marks_every_switch_and_false_positive_it_counts(tmp_path):
    gt = tmp_path / "gt.csv"
    tracks = tmp_path / "tr.csv"
    # person 1 tracked by 10 then by 11 (a switch at (0, 1)); person 2 occluded in frame 1 and matched there by
    # track 20 (excused); a ghost track 30 at (9, 9) in frame 2
    gt.write_text("frame,t,id,x,y,visible\n0,0,1,0,0,1\n0,0,2,4,0,1\n1,0.1,1,0,0.5,1\n1,0.1,2,4,0,0\n"
                  "2,0.2,1,0,1,1\n2,0.2,2,4,0,1\n")
    tracks.write_text("frame,t,id,x,y\n0,0,10,0,0\n0,0,20,4,0\n1,0.1,10,0,0.5\n1,0.1,20,4,0\n"
                      "2,0.2,11,0,1\n2,0.2,20,4,0\n2,0.2,30,9,9\n")
    events = _events(load_sequence(gt), load_sequence(tracks, occlusion=False), 1.0)
    assert events["switches"].tolist() == [[0.0, 1.0]]
    assert events["false_positives"].tolist() == [[9.0, 9.0]]
    assert events["stamp"].tolist() == [0.0, 0.1, 0.2]
    # per frame: counted gt, matches, fp, fn, switches
    assert events["counts"][:, :5].tolist() == [[2, 2, 0, 0, 0], [1, 1, 0, 0, 0], [2, 2, 1, 0, 1]]


def test_report_of_a_run_without_anyone(tmp_path):
    # nobody in the room: no ground truth, no tracks; the report says so and draws its (empty) figures
    empty = tmp_path / "empty.yaml"
    empty.write_text("name: empty\nduration: 1.0\nmap: {walls: [[[0, 0], [20, 0], [20, 20], [0, 20], [0, 0]]]}\n"
                     "robot: {start: [5, 5, 0]}\nsensors: {lasers: [{name: front_laser, mount: [0.25, 0, 0]}]}\n")
    run = tmp_path / "run"
    assert main(["run", str(empty), "--out", str(run), "--quiet"]) == 0
    assert main(["report", str(run)]) == 0
    text = (run / "report" / "report.md").read_text()
    assert "0 frames; ground truth 0 rows, of which 0 ignored" in text
    assert json.loads((run / "report" / "tracking.json").read_text())["tracking"]["mota"] is None
