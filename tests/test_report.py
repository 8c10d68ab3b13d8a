"""``crowdsim report``: the report of a run holds its metrics exactly, marks every ID switch and false positive
the evaluation counted, writes its figures, and refuses to overwrite."""

import json
import re
import xml.etree.ElementTree as ET

import numpy as np

from crowdsim.cli import main
from evaluation.io import load_sequence
from evaluation.report import _events, write_report
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


def _walking_pair(run):
    """A run directory by hand, as an older run wrote it: persons 1 and 2 side by side 1 m apart walking along x at
    1 m/s for 3 frames of 0.5 s, tracked exactly by tracks 11 and 12; no detections, no robot, no groups."""
    run.mkdir()
    gt, tracks = ["frame,t,id,x,y,vx,vy,visible"], ["frame,t,id,x,y,vx,vy"]
    for f in range(3):
        for person, y in ((1, 0.0), (2, 1.0)):
            gt.append(f"{f},{0.5 * f},{person},{0.5 * f},{y},1,0,1")
            tracks.append(f"{f},{0.5 * f},{person + 10},{0.5 * f},{y},1,0")
    (run / "groundtruth.csv").write_text("\n".join(gt) + "\n")
    (run / "tracks.csv").write_text("\n".join(tracks) + "\n")
    return run


def _svg_groups(path):
    root = ET.parse(path).getroot()
    (layer,) = [e for e in root.iter() if e.get("id") == "groups"]
    return [g for g in layer if g.tag.endswith("}g")]


def test_report_of_a_run_without_groups_csv(tmp_path):
    run = _walking_pair(tmp_path / "run")
    out = tmp_path / "report"
    out.mkdir()
    tracking = write_report(out, run, np.zeros((0, 2, 2)), 0.5, "old run")
    assert (tracking["mota"], tracking["id_switches"], tracking["frames"]) == (1.0, 0, 3)
    assert _svg_groups(out / "topdown.svg") == []  # the layer is there, empty
    assert "G" not in re.sub(r"<[^>]*>", "", (out / "topdown.svg").read_text()).replace("old run", "")
    assert "tracked group" not in (out / "report.md").read_text()


def test_report_draws_the_groups_of_groups_csv(tmp_path):
    run = _walking_pair(tmp_path / "run")
    # group 7 of tracks 11 and 12 in frames 1 and 2 (not 0), its centroid between them; relations.csv is not read
    (run / "groups.csv").write_text("frame,t,group,id,x,y,age\n1,0.5,7,11,0.5,0.5,0\n1,0.5,7,12,0.5,0.5,0\n"
                                    "2,1.0,7,11,1.0,0.5,0.5\n2,1.0,7,12,1.0,0.5,0.5\n")
    out = tmp_path / "report"
    out.mkdir()
    write_report(out, run, np.zeros((0, 2, 2)), 0.5, "with groups")
    frames = _svg_groups(out / "topdown.svg")
    assert len(frames) == 2
    texts = [t for t in frames[1].iter() if t.tag.endswith("}text")]
    paths = [t for t in frames[1].iter() if t.tag.endswith("}path")]
    # frame 2: tracks 11 at (1, 0) m -> (100, 0), 12 at (1, 1) m -> (100, -100), the centroid (1, 0.5) m -> (100, -50)
    assert [(t.text, t.get("x"), t.get("y")) for t in texts] == [("G7", "100.0", "-50.0")]
    assert [p.get("d") for p in paths] == ["M100.0,0.0L100.0,-50.0M100.0,-100.0L100.0,-50.0"]
    assert "members joined to its centroid, labelled G and its id" in (out / "report.md").read_text()
