"""The linear sum assignment kernel (pipeline/lsap.py): optima worked by hand, the errors, and the very pairs of
SciPy's solver (the same algorithm, whose choices among tied optima the project's outputs rest on) on many random
matrices with ties, forbidden pairs and both shapes."""

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment as scipy_assignment

from pipeline.lsap import linear_sum_assignment


def test_optima_worked_by_hand():
    # the six permutations cost 18, 18, 7, 15, 12 and 20: the least is rows 0, 1, 2 to columns 1, 0, 2 (4 + 1 + 2)
    cost = np.array([[9.0, 4.0, 8.0], [1.0, 7.0, 6.0], [5.0, 3.0, 2.0]])
    rows, cols = linear_sum_assignment(cost)
    assert rows.tolist() == [0, 1, 2] and cols.tolist() == [1, 0, 2]
    assert rows.dtype == np.int64 and cols.dtype == np.int64
    # the greatest, 20: columns 2, 1, 0 (8 + 7 + 5)
    assert linear_sum_assignment(cost, maximize=True)[1].tolist() == [2, 1, 0]
    # wide (2 x 3) and tall (3 x 2): every row (column) of the shorter side assigned, rows ascending
    wide = np.array([[5.0, 1.0, 3.0], [2.0, 9.0, 1.5]])
    assert [a.tolist() for a in linear_sum_assignment(wide)] == [[0, 1], [1, 2]]  # 1 + 1.5
    assert [a.tolist() for a in linear_sum_assignment(wide.T)] == [[1, 2], [0, 1]]
    # a forbidden pair (inf) is avoided even at a greater total (1 + 100 where 2 + inf)
    assert linear_sum_assignment(np.array([[1.0, np.inf], [2.0, 100.0]]))[1].tolist() == [0, 1]
    # a constant matrix gives the identity; an empty one nothing
    assert linear_sum_assignment(np.zeros((3, 3)))[1].tolist() == [0, 1, 2]
    assert [a.size for a in linear_sum_assignment(np.zeros((0, 4)))] == [0, 0]
    assert [a.size for a in linear_sum_assignment(np.zeros((4, 0)))] == [0, 0]


@pytest.mark.parametrize("cost, message", [(np.zeros(3), "2-D"), (np.array([[np.nan]]), "NaN or -inf"),
                                           (np.array([[-np.inf, 1.0]]), "NaN or -inf"),
                                           (np.array([[np.inf, np.inf], [1.0, 2.0]]), "infeasible")])
def test_bad_matrices_are_refused(cost, message):
    with pytest.raises(ValueError, match=message):
        linear_sum_assignment(cost)


def test_the_pairs_are_scipys_ties_included():
    rng = np.random.default_rng(11)
    for trial in range(6000):
        n, m = rng.integers(0, 9, 2)
        kind = trial % 4
        if kind == 0:  # small integers: many tied optima
            cost = rng.integers(0, 4, (n, m)).astype(float)
        elif kind == 1:
            cost = rng.random((n, m))
        elif kind == 2:  # forbidden pairs, possibly no full assignment
            cost = rng.random((n, m))
            cost[rng.random((n, m)) < 0.4] = np.inf
        else:
            cost = np.round(rng.normal(0, 3, (n, m)), 1)
        maximize = trial % 3 == 0 and kind != 2
        try:
            expected = scipy_assignment(cost, maximize=maximize)
        except ValueError:
            with pytest.raises(ValueError):
                linear_sum_assignment(cost, maximize=maximize)
            continue
        got = linear_sum_assignment(cost, maximize=maximize)
        assert np.array_equal(got[0], expected[0]) and np.array_equal(got[1], expected[1])
