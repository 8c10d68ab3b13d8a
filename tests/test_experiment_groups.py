"""The relation classifiers' training data and models, and the group experiment's queue check, on hand-made cases
and a short airport run."""

import numpy as np
import pytest

from crowdsim.experiments.groups import score, strangers_joined
from crowdsim.experiments.relations import GroupCycle, collect, labelled_pairs, train_forest, train_svm
from pipeline.groups.relations import load_model, save_model
from pipeline.types import TrackedGroups, TrackedPersons


def persons(ids, position, velocity, group=None) -> TrackedPersons:
    n = len(ids)
    return TrackedPersons(0.0, "odom", np.asarray(ids, np.int64), np.ones(n, bool), np.zeros(n, bool),
                          np.full(n, -1, np.int64), np.asarray(position, float), np.asarray(velocity, float),
                          np.zeros((n, 2, 2)), np.zeros((n, 2, 2)), np.zeros(n),
                          None if group is None else np.asarray(group, np.int64))


def hand_cycle() -> GroupCycle:
    # persons 1, 2 walk together (group 5), 3 alone; tracks 10, 11, 12 match them, track 13 is a false positive
    gt = persons([1, 2, 3], [[0, 0], [0.6, 0], [0, 1]], [[1, 0], [1, 0], [1, 0]], [5, 5, -1])
    tracks = persons([10, 11, 12, 13], [[0, 0.1], [0.6, 0.1], [0, 1.1], [0.3, 0.5]],
                     [[1, 0], [1.1, 0], [0.9, 0], [1, 0]])
    return GroupCycle(0.0, tracks, gt, np.array([1, 2, 3]), np.array([10, 11, 12]), np.zeros(0, np.int64),
                      np.array([False, True, True]))


def test_labelled_pairs_are_the_matched_tracks_inside_the_gates():
    x, related = labelled_pairs(hand_cycle())
    # pairs (10, 11), (10, 12), (11, 12); the false positive 13 is no person and left out
    np.testing.assert_allclose(x, [[0.6, 0.1, 0.0], [1.0, 0.1, 0.0], [np.hypot(0.6, 1.0), 0.2, 0.0]])
    assert related.tolist() == [True, False, False]
    # from the true persons themselves: the same pairs, with the true speeds
    x, related = labelled_pairs(hand_cycle().from_groundtruth())
    np.testing.assert_allclose(x[:, 1], 0.0)
    assert related.tolist() == [True, False, False]


def test_the_queue_check_counts_strangers_in_one_group():
    c = hand_cycle()
    # one detected group of tracks 11, 12, 13: queued persons 2 (group 5) and 3 (alone) are two strangers; 13 is
    # no person
    groups = TrackedGroups(0.0, "odom", np.array([0]), np.zeros((1, 2)), np.array([0, 0, 0]), np.array([11, 12, 13]))
    assert strangers_joined(c, groups) == 2
    groups = TrackedGroups(0.0, "odom", np.array([0]), np.zeros((1, 2)), np.array([0, 0]), np.array([10, 11]))
    assert strangers_joined(c, groups) == 1  # person 1 does not queue; 2 alone


def synthetic_pairs(n, rng):
    """Related pairs walk close and alike; unrelated ones are farther or differ. The labels: the truth, and as
    observed, with 15% of them flipped (P(related) 0.85 where pairs look related, 0.15 where they do not)."""
    related = rng.random(n) < 0.4
    d = np.where(related, rng.uniform(0.4, 1.2, n), rng.uniform(0.8, 3.0, n))
    dv = np.where(related, rng.uniform(0, 0.15, n), rng.uniform(0, 1.0, n))
    dtheta = np.where(related, rng.uniform(0, 0.2, n), rng.uniform(0, np.pi / 4, n))
    return np.column_stack([d, dv, dtheta]), related, related ^ (rng.random(n) < 0.15)


def test_trained_classifiers_separate_synthetic_pairs_and_survive_saving(tmp_path):
    rng = np.random.default_rng(0)
    x, _, y = synthetic_pairs(4000, rng)
    x_cal, _, y_cal = synthetic_pairs(2000, rng)
    x_test, truth, observed = synthetic_pairs(2000, rng)
    for name, model in (("svm", train_svm(x, y, x_cal, y_cal)), ("forest", train_forest(x, y))):
        p = model.predict_proba(x_test)
        assert ((p >= 0.5) == truth).mean() > 0.9, name
        # calibrated: the pairs given 0.6-0.95 (those that look related) are related as often as they are given
        band = (p > 0.6) & (p < 0.95)
        assert band.sum() > 300 and abs(observed[band].mean() - p[band].mean()) < 0.05, name
        path = tmp_path / f"{name}.npz"
        save_model(path, model, {"test": True})
        np.testing.assert_array_equal(load_model(str(path)).predict_proba(x_test), p)


def test_a_bad_model_file_is_named(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_text("not a model")
    with pytest.raises(ValueError, match=f"model: {bad} is not a relation model"):
        load_model(str(bad))


@pytest.fixture(scope="module")
def short_run():
    return collect(1200, 4.0)


def test_the_experiment_scores_a_short_run_from_tracks_and_from_the_persons(short_run):
    from_tracks = score(short_run, "tracker", "spencer", "single", 0.5)
    from_truth = score(short_run, "groundtruth", "spencer", "single", 0.5)
    for s in (from_tracks, from_truth):
        assert s["frames"] == len(short_run) and s["true_groups"] > 0
        assert s["queue"]["cycles"] <= len(short_run)
    # from the true persons every counted person is matched: every near pair of persons is scored
    assert from_truth["pairwise"]["pairs"] >= from_tracks["pairwise"]["pairs"]
    assert from_truth["true_groups"] == from_tracks["true_groups"]  # the same persons counted


def test_the_report_tables_hold_each_configurations_figures(short_run, tmp_path):
    import json

    from crowdsim.experiments.groups import configurations, write

    s = score(short_run, "tracker", "forest", "average", 0.5)
    text = write(tmp_path, [[s] * len(configurations())], [1200])
    f1 = f"{100 * s['t_2_3']['f1']:.1f}"
    assert f"| tracker | forest | average | {f1} |" in text
    assert f"| tracker | forest | {s['pairwise']['pairs']} | {s['pairwise']['positives']} |" in text
    saved = json.loads((tmp_path / "groups.json").read_text())
    assert len(saved["configurations"]) == 2 * 3 * 3 * 6 and saved["seeds"] == [1200]
    assert (tmp_path / "groups.png").stat().st_size > 10_000
