"""The group stage in a run: relations.csv and groups.csv as the tracks say, the groups object of metrics.json, and
``crowdsim evaluate`` reproducing it exactly from the files alone."""

import json

import numpy as np

from crowdsim.cli import main
from crowdsim.run import RELATIONS_WRITTEN
from evaluation.io import read_table
from test_cli import one_error_line
from test_evaluate_cli import tiny_run  # noqa: F401 (the fixture: a tiny room's run directory)


def test_groups_csv_holds_each_groups_members_and_their_centroid(tiny_run):
    tracks, groups = read_table(tiny_run / "tracks.csv"), read_table(tiny_run / "groups.csv", ("frame", "group", "id"))
    assert len(groups["frame"]) > 0  # the standing pair is found as a group
    for frame, group in set(zip(groups["frame"].tolist(), groups["group"].tolist())):
        rows = (groups["frame"] == frame) & (groups["group"] == group)
        members = groups["id"][rows]
        assert len(members) >= 2 and len(set(members)) == len(members)
        at = (tracks["frame"] == frame) & np.isin(tracks["id"], members)
        assert at.sum() == len(members)  # every member is a track of that cycle
        centroid = [tracks["x"][at].mean(), tracks["y"][at].mean()]
        np.testing.assert_allclose(np.column_stack([groups["x"][rows], groups["y"][rows]]),
                                   np.tile(centroid, (rows.sum(), 1)), atol=1e-4)
    # a track is in one group at most in a cycle
    key = groups["frame"] * 1e6 + groups["id"]
    assert len(np.unique(key)) == len(key)


def test_relations_csv_holds_each_near_pair_once(tiny_run):
    tracks = read_table(tiny_run / "tracks.csv")
    rel = read_table(tiny_run / "relations.csv", ("frame", "track_a", "track_b", "strength"))
    for frame in np.unique(tracks["frame"])[::10]:
        at = tracks["frame"] == frame
        ids, xy = tracks["id"][at], np.column_stack([tracks["x"][at], tracks["y"][at]])
        i, j = np.triu_indices(len(ids), 1)
        near = np.hypot(*(xy[i] - xy[j]).T) <= RELATIONS_WRITTEN
        expected = {(min(a, b), max(a, b)) for a, b in zip(ids[i][near], ids[j][near])}
        r = rel["frame"] == frame
        got = [(min(a, b), max(a, b)) for a, b in zip(rel["track_a"][r], rel["track_b"][r])]
        assert set(got) == expected and len(got) == len(expected)
    assert ((rel["strength"] >= 0) & (rel["strength"] <= 1)).all()


def test_near_relations_worked_by_hand():
    from crowdsim.run import _near

    # tracks 7 at (0, 0), 3 at (3, 4), 9 at (10, 0): 7-3 are 5 m apart (within, inclusive), 3-9 and 7-9 farther
    ids, xy = np.array([7, 3, 9]), np.array([[0.0, 0.0], [3.0, 4.0], [10.0, 0.0]])
    assert _near(ids, xy, np.array([7, 3, 9]), np.array([3, 9, 7]), 5.0).tolist() == [True, False, False]
    assert _near(ids, xy, np.array([7]), np.array([3]), 4.99).tolist() == [False]


def test_metrics_have_the_groups_and_evaluate_reproduces_them_exactly(tiny_run, tmp_path, capsys):
    metrics = json.loads((tiny_run / "metrics.json").read_text())
    groups = metrics["groups"]
    assert groups["true_groups"] > 0 and groups["frames"] == metrics["tracking"]["frames"]
    assert "| group F1 (T=2/3) |" in (tiny_run / "summary.md").read_text()
    js = tmp_path / "m.json"
    files = {name: str(tiny_run / f"{name}.csv") for name in ("groundtruth", "tracks", "relations", "groups")}
    assert main(["evaluate", "--gt", files["groundtruth"], "--tracks", files["tracks"], "--relations",
                 files["relations"], "--groups", files["groups"], "--json", str(js)]) == 0
    assert json.loads(js.read_text())["groups"] == groups
    assert "| group F1 (T=2/3) |" in capsys.readouterr().out
    # --runs scores the groups of each run directory that has them
    js2 = tmp_path / "runs.json"
    assert main(["evaluate", "--runs", str(tiny_run), "--json", str(js2)]) == 0
    assert json.loads(js2.read_text())["groups"] == {str(tiny_run): groups}


def test_relations_without_groups_is_one_clear_error(tiny_run, capsys):
    assert main(["evaluate", "--gt", str(tiny_run / "groundtruth.csv"), "--tracks", str(tiny_run / "tracks.csv"),
                 "--relations", str(tiny_run / "relations.csv")]) == 2
    assert "--relations and --groups: expected both" in one_error_line(capsys.readouterr().err)


def test_a_ground_truth_without_groups_is_named(tiny_run, tmp_path, capsys):
    gt = tmp_path / "gt.csv"
    gt.write_text("frame,t,id,x,y,visible\n0,0,1,0,0,1\n")
    assert main(["evaluate", "--gt", str(gt), "--tracks", str(tiny_run / "tracks.csv"), "--relations",
                 str(tiny_run / "relations.csv"), "--groups", str(tiny_run / "groups.csv")]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert str(gt) in line and "group" in line


def test_a_relation_model_that_is_not_there_is_one_clear_error(tmp_path, capsys):
    scenario = tmp_path / "typo.yaml"
    scenario.write_text("base: airport_disembarkation\nduration: 1\npipeline:\n  groups:\n    model: forrest\n")
    assert main(["run", str(scenario), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert f"{scenario}: pipeline.groups: model: forrest is not a relation model" in line
    assert "expected spencer, svm, forest" in line
    assert not (tmp_path / "out").exists()
