"""The group stage by hand: the coherent-motion indicators and SPENCER's gates, its released model's strengths, group
detection with and without chaining, and composition tracking through a split, a merge and a member swap."""

import numpy as np
import pytest

from pipeline.groups import CoherentMotionGroups
from pipeline.groups.detection import LINKAGES, detect_groups
from pipeline.groups.relations import (GATED_STRENGTH, SPENCER, LongTermRelations, RelationEstimator, indicators,
                                       monomial_powers, save_model, tabulate)
from pipeline.groups.tracking import CompositionTracker
from pipeline.types import TrackedPersons


def tracks(ids, position, velocity, stamp=0.0) -> TrackedPersons:
    n = len(ids)
    return TrackedPersons(stamp, "odom", np.asarray(ids, np.int64), np.ones(n, bool), np.zeros(n, bool),
                          np.full(n, -1, np.int64), np.asarray(position, float).reshape(-1, 2),
                          np.asarray(velocity, float).reshape(-1, 2), np.zeros((n, 2, 2)), np.zeros((n, 2, 2)),
                          np.zeros(n))


def test_indicators_by_hand():
    pos = [[0, 0], [3, 4], [1, 0], [0, 2]]
    # east at 1 m/s; heading 170 deg at 0.5; north at 1; 0.05 m/s north: slower than 0.1, heading taken as 0
    vel = [[1, 0], [0.5 * np.cos(np.radians(170)), 0.5 * np.sin(np.radians(170))], [0, 1], [0, 0.05]]
    i, j, x = indicators(np.array(pos, float), np.array(vel, float))
    got = {(a, b): row for a, b, row in zip(i, j, x)}
    assert got[(0, 1)] == pytest.approx([5.0, 0.5, np.radians(170)])
    assert got[(0, 2)] == pytest.approx([1.0, 0.0, np.pi / 2])
    assert got[(0, 3)] == pytest.approx([2.0, 0.95, 0.0])  # the slow track "heads" east, as the mover
    assert got[(1, 3)] == pytest.approx([np.hypot(3, 2), 0.45, np.radians(170)])
    assert got[(2, 3)] == pytest.approx([np.hypot(1, 2), 0.95, np.pi / 2])
    # headings 170 and -170 deg are 20 deg apart, across the wrap
    unit = np.array([[np.cos(np.radians(a)), np.sin(np.radians(a))] for a in (170, -170)])
    _, _, x = indicators(np.zeros((2, 2)), unit)
    assert x[0, 2] == pytest.approx(np.radians(20))


def test_spencer_released_model_and_its_gates():
    # f = 3.03765 - 1.875462 d - 0.559679 dv - 0.913379 dtheta; P = 1 / (1 + exp(-1.55322 f - 0.0123641))
    for x, p in (((0, 0, 0), 0.99126), ((1, 0, 0), 0.86027), ((1.5, 0.2, 0.2), 0.47587), ((2, 0.5, 0.5), 0.096259)):
        f = 3.03765 - 1.875462017868918 * x[0] - 0.5596792850946883 * x[1] - 0.913378846604351 * x[2]
        got = SPENCER.predict_proba(np.array([x], float))[0]
        assert got == pytest.approx(1 / (1 + np.exp(-1.55322 * f - 0.0123641)))
        assert got == pytest.approx(p, abs=5e-5)
    est = RelationEstimator("spencer")
    # gates are strict: 3 m apart is classified, 3.01 m gated; speeds 1.01 m/s apart gated; headings past pi/4 gated
    pos = np.array([[0, 0], [3.0, 0], [0, 3.01], [-1, 0]], float)
    vel = np.array([[1, 0], [1, 0], [1, 0], [1.0 * np.cos(0.8), 1.0 * np.sin(0.8)]])
    i, j, s = est.strengths(pos, vel)
    got = dict(zip(zip(i, j), s))
    assert got[(0, 1)] == pytest.approx(SPENCER.predict_proba(np.array([[3.0, 0, 0]]))[0])
    assert got[(0, 2)] == GATED_STRENGTH and got[(0, 3)] == GATED_STRENGTH  # 3.01 m; 0.8 rad > pi/4
    i, j, s = est.strengths(np.array([[0, 0], [1, 0]], float), np.array([[0.2, 0], [1.21, 0]]))
    assert s[0] == GATED_STRENGTH  # 1.01 m/s apart


def test_a_tabulated_classifier_gives_the_value_at_the_nearest_grid_point(tmp_path):
    # SPENCER's model on a grid of 0.5 m, 0.5 m/s and pi/8 rad up to its gates (7 x 3 x 3 points), one sample a cell
    table = tabulate(SPENCER, np.array([3.0, 1.0, np.pi / 4]), np.array([0.5, 0.5, np.pi / 8]), samples=1)
    assert table.values.shape == (7, 3, 3)
    np.testing.assert_allclose(table.upper, [3.0, 1.0, np.pi / 4])
    # (1.2, 0.3, 0.1) is nearest (1.0, 0.5, 0.0); (2.9, 0.74, 0.7) nearest (3.0, 0.5, pi/4)
    x = np.array([[1.2, 0.3, 0.1], [2.9, 0.74, 0.7]])
    nodes = np.array([[1.0, 0.5, 0.0], [3.0, 0.5, np.pi / 4]])
    np.testing.assert_allclose(table.predict_proba(x), SPENCER.predict_proba(nodes), rtol=1e-6)
    # the estimator applies it to the pairs inside the gates, and refuses gates wider than the table
    path = tmp_path / "table.npz"
    save_model(path, table, {"test": True})
    i, j, s = RelationEstimator(str(path)).strengths(np.array([[0, 0], [1.2, 0]]), np.array([[1.0, 0], [1.3, 0]]))
    assert s[0] == pytest.approx(SPENCER.predict_proba(np.array([[1.0, 0.5, 0.0]]))[0], rel=1e-6)
    with pytest.raises(ValueError, match=r"tabulated up to the gates \[3.0, 1.0, 0.7854\]"):
        RelationEstimator(str(path), max_distance=4.0)


def test_a_table_holds_each_cells_mean():
    # P = d^2 / 9 over a cell of 0.3 m, sampled at d + (-1/3, 0, 1/3) 0.3 m: the mean is (d^2 + 2 (0.1)^2 / 3) / 9
    class Square:
        @staticmethod
        def predict_proba(x):
            return x[:, 0] ** 2 / 9

    table = tabulate(Square, np.array([3.0, 1.0, 0.5]), np.array([0.3, 0.5, 0.5]))
    d = 0.3 * np.arange(11)
    np.testing.assert_allclose(table.values[:, 1, 0], (d ** 2 + 2 * 0.01 / 3) / 9, rtol=1e-6)


def test_monomials_of_degree_three_are_the_19_products():
    powers = monomial_powers(3, 3)
    assert len(powers) == 19 and set(powers.sum(axis=1)) == {1, 2, 3}
    assert len({tuple(p) for p in powers}) == 19


def queue_relations(n=5, spacing=0.8):
    """Standing strangers in a line ``spacing`` apart, strengths from SPENCER's model (speeds and headings 0)."""
    pos = np.column_stack([spacing * np.arange(n), np.zeros(n)])
    return RelationEstimator("spencer").strengths(pos, np.zeros((n, 2)))


def test_single_linkage_chains_a_queue_and_complete_linkage_does_not():
    i, j, s = queue_relations()
    # f = 3.03765 - 1.875462 d: neighbours 0.8 m apart 1/(1 + exp(-1.55322 x 1.53728 - 0.01236)) = 0.9168; two apart
    # (1.6 m) 0.5174; three (2.4 m) 0.0944; four (3.2 m) gated
    assert s[(i == 0) & (j == 1)][0] == pytest.approx(0.9168, abs=1e-4)
    assert s[(i == 0) & (j == 2)][0] == pytest.approx(0.5174, abs=1e-4)
    assert s[(i == 0) & (j == 4)][0] == GATED_STRENGTH
    labels = detect_groups(5, i, j, s, 0.5, "single")
    assert len(set(labels)) == 1  # SPENCER: the whole queue is one group
    labels = detect_groups(5, i, j, s, 0.5, "complete")
    # complete linkage: a group needs every pair at 0.5 or more; triples of neighbours (0-1-2) pass, no more
    assert max(np.bincount(labels)) <= 3 and len(set(labels)) >= 2
    # a clique of three stays one group under every linkage
    pos = np.array([[0, 0], [0.8, 0], [0.4, 0.6]])
    i, j, s = RelationEstimator("spencer").strengths(pos, np.tile([1.0, 0.0], (3, 1)))
    for method in ("single", "complete", "average"):
        assert len(set(detect_groups(3, i, j, s, 0.5, method))) == 1


def test_average_linkage_by_hand():
    # 0-1 and 2-3 strongly related (0.9), 1-2 at 0.6, the rest missing (strength 0): single links all four,
    # average merges {0,1} and {2,3} only if their mean distance 1 - (0.6 + 0 + 0 + 0) / 4 = 0.85 <= 0.5: no
    i, j, s = np.array([0, 2, 1]), np.array([1, 3, 2]), np.array([0.9, 0.9, 0.6])
    assert len(set(detect_groups(4, i, j, s, 0.5, "single"))) == 1
    labels = detect_groups(4, i, j, s, 0.5, "average")
    assert labels[0] == labels[1] and labels[2] == labels[3] and labels[0] != labels[2]


def groups_of(result):
    return {g: set(result.member_track[result.member_group == g].tolist()) for g in result.group_id.tolist()}


def step(tracker, stamp, clusters):
    ids = np.array(sorted(t for c in clusters for t in c), np.int64)
    labels = np.array([next(k for k, c in enumerate(clusters) if t in c) for t in ids])
    return tracker.update(stamp, "odom", ids, np.column_stack([ids, np.zeros(len(ids))]).astype(float), labels)


def test_composition_tracking_through_a_split_a_merge_and_a_swap():
    tr = CompositionTracker()
    g = step(tr, 0.0, [{1, 2, 3, 4}, {5}])
    assert groups_of(g) == {0: {1, 2, 3, 4}} and g.centroid[0] == pytest.approx([2.5, 0]) and g.age[0] == 0
    assert step(tr, 1.0, [{1, 2, 3, 4}, {5}]).age[0] == 1.0  # the same members: one second old
    # split: both halves are subsets of {1,2,3,4}; {1,2} (smallest id first) keeps its id, {3,4} gets a new one
    g = step(tr, 2.0, [{1, 2}, {3, 4}, {5}])
    assert groups_of(g) == {0: {1, 2}, 1: {3, 4}} and list(g.age) == [0.0, 0.0]  # new member sets: age restarts
    # merge: subsets {1,2} (id 0) and {3,4} (id 1) of equal size and age, and the remembered {1,2,3,4} (id 0,
    # larger): id 0
    g = step(tr, 3.0, [{1, 2, 3, 4}, {5}])
    assert groups_of(g) == {0: {1, 2, 3, 4}}
    assert g.age[0] == 3.0  # {1,2,3,4} has existed since 0 s while remembered (SPENCER's age)
    # member swap: {1,5} is neither a subset nor a superset of any remembered set: a new id
    g = step(tr, 4.0, [{1, 5}, {2}, {3}, {4}])
    assert groups_of(g) == {2: {1, 5}}
    # the larger of two candidates wins, and one id is never given twice in a cycle
    tr = CompositionTracker()
    step(tr, 0.0, [{1, 2}, {3, 4, 5}])
    g = step(tr, 1.0, [{1, 2, 3, 4, 5}])
    assert groups_of(g) == {1: {1, 2, 3, 4, 5}}


def test_composition_memory_forgets_the_oldest():
    tr = CompositionTracker(memory=2)
    step(tr, 0.0, [{1, 2}])
    step(tr, 1.0, [{3, 4}])
    step(tr, 2.0, [{5, 6}])  # {1,2} is pushed out of the memory of two
    assert groups_of(step(tr, 3.0, [{1, 2}])) == {3: {1, 2}}


def test_long_term_relations_rise_and_fall_at_spencers_rates():
    lt = LongTermRelations()
    a, b = np.array([1]), np.array([2])
    assert lt.smooth(0.0, a, b, np.array([0.9]), np.array([1.0]))[0] == 0.0  # new pairs start at 0
    assert lt.smooth(3.5, a, b, np.array([0.9]), np.array([1.0]))[0] == pytest.approx(0.5)  # 0.5 in 3.5 s
    assert lt.smooth(4.5, a, b, np.array([0.1]), np.array([1.0]))[0] == pytest.approx(0.5 - 0.5 / 40)  # slow decay
    assert lt.smooth(5.5, a, b, np.array([0.9]), np.array([4.5]))[0] == pytest.approx(0.4875 - 0.1)  # far: fast
    assert lt.smooth(6.5, np.array([2]), np.array([3]), np.array([0.9]), np.array([1.0]))[0] == pytest.approx(
        0.5 / 3.5)  # pair (1, 2) forgotten; (2, 3) new, one second of growth from 0


def test_the_stage_groups_walkers_side_by_side_and_not_a_passer_by():
    stage = CoherentMotionGroups(model="spencer")
    t = tracks([4, 7, 9], [[0, 0], [0, 0.8], [1.0, 2.0]], [[1.2, 0], [1.2, 0], [-1.2, 0]])
    relations, groups = stage.update(0.0, t)
    assert list(zip(relations.track_a, relations.track_b)) == [(4, 7), (4, 9), (7, 9)]
    assert relations.strength[1] == relations.strength[2] == GATED_STRENGTH  # opposite headings
    assert groups_of(groups) == {0: {4, 7}} and groups.centroid[0] == pytest.approx([0, 0.4])


def test_components_are_scipys_connected_components_on_random_graphs():
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from pipeline.groups.detection import components

    rng = np.random.default_rng(1)
    for _ in range(200):
        n = int(rng.integers(1, 60))
        m = int(rng.integers(0, 2 * n))
        a, b = rng.integers(0, n, m), rng.integers(0, n, m)
        ours = components(n, a, b)
        _, theirs = connected_components(coo_matrix((np.ones(m), (a, b)), shape=(n, n)), directed=False)
        # the same partition, labelled in the order of each component's smallest node
        assert (ours[:, None] == ours[None]).tolist() == (theirs[:, None] == theirs[None]).tolist()
        first = [int(np.flatnonzero(ours == k)[0]) for k in range(ours.max() + 1)]
        assert first == sorted(first)


@pytest.mark.parametrize("model", ["svm", "forest", "spencer"])
def test_a_passport_queue_of_strangers_is_one_group_only_with_single_linkage(model):
    # eight strangers standing in line 0.7 m apart (the airport's queue spacing), their tracks jittering by 5 cm and
    # 5 cm/s: every classifier relates neighbours (standing 0.7 m apart is what a conversation group looks like too),
    # so SPENCER's single linkage chains the whole queue; complete linkage keeps groups to neighbours
    rng = np.random.default_rng(3)
    n = 8
    line = np.column_stack([np.zeros(n), 0.7 * np.arange(n)])
    queue = tracks(np.arange(1, n + 1), line + rng.normal(0, 0.05, (n, 2)), rng.normal(0, 0.05, (n, 2)))
    _, single = CoherentMotionGroups(model=model, linkage="single").update(0.0, queue)
    assert [len(m) for m in groups_of(single).values()] == [n]
    _, complete = CoherentMotionGroups(model=model, linkage="complete").update(0.0, queue)
    assert max(len(m) for m in groups_of(complete).values()) <= 3


@pytest.mark.parametrize("method", ["complete", "average"])
def test_detection_cuts_as_scipys_fcluster_of_the_whole_tree(method):
    # detect_groups clusters only the tracks with a pair at the threshold and cuts the tree itself (cut_tree): the
    # partition must be scipy's fcluster of the tree of all tracks, pairs left out of the relations at strength 0
    from scipy.cluster.hierarchy import fcluster, linkage

    rng = np.random.default_rng(2)
    for _ in range(200):
        k = int(rng.integers(2, 16))
        i, j = np.triu_indices(k, 1)
        strength = rng.uniform(0, 0.8, len(i))
        given = rng.random(len(i)) < 0.6
        ours = detect_groups(k, i[given], j[given], strength[given], 0.5, method)
        theirs = fcluster(linkage(1.0 - np.where(given, strength, 0.0), method=method), 0.5, criterion="distance")
        assert (ours[:, None] == ours[None]).tolist() == (theirs[:, None] == theirs[None]).tolist()
        assert sorted(set(ours.tolist())) == list(range(len(set(ours.tolist()))))


def test_gates_in_one_pass_by_hand():
    from pipeline.groups.relations import _gated

    # pairs in triu order: (0, 1) place 0, 3 m apart (the gate is inclusive), speeds 1 and 1.5, headings 0 and 0.5
    # rad: kept; (0, 2) place 1, 1 m apart but speeds 1.5 m/s apart: gated; (1, 2) place 2, hypot(3, 1) m: gated
    pos = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 1.0]])
    at, x = _gated(pos, np.array([1.0, 1.5, 2.5]), np.array([0.0, 0.5, 0.0]), (3.0 + 1e-9) ** 2,
                   np.array([3.0, 1.0, np.pi / 4]))
    assert at.tolist() == [0] and x.tolist() == [[3.0, 0.5, 0.5]]
    # headings 3 and -3 rad are 2 pi - 6 apart across the wrap
    at, x = _gated(pos[:2] / 3, np.ones(2), np.array([3.0, -3.0]), 1.0, np.array([3.0, 1.0, np.pi / 4]))
    assert at.tolist() == [0] and x[0, 2] == 2 * np.pi - 6.0


def test_components_by_hand():
    from pipeline.groups.detection import components

    # edges 4-1, 1-3 and a loop at 5: {0}, {1, 3, 4}, {2}, {5}, numbered by their smallest node
    assert components(6, np.array([4, 1, 5]), np.array([1, 3, 5])).tolist() == [0, 1, 2, 1, 1, 3]
    assert components(3, np.zeros(0, np.int64), np.zeros(0, np.int64)).tolist() == [0, 1, 2]


def test_nearest_neighbour_chain_and_its_cut_by_hand():
    from pipeline.groups.detection import cut, nn_chain

    # five points: 0-1 and 2-3 at 0.25, 1-2 0.375, 0-2 0.5, 1-3 0.625, 0-3 0.875, point 4 at 1 from all. The chain
    # from 0 meets 1, mutual: merge (0, 1) at 0.25; complete linkage: {0,1} to 2 max(0.5, 0.375), to 3
    # max(0.875, 0.625). The chain from 1 goes to 2 (0.5), then 3 (0.25), mutual: (2, 3) at 0.25; {0,1}-{2,3}
    # max(0.5, 0.875); last the rest and 4 at 1.
    d = {(0, 1): 0.25, (2, 3): 0.25, (1, 2): 0.375, (0, 2): 0.5, (1, 3): 0.625, (0, 3): 0.875}
    i, j = np.triu_indices(5, 1)
    distance = np.array([d.get((a, b), 1.0) for a, b in zip(i, j)])
    first, second, height = nn_chain(distance, 5, False)
    assert list(zip(first.tolist(), second.tolist(), height.tolist())) == [(0, 1, 0.25), (2, 3, 0.25),
                                                                           (1, 3, 0.875), (3, 4, 1.0)]
    # average linkage: {0,1}-2 (0.5 + 0.375) / 2, {0,1}-3 (0.875 + 0.625) / 2, then (0.4375 + 0.75) / 2
    assert nn_chain(distance, 5, True)[2].tolist() == [0.25, 0.25, 0.59375, 1.0]
    # cut at 0.5: the point left alone first, then the clusters in the order of the merge that made them
    assert cut(first, second, height, 5, 0.5).tolist() == [1, 1, 2, 2, 0]
    assert cut(first, second, height, 5, 0.1).tolist() == [0, 1, 2, 3, 4]


def test_the_chain_keeps_the_previous_of_equal_neighbours():
    from pipeline.groups.detection import cut, nn_chain

    # 0-1 and 1-2 both 0.25 apart, 0-2 0.75: from 0 the chain meets 1, whose nearest is 0 or 2 at a tie; scipy
    # keeps the previous link (0), so (0, 1) merge first and 2 joins only at max(0.75, 0.25): cut at 0.5, {0, 1}
    # and {2}, not {0} and {1, 2}
    first, second, height = nn_chain(np.array([0.25, 0.75, 0.25]), 3, False)
    assert list(zip(first.tolist(), second.tolist(), height.tolist())) == [(0, 1, 0.25), (1, 2, 0.75)]
    assert cut(first, second, height, 3, 0.5).tolist() == [1, 1, 0]


def test_composition_tracking_prefers_the_first_remembered_among_equals_and_compares_whole_sets():
    tr = CompositionTracker()
    step(tr, 0.0, [{1, 2}, {3, 4}])  # ids 0 and 1, one age, one size
    # {1, 2, 3, 4} holds both: equal size and age, so the first remembered ({1, 2}, id 0) gives its id
    assert groups_of(step(tr, 1.0, [{1, 2, 3, 4}])) == {0: {1, 2, 3, 4}}
    # 65 and 1 share their signature bit (65 = 1 modulo 64): {2, 65} is no subset of {1, 2, 3, 4}, a new id
    assert groups_of(step(tr, 2.0, [{2, 65}])) == {2: {2, 65}}
    # a cluster wider than the memory's rows so far (8 members) is remembered whole: the same ten keep their id
    ten = set(range(100, 110))
    g = step(tr, 3.0, [ten])
    assert groups_of(step(tr, 4.0, [ten])) == groups_of(g) == {3: ten}


def test_composition_memory_forgets_the_set_seen_longest_ago():
    tr = CompositionTracker(memory=2)
    step(tr, 0.0, [{1, 2}])  # id 0
    step(tr, 1.0, [{3, 4}])  # id 1
    step(tr, 2.0, [{1, 2}])  # seen again: now the newest
    step(tr, 3.0, [{5, 6}])  # id 2: {3, 4}, seen longest ago, is forgotten, not {1, 2}
    assert groups_of(step(tr, 4.0, [{1, 2}, {3, 4}])) == {0: {1, 2}, 3: {3, 4}}


def test_detect_groups_and_the_tracker_reject_rows_they_do_not_have():
    for method in LINKAGES:
        with pytest.raises(ValueError, match="0 <= "):
            detect_groups(3, np.array([0]), np.array([3]), np.array([0.9]), method=method)  # row 3 of 3
        with pytest.raises(ValueError, match="one entry each"):
            detect_groups(3, np.array([0, 1]), np.array([1, 2]), np.array([0.9]), method=method)
    with pytest.raises(ValueError, match="one entry each"):
        CompositionTracker().update(0.0, "map", np.array([1, 2]), np.zeros((2, 2)), np.array([0]))
