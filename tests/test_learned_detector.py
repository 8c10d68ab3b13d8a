"""The learned segment classifier (``laser_learned``): Arras et al.'s segment features on hand-worked segments, the
numpy-only models against scikit-learn's own predictions, the shipped models on synthetic scans, and the detector
selected from a scenario and run in the loop."""

import json

import numpy as np
import pytest
import yaml
from conftest import room
from test_laser_detector import ANGLE_MIN, INC, N_BEAMS, circle_ranges, line_ranges, scan_of

from crowdsim.cli import main
from crowdsim.experiments.train_detector import collect, forest_from_sklearn, label_segments, stumps_from_sklearn
from crowdsim.loop import Simulation
from pipeline.detectors.learned_segments import Forest, LearnedSegmentDetector, SegmentModel, load_model
from pipeline.detectors.segment_features import (FEATURE_NAMES, MAX_RADIUS, Segments, jump_segments,
                                                 segment_features)
from pipeline.types import UNKNOWN_VARIANCE, LaserScan
from scenarios import load_scenario, scenario_from_dict


def segments_of(*runs) -> Segments:
    """Point runs [k_i, 2] as consecutive segments of one scan."""
    p = np.concatenate(runs)
    count = np.array([len(r) for r in runs])
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    return Segments(p, np.arange(len(p)), np.repeat(np.arange(len(runs)), count), start, count)


def features(*runs, range_max=20.0) -> dict[str, np.ndarray]:
    f = segment_features(segments_of(*runs), range_max)
    return dict(zip(FEATURE_NAMES, f.T))


# --- features ------------------------------------------------------------------------------------------------------

def test_an_arc_of_a_circle_has_zero_circularity_and_its_exact_radius():
    # 9 points 0.25 rad apart on the circle of radius 0.25 about (3, 1), the side facing the origin: the algebraic
    # fit is exact; every triangle of 3 points on a circle has circumradius r (curvature 4 = 1/r); the chord
    # directions turn by the angle step 0.25 rad at each inner point; all steps are equal (regularity 0)
    a = np.pi + np.linspace(-1.0, 1.0, 9)
    f = features(np.column_stack([3 + 0.25 * np.cos(a), 1 + 0.25 * np.sin(a)]))
    assert f["circularity"][0] == pytest.approx(0.0, abs=1e-20)
    assert f["radius"][0] == pytest.approx(0.25, rel=1e-12)
    assert f["mean_curvature"][0] == pytest.approx(4.0, rel=1e-9)
    assert f["mean_angular_difference"][0] == pytest.approx(0.25, rel=1e-9)
    assert f["boundary_length"][0] == pytest.approx(8 * 2 * 0.25 * np.sin(0.125), rel=1e-12)  # 8 chords
    assert f["boundary_regularity"][0] == pytest.approx(0.0, abs=1e-12)
    assert f["width"][0] == pytest.approx(2 * 0.25 * np.sin(1.0), rel=1e-12)  # chord over 2 rad
    assert f["n_points"][0] == 9


def test_a_long_arc_and_its_neighbours_by_hand():
    # 300 points (more than the 128 of one pairwise block) 0.01 rad apart on the circle of radius 2 about (6, 0),
    # between two 3-point segments: the fit is still exact, the steps all 2 * 2 sin(0.005), and the jumps are the
    # gaps to the neighbours' nearest points
    a = np.pi + (np.arange(300) - 149.5) * 0.01
    arc = np.column_stack([6 + 2 * np.cos(a), 2 * np.sin(a)])
    before, after = arc[0] + [[0.0, -1.0], [0.0, -0.9], [0.0, -0.8]], arc[-1] + [[0.0, 0.5], [0.0, 0.6], [0.0, 0.7]]
    f = features(before, arc, after)
    assert f["radius"][1] == pytest.approx(2.0, rel=1e-9) and f["circularity"][1] == pytest.approx(0.0, abs=1e-12)
    assert f["boundary_length"][1] == pytest.approx(299 * 4 * np.sin(0.005), rel=1e-12)
    assert f["mean_curvature"][1] == pytest.approx(0.5, rel=1e-6)
    assert (f["jump_prev"][1], f["jump_next"][1]) == (pytest.approx(0.8), pytest.approx(0.5))
    assert f["n_points"].tolist() == [3, 300, 3]


def test_points_on_a_line_have_zero_linearity_and_no_circle():
    # 7 points 1/3 m apart on x = 5: no residual to the line; collinear points have no circle, so the radius is
    # MAX_RADIUS and the circularity the line's residual, 0; nothing turns
    f = features(np.column_stack([np.full(7, 5.0), np.linspace(-1.0, 1.0, 7)]))
    assert f["linearity"][0] == pytest.approx(0.0, abs=1e-20)
    assert (f["radius"][0], f["circularity"][0]) == (MAX_RADIUS, f["linearity"][0])
    assert f["mean_curvature"][0] == f["mean_angular_difference"][0] == 0.0
    assert f["width"][0] == pytest.approx(2.0) and f["boundary_length"][0] == pytest.approx(2.0)
    # sigma^2 = sum y^2 / (n - 1) = (2 (1 + 4/9 + 1/9)) / 6 = 14/27
    assert f["std"][0] == pytest.approx(np.sqrt(14 / 27))
    # the median is the middle point (5, 0): mean |y| = 2 (1/3 + 2/3 + 1) / 7 = 4/7
    assert f["median_deviation"][0] == pytest.approx(4 / 7)


def test_a_three_point_segment_by_hand():
    # (0,0), (1,0), (1,1): a right triangle. Curvature 4A / (a b c) = 4 (1/2) / (1 * 1 * sqrt 2) = sqrt 2, the
    # inverse of the circumradius sqrt(2)/2 (half the hypotenuse), which is the fitted circle's radius (3 points
    # lie on a circle exactly). The turn from (1,0) to (0,1) is pi/2. Mean (2/3, 1/3): centred scatter
    # [[2/3, 1/3], [1/3, 2/3]], eigenvalues 1 and 1/3, so linearity 1/3 and sigma = sqrt((2/3 + 2/3) / 2).
    # Median (1, 0): distances 1, 0, 1, mean 2/3. Steps 1 and 1: boundary 2, regularity 0. Width sqrt 2.
    f = features(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]))
    expected = {"n_points": 3, "std": np.sqrt(2 / 3), "median_deviation": 2 / 3, "width": np.sqrt(2),
                "linearity": 1 / 3, "circularity": 0.0, "radius": np.sqrt(2) / 2, "boundary_length": 2.0,
                "boundary_regularity": 0.0, "mean_curvature": np.sqrt(2), "mean_angular_difference": np.pi / 2}
    for name, value in expected.items():
        assert f[name][0] == pytest.approx(value, abs=1e-12), name


def test_jump_distances_regularity_and_an_even_median():
    # three segments: the first's predecessor and the last's successor are nothing nearer than range_max
    a = np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]])  # steps 1 and 2: sample sd sqrt(2 * 0.5^2 / 1)
    b = np.array([[3.0, 4.0], [4.0, 4.0], [6.0, 4.0], [7.0, 4.0]])  # even count: median x (4 + 6) / 2 = 5
    c = np.array([[7.0, 7.0], [7.0, 8.0], [7.0, 9.0]])
    f = features(a, b, c, range_max=15.0)
    np.testing.assert_allclose(f["jump_prev"], [15.0, 4.0, 3.0])  # |(3,4) - (3,0)|, |(7,7) - (7,4)|
    np.testing.assert_allclose(f["jump_next"], [4.0, 3.0, 15.0])
    assert f["boundary_regularity"][0] == pytest.approx(np.sqrt(0.5))
    assert f["median_deviation"][1] == pytest.approx((2 + 1 + 1 + 2) / 4)


def test_single_and_two_point_segments_get_finite_defaults():
    f = segment_features(segments_of(np.array([[2.0, 0.0]]), np.array([[4.0, 0.0], [4.0, 0.5]])), 20.0)
    assert np.isfinite(f).all()
    one, two = dict(zip(FEATURE_NAMES, f[0])), dict(zip(FEATURE_NAMES, f[1]))
    assert (one["std"], one["width"], one["radius"], one["mean_curvature"]) == (0.0, 0.0, MAX_RADIUS, 0.0)
    assert (two["width"], two["linearity"], two["radius"], two["boundary_regularity"]) == (0.5, 0.0, MAX_RADIUS, 0.0)


def test_jump_segments_from_a_scan_and_labels_by_the_majority_of_returns():
    # a body at (4, 0) in front of a wall at x = 8: wall | body | wall; the body's 11 returns hit person 7
    ranges = np.fmin(line_ranges((8.0, -3.0), (8.0, 3.0)), circle_ranges((4.0, 0.0)))
    person = np.where(np.isclose(ranges, circle_ranges((4.0, 0.0))), 7, -1)
    scan = LaserScan(0.0, "front_laser", ANGLE_MIN, INC, 20.0, ranges, person)
    seg = jump_segments(scan, 0.4)
    np.testing.assert_array_equal(seg.count[1], 11)
    np.testing.assert_array_equal(seg.beam[seg.label == 1], np.arange(185, 196))  # -2.5 .. 2.5 deg
    np.testing.assert_array_equal(label_segments(seg, person), [-1, 7, -1])
    # 6 of 11 returns are a majority; 5 (and 5 of another person, 1 of none) are not
    person[185:191] = 3
    np.testing.assert_array_equal(label_segments(seg, person), [-1, 3, -1])
    person[190] = -1
    np.testing.assert_array_equal(label_segments(seg, person), [-1, -1, -1])


def test_collect_labels_the_airport_scans_of_a_seed():
    # 0.4 s = 10 laser cycles, every 5th kept: cycles 0 and 5 of both lasers
    data = collect(1000, 0.4, every=5)
    assert data.n_scans == 4 and data.x.shape == (len(data.person), len(FEATURE_NAMES))
    assert set(np.unique(data.seg_scan)) == set(np.unique(data.gt_scan)) == {0, 1, 2, 3}
    assert (data.x[:, 0] >= 3).all() and 0.2 < data.person.mean() < 0.9  # candidates: >= 3 returns
    # a person segment lies on its person: the centroid within a body's width of the centre, in front of it
    gap = np.linalg.norm(data.target[data.person] - data.centroid[data.person], axis=1)
    assert gap.max() < 0.5 and np.isnan(data.target[~data.person]).all()
    assert (data.gt_beams >= 1).all() and len(data.geometric) > 0


def test_train_detector_command_refuses_bad_arguments(tmp_path, capsys):
    assert main(["experiment", "train-detector", "--seeds", "0"]) == 2
    assert "--seeds: expected 1 to 1000 training seeds, got 0" in capsys.readouterr().err
    (tmp_path / "kept").write_text("x")
    assert main(["experiment", "train-detector", "--out", str(tmp_path)]) == 2
    assert "already exists and is not empty" in capsys.readouterr().err
    assert (tmp_path / "kept").read_text() == "x"


# --- numpy models against scikit-learn -----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def toy_data():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(600, len(FEATURE_NAMES))) * rng.uniform(0.01, 10.0, len(FEATURE_NAMES))
    y = (x[:, 1] / x[:, 1].std() + np.sin(x[:, 5]) + 0.5 * rng.normal(size=600)) > 0.3
    return x, y, rng.normal(size=(400, len(FEATURE_NAMES))) * x.std(axis=0)


def test_shipped_stumps_equal_scikit_learns_adaboost(tmp_path, toy_data):
    ensemble = pytest.importorskip("sklearn.ensemble")
    tree = pytest.importorskip("sklearn.tree")
    x, y, new = toy_data
    ada = ensemble.AdaBoostClassifier(tree.DecisionTreeClassifier(max_depth=1), n_estimators=40,
                                      random_state=0).fit(x, y)
    SegmentModel(stumps_from_sklearn(ada), 0.5, 0.1, 0.0).save(tmp_path / "m.json")
    model = load_model(tmp_path / "m.json")
    stored = json.loads((tmp_path / "m.json").read_text())  # plain JSON: no pickle, no scikit-learn
    assert len(stored["stumps"]["weight"]) == 40 and stored["features"] == list(FEATURE_NAMES)
    total = ada.estimator_weights_.sum()
    for data in (x, new):
        # F = sum of the weighted votes, which scikit-learn's decision function gives as 2 F / total; its
        # predict_proba is the logistic function of 2 F / total
        f = np.log(1 / model.classifier.predict_proba(data) - 1) * -1
        np.testing.assert_allclose(f, ada.decision_function(data) * total / 2, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(1 / (1 + np.exp(-2 * f / total)), ada.predict_proba(data)[:, 1], atol=1e-12)
    p = model.classifier.predict_proba(x)
    assert p.min() < 0.001 and p.max() > 0.97  # the log-odds spread out, scikit-learn's mean vote much less:
    assert 0.15 < ada.predict_proba(x)[:, 1].min() and ada.predict_proba(x)[:, 1].max() < 0.85


def test_shipped_forest_equals_scikit_learns_random_forest(tmp_path, toy_data):
    ensemble = pytest.importorskip("sklearn.ensemble")
    x, y, new = toy_data
    rf = ensemble.RandomForestClassifier(n_estimators=7, max_depth=6, random_state=0).fit(x, y)
    SegmentModel(forest_from_sklearn(rf), 0.4, 0.1, 0.02).save(tmp_path / "m.npz")
    model = load_model(tmp_path / "m.npz")
    with np.load(tmp_path / "m.npz", allow_pickle=False) as z:  # plain arrays only
        assert len(z["roots"]) == 7 and z["left"].dtype == np.int64
    assert (model.threshold, model.offset, model.per_width) == (0.4, 0.1, 0.02)
    np.testing.assert_allclose(model.classifier.predict_proba(new), rf.predict_proba(new)[:, 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(model.classifier.predict_proba(x), rf.predict_proba(x)[:, 1], rtol=0, atol=1e-12)


def test_a_two_tree_forest_by_hand():
    # tree 0 (nodes 0-2): x0 <= 0.5 ? 0.2 : 0.8; tree 1 (nodes 3-7): x1 <= 1 ? (x0 <= 2 ? 0.0 : 1.0) : 0.6; the
    # probability is the trees' mean; a NaN feature goes left, as no comparison with it holds
    forest = Forest(feature=np.array([0, -2, -2, 1, 0, -2, -2, -2]),
                    threshold=np.array([0.5, -2, -2, 1.0, 2.0, -2, -2, -2]),
                    left=np.array([1, -1, -1, 4, 5, -1, -1, -1]), right=np.array([2, -1, -1, 7, 6, -1, -1, -1]),
                    value=np.array([0, 0.2, 0.8, 0, 0, 0.0, 1.0, 0.6]), roots=np.array([0, 3]))
    x = np.array([[0.4, 2.0], [3.0, 0.5], [np.nan, 0.0], [0.5, 1.0]])
    assert forest.predict_proba(x).tolist() == [(0.2 + 0.6) / 2, (0.8 + 1.0) / 2, (0.2 + 0.0) / 2, (0.2 + 0.0) / 2]
    assert forest.predict_proba(np.zeros((0, 2))).shape == (0,)


def test_a_wrong_model_is_one_clear_error(tmp_path):
    with pytest.raises(ValueError, match="expected adaboost, forest or the path of a .json or .npz model file"):
        LearnedSegmentDetector(model="svm")
    (tmp_path / "m.json").write_text(json.dumps({"format": "something else", "features": ["n_points"]}))
    with pytest.raises(ValueError, match="expected a crowdsim-segment-stumps/1 model"):
        load_model(tmp_path / "m.json")


# --- the shipped models on synthetic scans -------------------------------------------------------------------------

def torso_and_walls(rng) -> LaserScan:
    """A round body (the hip's radius, 0.18 m) at (3, 0.8) in front of a wall at x = 7 from y = -4 to 4, and a flat
    1 m board at 2.5 m on the right; the airport lasers' 7 mm range noise."""
    ranges = np.fmin(np.fmin(line_ranges((7.0, -4.0), (7.0, 4.0)), circle_ranges((3.0, 0.8), 0.18)),
                     line_ranges((1.0, -2.3), (1.9, -2.7)))
    return scan_of(ranges + rng.normal(0.0, 0.007, N_BEAMS))


@pytest.mark.parametrize("model", ["adaboost", "forest"])
def test_shipped_model_finds_the_body_and_not_the_walls(model):
    rng = np.random.default_rng(1)
    detector = LearnedSegmentDetector(model=model)
    for _ in range(20):
        scan = torso_and_walls(rng)
        centre, p = detector.score(scan)
        body = np.linalg.norm(centre - [3.0, 0.8], axis=1) < 0.15
        assert body.sum() == 1 and p[body][0] > 0.99  # the body, near its centre, with high confidence
        assert (~body).sum() == 3 and p[~body].max() < min(0.25, detector.threshold / 2)  # walls and board: low
        det = detector.detect(scan)
        assert len(det) == 1 and det.confidence[0] == p[body][0]
        np.testing.assert_allclose(det.covariance[0], np.diag([0.1, 0.1, UNKNOWN_VARIANCE]))
    assert detector.detect(scan).detection_id[0] == 20  # ids count up over scans until reset
    detector.reset()
    assert detector.detect(scan).detection_id[0] == 0


def test_threshold_defaults_to_the_models_and_can_be_set():
    forest = LearnedSegmentDetector()
    assert forest.threshold == load_model("forest").threshold
    assert 0.0 < forest.threshold < 1.0
    scan = torso_and_walls(np.random.default_rng(2))
    assert len(LearnedSegmentDetector(threshold=0.0).detect(scan)) == len(forest.score(scan)[1])  # every candidate
    assert len(LearnedSegmentDetector(threshold=1.0 + 1e-9).detect(scan)) == 0


def test_an_empty_scan_gives_no_detection():
    det = LearnedSegmentDetector().detect(scan_of())
    assert len(det) == 0 and det.position.shape == (0, 3) and det.confidence.shape == (0,)


# --- in the loop ---------------------------------------------------------------------------------------------------

def people_ahead(detector: dict) -> dict:
    """The conftest room, a standing group and a flow in front of the parked robot, the given detector."""
    return room(waypoints={"east": {"position": [30, 6]}}, routes={"across": {"waypoints": ["east"]}},
                sources=[{"position": [5, 6], "size": [1, 2], "rate": 2.0, "routes": {"across": 1.0}}],
                standing=[{"position": [6, 2], "count": 3}], warmup=2.0, duration=1.0,
                pipeline={"detector": detector})


def test_the_scenario_key_selects_the_learned_detector_and_it_runs_in_the_loop():
    sc = scenario_from_dict(people_ahead({"type": "laser_learned", "model": "adaboost", "threshold": 0.7}))
    assert sc["pipeline"]["detector"] == {"type": "laser_learned", "model": "adaboost", "threshold": 0.7,
                                          "jump_distance": 0.4, "min_points": 3, "position_variance": 0.1}
    sim = Simulation(sc)
    detectors = sim.pipeline.detectors
    assert {type(d) for d in detectors.values()} == {LearnedSegmentDetector}
    assert detectors["front_laser"].threshold == 0.7 and detectors["front_laser"] is not detectors["rear_laser"]
    sim.warm_up()
    conf = [c for f in sim.frames(1.0) for c in f.detector_outputs["front_laser"].confidence]
    assert len(conf) >= 25 and min(conf) >= 0.7 and max(conf) <= 1.0  # the group is seen in each of 25 scans
    assert len(set(conf)) > 1  # probabilities, not the geometric detector's 1.0


def test_crowdsim_run_with_the_learned_detector_writes_a_run_that_reloads(tmp_path, capsys):
    path = tmp_path / "learned.yaml"
    path.write_text(yaml.safe_dump(people_ahead({"type": "laser_learned"})))
    assert main(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"]) == 0
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["tracking"]["frames"] == 25
    confidence = np.loadtxt(tmp_path / "run" / "detections.csv", delimiter=",", skiprows=1, usecols=5, ndmin=1)
    threshold = load_model("forest").threshold
    assert len(confidence) >= 25 and confidence.min() >= threshold and confidence.min() < 1.0
    again = load_scenario(str(tmp_path / "run" / "scenario.yaml"))["pipeline"]["detector"]  # every default filled
    assert again == {"type": "laser_learned", "model": "forest", "threshold": None, "jump_distance": 0.4,
                     "min_points": 3, "position_variance": 0.1}
