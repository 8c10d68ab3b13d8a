"""SPENCER's duplicate-track guards (pipeline/tracking/duplicates.py) on hand-worked cases."""

import numpy as np

from pipeline.tracking.duplicates import DuplicateGuard


def history(*tracks):
    """past [10, 2, n] from each track's 10 positions [(x, y), ...]."""
    return np.stack([np.asarray(t, float) for t in tracks], axis=-1)


def test_two_tracks_close_in_seven_of_ten_cycles_are_duplicates_and_the_weaker_goes():
    a = [(k * 0.05, 0.0) for k in range(10)]
    b = [(k * 0.05, 0.10 if k < 7 else 0.5) for k in range(10)]  # 0.10 m apart in 7 cycles: duplicates
    c = [(k * 0.05, 0.10 if k < 6 else 0.5) for k in range(10)]  # in 6 only: not
    guard = DuplicateGuard()
    full = np.full(2, 10)
    assert guard.duplicates(history(a, b), full, np.array([30, 12])).tolist() == [False, True]
    assert guard.duplicates(history(a, b), full, np.array([12, 30])).tolist() == [True, False]
    assert guard.duplicates(history(a, b), full, np.array([20, 20])).tolist() == [False, True]  # tie: the younger
    assert guard.duplicates(history(a, c), full, np.array([30, 12])).tolist() == [False, False]
    # 0.15 m is not within 0.15 m (SPENCER's strict <)
    d = [(k * 0.05, 0.15) for k in range(10)]
    assert guard.duplicates(history(a, d), full, np.array([30, 12])).tolist() == [False, False]


def test_a_track_without_ten_cycles_of_history_is_never_a_duplicate_and_zero_turns_the_guard_off():
    a = [(0.0, 0.0)] * 10
    guard = DuplicateGuard()
    assert not guard.duplicates(history(a, a), np.array([10, 9]), np.array([5, 50])).any()
    assert guard.duplicates(history(a, a, a), np.array([10, 10, 10]), np.array([5, 50, 7])).tolist() == \
        [True, False, True]
    assert not DuplicateGuard(distance=0.0).duplicates(history(a, a), np.array([10, 10]), np.array([5, 50])).any()


def test_a_new_track_needs_clearance_from_recently_matched_tracks_only():
    guard = DuplicateGuard()
    xy = np.array([[0.0, 5.0], [0.0, 0.0]])  # tracks at (0, 0) and (5, 0)
    z = np.array([[0.2, 0.0], [0.3, 0.0], [5.1, 0.0]])
    assert guard.blocked(z, xy, np.array([0, 0])).tolist() == [True, False, True]
    assert guard.blocked(z, xy, np.array([4, 5])).tolist() == [True, False, False]  # missed 5 in a row: not recent
    assert not DuplicateGuard(clearance=0.0).blocked(z, xy, np.array([0, 0])).any()


def test_the_tracker_drops_a_track_that_multi_association_drove_onto_a_neighbour():
    """Two people walk side by side 0.4 m apart; person B's detections stop (B hidden for good at cycle 30). With
    NN with multiple associations, B's track takes A's detections and follows A for ever: two tracks on one person.
    With SPENCER's duplicate deletion it goes once the two have been within 0.15 m for 7 of 10 cycles."""
    from pipeline.tracking.association import MultiNN
    from pipeline.tracking.nnt import NearestNeighbourTracker
    from pipeline.types import DetectedPersons

    def run(duplicates=None):
        tracker = NearestNeighbourTracker(association=MultiNN(), duplicates=duplicates)
        counts = []
        for k in range(120):
            xy = [(0.05 * k, 0.0)] + ([(0.05 * k, 0.4)] if k < 30 else [])
            m = len(xy)
            cov = np.zeros((m, 3, 3))
            cov[:, 0, 0] = cov[:, 1, 1] = 0.1  # seed 000 Sec. IV-C
            cov[:, 2, 2] = 1.0
            pos = np.column_stack([np.array(xy), np.zeros(m)])
            out = tracker.update(0.04 * k, DetectedPersons(0.04 * k, "odom", "laser", np.arange(m), pos, cov,
                                                           np.ones(m)))
            counts.append(len(out.track_id))
        return counts

    plain, guarded = run(), run(DuplicateGuard(clearance=0.0))
    assert plain[25] == guarded[25] == 2
    assert plain[-1] == 2  # B's track rides on A's detections
    assert guarded[-1] == 1


def test_the_sorted_search_finds_what_comparing_every_pair_finds():
    rng = np.random.default_rng(3)
    guard = DuplicateGuard()
    for trial in range(50):
        n = int(rng.integers(2, 60))
        base = rng.uniform(0, 3, (1, 2, n))  # crowded: many pairs near 0.15 m
        past = base + rng.normal(0, 0.08, (10, 2, n))
        filled = rng.integers(8, 12, n)
        hits = rng.integers(1, 5, n)
        full = np.flatnonzero(filled >= 10)
        d2 = ((past[:, :, full, None] - past[:, :, None, full]) ** 2).sum(axis=1)
        close = np.triu(np.count_nonzero(d2 < 0.15 ** 2, axis=0) >= 7, 1)
        i, j = np.nonzero(close)
        expected = np.zeros(n, bool)
        expected[np.where(hits[full[i]] < hits[full[j]], full[i], full[j])] = True
        assert np.array_equal(guard.duplicates(past, filled, hits), expected)
