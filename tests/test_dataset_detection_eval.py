"""Scoring a detector on a dataset (crowdsim/datasets/detection_eval.py, ``crowdsim dataset evaluate-detector``):
the scores against evaluation.detection fed by hand from the tables, the min-beams rule, a hand-made dataset worked
out on paper, and the command's table, JSON and errors."""

import json

import h5py
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from test_dataset_reader import make_dataset

from crowdsim.cli import main
from crowdsim.datasets import episode as episode_module
from crowdsim.datasets import evaluate_detector
from crowdsim.datasets.detection_eval import FUSED, MIN_BEAMS, detection_table
from crowdsim.datasets.layout import DatasetError
from evaluation.detection import detection_scores

LASERS = ("front_laser", "rear_laser")


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    return make_dataset(tmp_path_factory.mktemp("detection_eval"))


def columns(path, names) -> dict:
    table = pq.read_table(path, columns=names)
    return {n: table.column(n).to_numpy(zero_copy_only=False) for n in names}


def frames_by_hand(folder, episode_ids, detector, min_beams):
    """(det_xy, det_conf, gt_xy) per scored frame, from whole tables: numpy masks, no reader."""
    for i in episode_ids:
        ep = folder / i
        lasers = LASERS if detector == FUSED else (detector,)
        with h5py.File(ep / "sensors.h5", "r") as f:
            scanned = f[f"lasers/{lasers[0]}/frame"][()] if detector != FUSED else np.arange(len(f["robot/stamp"]))
        p = columns(ep / "persons.parquet", ["frame", "x", "y", *(f"{laser}.beams" for laser in lasers)])
        d = columns(ep / "detections.parquet", ["frame", "detector", "confidence", "world_x", "world_y"])
        counts = np.max([p[f"{laser}.beams"] for laser in lasers], axis=0) >= min_beams
        for frame in scanned:
            g = (p["frame"] == frame) & counts
            m = (d["frame"] == frame) & (d["detector"] == detector)
            yield (np.column_stack([d["world_x"][m], d["world_y"][m]]), d["confidence"][m],
                   np.column_stack([p["x"][g], p["y"][g]]))


@pytest.mark.parametrize("detector", [FUSED, "front_laser", "rear_laser"])
def test_the_scores_are_evaluation_detection_fed_by_hand_from_the_tables(dataset, detector):
    ids = ["episode_00000", "episode_00001", "episode_00002"]
    got = evaluate_detector(dataset, detector, split="mini")
    expected = detection_scores(frames_by_hand(dataset, ids, detector, MIN_BEAMS))
    assert (got.episodes, got.frames, got.min_beams) == (3, 150, MIN_BEAMS)
    assert got.n_gt > 0 and got.n_detections > 0
    for r, e in expected.items():
        s = got.scores[r]
        assert (s.n_gt, s.n_detections) == (got.n_gt, got.n_detections) == (e.n_gt, e.n_detections)
        assert (s.ap, s.peak_f1, s.eer) == (e.ap, e.peak_f1, e.eer)
        np.testing.assert_array_equal(s.precision, e.precision)


@pytest.mark.parametrize("detector", [FUSED, "front_laser"])
def test_min_beams_keeps_the_persons_the_table_says_were_hit_that_often(dataset, detector):
    p = columns(dataset / "episode_00002" / "persons.parquet", [f"{laser}.beams" for laser in LASERS])
    beams = np.max(list(p.values()), axis=0) if detector == FUSED else p[f"{detector}.beams"]
    counts = [evaluate_detector(dataset, detector, min_beams=k).n_gt for k in (1, 4, MIN_BEAMS, 12)]
    assert counts == [int((beams >= k).sum()) for k in (1, 4, MIN_BEAMS, 12)]
    assert counts[0] > counts[1] > counts[2] > counts[3] > 0


def write_table(path, schema: pa.Schema, rows: list[dict]) -> None:
    """A table of ``schema`` with ``rows`` (columns left out are null)."""
    pq.write_table(pa.table({f.name: pa.array([r.get(f.name) for r in rows], f.type) for f in schema},
                            schema=schema), path)


@pytest.fixture
def hand_made(tmp_path):
    """One episode of 4 frames; front_laser scans frames 0 and 2, rear_laser every frame. Persons (world x, y; front,
    rear beams): frame 0 A (0, 0; 10, 0) and B (5, 0; 3, 0); frame 1 A (0.5, 0; 9, 0); frame 2 A (1, 0; 7, 0) and
    C (-3, 0; 0, 8); frame 3 nobody. Detections (confidence at x, y): front 0.9 at (0.1, 0), 0.8 at (5.1, 0) in
    frame 0 and 0.4 at (1.4, 0) in frame 2; fusion the same plus 0.6 at (9, 9) in frame 1 and 0.5 at (-3, 0.2) in
    frame 2."""
    root, ep = tmp_path / "hand", tmp_path / "hand" / "episode_00000"
    ep.mkdir(parents=True)
    laser = {"n_beams": 4, "angle_min": 0.0, "angle_increment": 0.1}
    (ep / "meta.json").write_text(json.dumps({"frames": 4, "calibration": {
        "lasers": {"front_laser": laser, "rear_laser": laser}, "depth_cameras": {}, "wall_cameras": {}}}))
    (root / "manifest.json").write_text(json.dumps({"episodes": [{"id": "episode_00000"}], "mini": [],
                                                    "splits": {"train": [], "val": [], "test": ["episode_00000"]}}))
    with h5py.File(ep / "sensors.h5", "w") as f:
        f["lasers/front_laser/frame"] = np.array([0, 2], np.int32)
        f["lasers/rear_laser/frame"] = np.arange(4, dtype=np.int32)
    persons = [(0, 1, 0, 0, 10, 0), (0, 2, 5, 0, 3, 0), (1, 1, 0.5, 0, 9, 0), (2, 1, 1, 0, 7, 0), (2, 3, -3, 0, 0, 8)]
    write_table(ep / "persons.parquet", episode_module.persons_schema(list(LASERS), []),
                [dict(zip(("frame", "id", "x", "y", "front_laser.beams", "rear_laser.beams"), p)) for p in persons])
    dets = [(0, "front_laser", 0.9, 0.1, 0), (0, "front_laser", 0.8, 5.1, 0), (0, FUSED, 0.9, 0.1, 0),
            (0, FUSED, 0.8, 5.1, 0), (1, FUSED, 0.6, 9, 9), (2, "front_laser", 0.4, 1.4, 0), (2, FUSED, 0.4, 1.4, 0),
            (2, FUSED, 0.5, -3, 0.2)]
    write_table(ep / "detections.parquet", episode_module.DETECTIONS_SCHEMA,
                [dict(zip(("frame", "detector", "confidence", "world_x", "world_y"), d)) for d in dets])
    return root


@pytest.mark.parametrize("detector, min_beams, frames, n_gt, expected", [
    # front: frames 0, 2; A twice counts, B (3 beams) does not, so 0.8 is a false positive; 0.4 is 0.4 m off A
    ("front_laser", 6, 2, 2, {0.3: (0.5, 2 / 3, 0.5), 0.5: (0.5 + 0.25 * (0.5 + 2 / 3), 0.8, 0.5)}),
    ("front_laser", 3, 2, 3, {0.3: (2 / 3, 0.8, 2 / 3), 0.5: (1.0, 1.0, 1.0)}),
    # fusion: every frame; A (front beams) three times and C (rear beams); at 0.5 m P = 1, .5, 1/3, .5, .6 and
    # R = .25, .25, .25, .5, .75 down the confidences
    (FUSED, 6, 4, 4, {0.5: (0.25 + 0.125 * (1 / 3 + 0.5) + 0.125 * 1.1, 2 / 3, 0.5)}),
])
def test_a_hand_made_dataset_scores_as_worked_out_on_paper(hand_made, detector, min_beams, frames, n_gt, expected):
    got = evaluate_detector(hand_made, detector, min_beams=min_beams)
    assert (got.frames, got.n_gt) == (frames, n_gt)
    for r, (ap, f1, eer) in expected.items():
        s = got.scores[r]
        assert (s.ap, s.peak_f1, s.eer) == pytest.approx((ap, f1, eer)), r
    with pytest.raises(DatasetError, match="split 'val' holds no episode"):
        evaluate_detector(hand_made, detector, split="val")


def test_the_command_prints_the_table_and_writes_json(dataset, tmp_path, capsys):
    out = tmp_path / "scores.json"
    assert main(["dataset", "evaluate-detector", str(dataset), "--detector", "front_laser", "--json", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["detector", "split", "episodes", "frames", "GT", "detections", "AP@0.3",
                                "peakF1@0.3", "EER@0.3", "AP@0.5", "peakF1@0.5", "EER@0.5"]
    saved = json.loads(out.read_text())
    assert lines[1].split()[:6] == ["front_laser", "test", "1", "50", str(saved["n_gt"]), str(saved["n_detections"])]
    assert float(lines[1].split()[6]) == round(100 * saved["radii"]["0.3"]["ap"], 1)
    assert saved["min_beams"] == MIN_BEAMS and lines[-1].startswith("GT: persons hit by at least 6 beams")
    assert main(["dataset", "evaluate-detector", str(dataset)]) == 0
    printed = capsys.readouterr().out
    assert printed.splitlines()[1].startswith("fusion ")
    assert printed == detection_table([evaluate_detector(dataset)]) + "\n"


@pytest.mark.parametrize("args, words", [
    (["--detector", "side_laser"], ("no detector 'side_laser'", "front_laser, fusion, rear_laser")),
    (["--split", "holdout"], ("split 'holdout'", "train, val, test, mini")),
    (["--min-beams", "0"], ("--min-beams", "at least 1")),
    (["--min-beams", "1000"], ("no person", "1000 or more beams", "--min-beams")),
])
def test_errors_exit_2_with_one_line_naming_the_option(dataset, capsys, args, words):
    assert main(["dataset", "evaluate-detector", str(dataset), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("crowdsim: error: ") and err.count("\n") == 1, err
    assert all(w in err for w in words), err


def test_a_folder_that_is_no_dataset_or_an_existing_json_is_refused(dataset, tmp_path, capsys):
    assert main(["dataset", "evaluate-detector", str(tmp_path)]) == 2
    assert f"{tmp_path}: no readable manifest.json" in capsys.readouterr().err
    taken = tmp_path / "taken.json"
    taken.write_text("{}")
    assert main(["dataset", "evaluate-detector", str(dataset), "--json", str(taken)]) == 2
    assert f"--json {taken}: already exists" in capsys.readouterr().err and taken.read_text() == "{}"


def test_export_writes_the_format_and_says_what_it_wrote(dataset, tmp_path, capsys):
    out = tmp_path / "mot"
    assert main(["dataset", "export", str(dataset), "--format", "motchallenge", "--out", str(out),
                 "--split", "val"]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith(f"{out}: motchallenge, 1 episodes, ")
    assert [p.relative_to(out).as_posix() for p in out.rglob("gt.txt")] == ["val/episode_00001/gt/gt.txt"]
    assert main(["dataset", "export", str(dataset), "--format", "motchallenge", "--out", str(out)]) == 2
    assert f"--out {out}" in capsys.readouterr().err
    assert main(["dataset", "export", str(dataset), "--format", "motchallenge", "--laser", "front_laser",
                 "--out", str(tmp_path / "x")]) == 2
    assert "--laser" in capsys.readouterr().err and not (tmp_path / "x").exists()
