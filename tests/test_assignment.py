"""Sparse exact assignments (evaluation/assignment.py) on hand-worked cases and against the dense
``linear_sum_assignment`` on many small random instances: the optimum totals must agree (exactly for integer data)."""

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from evaluation import assignment
from evaluation.assignment import max_weight_matching, ospa_t_labels


def dense_weights(rows, cols, weight, shape):
    out = np.zeros(shape)
    out[rows, cols] = weight
    return out


def dense_ospa_t_cost(n_g, n_t, l, r, both, saving, cp):
    """The matrix today's ospa.track_labels builds."""
    b = dense_weights(l, r, both, (n_g.size, n_t.size))
    s = dense_weights(l, r, saving, (n_g.size, n_t.size))
    return cp * (n_g[:, None] + n_t[None, :] - b) - s


def assert_one_to_one(a, b):
    assert np.unique(a).size == a.size and np.unique(b).size == b.size


def assert_same_total(found, best, integer):
    if integer:
        assert found == best
    else:
        assert found == pytest.approx(best, rel=1e-9, abs=1e-9)


# max_weight_matching (IDF1)


def test_matching_hand_worked_not_greedy():
    # Row 0 sees column 0 for 3 frames and column 1 for 2, row 1 sees column 0 for 2, row 2 nothing of note but
    # column 2 for 1. Greedy takes (0, 0) = 3 and leaves row 1 without a column: 3 + 1 = 4. The optimum swaps:
    # (0, 1) + (1, 0) + (2, 2) = 2 + 2 + 1 = 5.
    rows, cols, weight = np.array([0, 0, 1, 2]), np.array([0, 1, 0, 2]), np.array([3, 2, 2, 1])
    picked = max_weight_matching(rows, cols, weight)
    np.testing.assert_array_equal(picked, [1, 2, 3])
    assert weight[picked].sum() == 5


def test_matching_empty_and_single():
    assert max_weight_matching(np.zeros(0, int), np.zeros(0, int), np.zeros(0)).size == 0
    np.testing.assert_array_equal(max_weight_matching(np.array([4]), np.array([7]), np.array([2.0])), [0])


@pytest.mark.parametrize("integer", [True, False])
def test_matching_equals_dense(integer):
    rng = np.random.default_rng(1 + integer)
    for _ in range(400):
        n_rows, n_cols = rng.integers(1, 13, 2)
        mask = rng.random((n_rows, n_cols)) < rng.random()
        rows, cols = np.nonzero(mask)
        weight = rng.integers(1, 6, rows.size) if integer else rng.uniform(0.01, 5.0, rows.size)
        picked = max_weight_matching(rows, cols, weight)
        assert_one_to_one(rows[picked], cols[picked])
        assert np.all(np.diff(picked) > 0)
        dense = dense_weights(rows, cols, weight, (n_rows, n_cols))
        i, j = linear_sum_assignment(dense, maximize=True)
        assert_same_total(weight[picked].sum(), dense[i, j].sum(), integer)


# ospa_t_labels (OSPA-T step 1)


def labels(n_g, n_t, l, r, both, saving, cp=1.0):
    """ospa_t_labels from the pairs' frames together and savings, as OSPA-T's statistics come: in three blocks."""
    w = cp * np.asarray(both, float) + saving
    return ospa_t_labels(n_g, n_t, lambda: zip(*(np.array_split(a, 3) for a in (l, r, w))), cp)


def test_ospa_t_hand_worked_loser_takes_the_cheapest_free_track():
    # Two people present 5 frames each; track 0 follows both (5 frames present, 5 together with each), closer to
    # person 0 (saving 4) than to person 1 (saving 2); tracks 1 and 2 (3 and 2 frames) meet nobody. cp = 1.
    # cost = n_g + n_t - both - saving: (0, 0) = 5 + 5 - 5 - 4 = 1, (1, 0) = 5 + 5 - 5 - 2 = 3; a person without a
    # pair pays n_g + n_t: 8 with track 1, 7 with track 2. Person 0 takes track 0 (1) and person 1 the cheapest
    # free track, 2 (7): 8; the other way round 3 + 7 = 10.
    n_g, n_t = np.array([5, 5]), np.array([5, 3, 2])
    l, r, both, saving = np.array([0, 1]), np.array([0, 0]), np.array([5, 5]), np.array([4.0, 2.0])
    gi, ti = labels(n_g, n_t, l, r, both, saving)
    np.testing.assert_array_equal(gi, [0, 1])
    np.testing.assert_array_equal(ti, [0, 2])
    # The same with the roles swapped (more gt ids than tracks): every track assigned, sorted by gt index.
    gi, ti = labels(n_t, n_g, r, l, both, saving)
    np.testing.assert_array_equal(gi, [0, 2])
    np.testing.assert_array_equal(ti, [0, 1])


def test_ospa_t_empty_sides():
    for n_g, n_t in (([], [3, 4]), ([3, 4], []), ([], [])):
        gi, ti = labels(np.array(n_g), np.array(n_t), np.zeros(0, int), np.zeros(0, int), np.zeros(0),
                        np.zeros(0))
        assert gi.size == ti.size == 0


def test_ospa_t_without_pairs_takes_the_cheapest_tracks():
    gi, ti = labels(np.array([4, 9]), np.array([7, 1, 3, 2]), np.zeros(0, int), np.zeros(0, int),
                           np.zeros(0), np.zeros(0))
    np.testing.assert_array_equal(gi, [0, 1])
    assert sorted(ti) == [1, 3]


def random_ospa_t(rng, n_gt, n_tr, kind):
    """Random statistics consistent with frames: both <= min(n_g, n_t), saving <= cp * both."""
    top = 3 if kind == "ties" else 12
    n_g, n_t = rng.integers(1, top, n_gt), rng.integers(1, top, n_tr)
    l, r = np.nonzero(rng.random((n_gt, n_tr)) < rng.random())
    both = rng.integers(0, np.minimum(n_g[l], n_t[r]) + 1)
    if kind == "ties":
        saving = np.zeros(l.size)
    elif kind == "integer":
        saving = np.where(rng.random(l.size) < 0.5, rng.integers(0, both + 1), 0).astype(float)
    else:
        saving = np.where(rng.random(l.size) < 0.5, rng.random(l.size) * both, 0.0)
    return n_g, n_t, l, r, both, saving


@pytest.mark.parametrize("kind", ["integer", "ties", "float"])
@pytest.mark.parametrize("shape", ["wide", "tall", "square"])
def test_ospa_t_equals_dense(kind, shape):
    rng = np.random.default_rng(["integer", "ties", "float"].index(kind) * 3 + ["wide", "tall", "square"].index(shape))
    for _ in range(150):
        small, large = sorted(rng.integers(0, 25, 2))
        n_gt, n_tr = {"wide": (small, large), "tall": (large, small), "square": (large, large)}[shape]
        cp = 1.0 if kind != "float" else float(rng.choice([0.5, 1.0, 2.5]))
        inst = random_ospa_t(rng, n_gt, n_tr, kind)
        gi, ti = labels(*inst, cp=cp)
        assert gi.size == ti.size == min(n_gt, n_tr)
        assert_one_to_one(gi, ti)
        assert np.all(np.diff(gi) > 0)
        cost = dense_ospa_t_cost(*inst, cp)
        i, j = linear_sum_assignment(cost)
        assert_same_total(cost[gi, ti].sum(), cost[i, j].sum(), kind != "float")


def test_ospa_t_balances_tied_optima(monkeypatch):
    # Where L peaks at a tie the matchings found on either side are unbalanced; the symmetric-difference step must
    # run on some of these instances and still give the dense optimum.
    calls = []
    balance = assignment._balance
    monkeypatch.setattr(assignment, "_balance", lambda *a: calls.append(1) or balance(*a))
    rng = np.random.default_rng(7)
    for _ in range(300):
        inst = random_ospa_t(rng, 30, 12, "integer")
        gi, ti = labels(*inst)
        cost = dense_ospa_t_cost(*inst, 1.0)
        i, j = linear_sum_assignment(cost)
        assert cost[gi, ti].sum() == cost[i, j].sum()
    assert len(calls) >= 3


def test_ospa_t_searches_again_with_more_pairs_where_the_price_lands_above_its_reach(monkeypatch):
    # The first search sees only the pairs useful below the lowest level of b; where its maximiser lies above that,
    # the search runs again with the pairs useful up to there, and still finds the dense optimum.
    searches = []
    search = assignment._search
    monkeypatch.setattr(assignment, "_search", lambda n, rows, *a: searches.append(rows.size) or search(n, rows, *a))
    rng = np.random.default_rng(11)
    again = 0
    for _ in range(200):
        searches.clear()
        inst = random_ospa_t(rng, int(rng.integers(1, 25)), int(rng.integers(1, 25)), "integer")
        gi, ti = labels(*inst)
        cost = dense_ospa_t_cost(*inst, 1.0)
        i, j = linear_sum_assignment(cost)
        assert cost[gi, ti].sum() == cost[i, j].sum()
        again += len(searches) > 1
        assert searches == sorted(searches)  # each search sees at least the pairs of the one before
    assert again >= 20
