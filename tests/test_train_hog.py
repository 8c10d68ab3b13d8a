"""The HOG detector's training data: the streaming room, random negative windows, saving and loading the model."""

import numpy as np
import pytest

from crowdsim.experiments.train_hog import SCALES, peak_f1, random_windows, save, stream_scenario
from pipeline.detectors.hog import PERSON_SHARE, HogModel, load_model


def test_the_training_room_streams_walkers_and_keeps_the_sequence_room():
    s = stream_scenario()
    assert s["clusters"] == () and len(s["sources"]) == 2
    assert all(route["sink"] for route in s["routes"].values())
    assert [c["width"] for c in s["sensors"]["wall_cameras"]] == [640, 640]  # seed 001's cameras, as the sequences


def test_random_windows_lie_inside_the_image_with_a_persons_shape():
    boxes = random_windows(np.random.default_rng(0), 640, 480, 500)
    assert 0 < len(boxes) <= 500
    height, width = boxes[:, 3] - boxes[:, 1], boxes[:, 2] - boxes[:, 0]
    # a person box is 3/4 of its window's height and half its width (a window is 128 x 64 at scale 1)
    np.testing.assert_allclose(height / width, PERSON_SHARE * 128 / 32)
    margin_v = height / PERSON_SHARE * (1 - PERSON_SHARE) / 2
    assert (boxes[:, 1] - margin_v >= 0).all() and (boxes[:, 3] + margin_v <= 480).all()
    assert (boxes[:, 0] - width / 2 >= 0).all() and (boxes[:, 2] + width / 2 <= 640).all()
    assert height.min() >= 96 * SCALES.min() - 1e-9


def test_peak_f1_by_hand():
    person = np.array([[0.0, 0.0, 10.0, 20.0]])
    hit, near, miss = [0.0, 0.0, 10.0, 20.0], [0.0, 5.0, 10.0, 25.0], [50.0, 0.0, 60.0, 20.0]  # IoU 1, 0.6, 0
    detections = [(np.array([hit, miss]), np.array([0.9, 0.95])),  # a false alarm scores above the hit
                  (np.array([near, hit]), np.array([0.8, 0.2])),  # two on one person: the second is a false alarm
                  (np.array([miss]), np.array([0.1]))]
    persons = [person, person, np.zeros((0, 4))]
    threshold, best = peak_f1(detections, persons)
    # by score: 0.95 no, 0.9 yes, 0.8 yes (IoU 0.6), 0.2 no, 0.1 no; at 0.8: precision 2/3, recall 2/2, F1 0.8
    assert threshold == 0.8 and best == pytest.approx({"f1": 0.8, "precision": 2 / 3, "recall": 1.0, "persons": 2})


def test_a_saved_model_keeps_its_numbers_and_a_bad_file_is_named(tmp_path):
    model = HogModel(np.arange(3780, dtype=np.float32) / 3780, -0.5, 0.25)
    again = load_model(save(model, {"test": True}, tmp_path))
    np.testing.assert_array_equal(again.weight, model.weight)
    assert (again.bias, again.threshold) == (-0.5, 0.25)
    bad = tmp_path / "bad.npz"
    bad.write_text("no model")
    with pytest.raises(ValueError, match=f"model: {bad} is not a HOG model"):
        load_model(bad)


def test_the_training_commands_refuse_bad_seeds_and_a_used_out(tmp_path, capsys):
    from crowdsim.cli import main

    assert main(["experiment", "train-hog", "--seeds", "0"]) == 2
    assert "--seeds: expected 1 to 100 training seeds (from 4100), and --workers at least 1; got 0" in \
        capsys.readouterr().err
    assert main(["experiment", "train-relations", "--seeds", "21"]) == 2
    assert "--seeds: expected 1 to 20 training seeds (from 1100)" in capsys.readouterr().err
    (tmp_path / "kept").write_text("x")
    assert main(["experiment", "train-hog", "--out", str(tmp_path)]) == 2
    assert "already exists and is not empty" in capsys.readouterr().err
    assert (tmp_path / "kept").read_text() == "x"
