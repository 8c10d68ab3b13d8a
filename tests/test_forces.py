"""The crowd's compiled force kernels and the wall grid, each against values worked by hand."""

import math

import numpy as np
import pytest

from crowdsim.crowd import forces
from crowdsim.crowd.contacts import _from_space, _to_space, push_out_of_walls
from crowdsim.envs.world import _contacts
from scenarios.wall_grid import WallGrid, near_walls

COS_100 = math.cos(math.radians(100))  # half of the default 200 degree field of view
A, GAMMA, LAM, N, N_PRIME = 4.5, 0.35, 2.0, 2.0, 3.0  # Moussaid et al. 2009, the scenario defaults


def test_seen_weight_is_one_for_forces_from_within_the_field_of_view():
    # heading +x: a push from ahead (force -x) and one from the side are seen; one from behind (force +x) is not
    assert forces.seen_weight(1.0, 0.0, -2.0, 0.0, COS_100, 0.46) == 1.0
    assert forces.seen_weight(1.0, 0.0, 0.0, 2.0, COS_100, 0.46) == 1.0
    assert forces.seen_weight(1.0, 0.0, 2.0, 0.0, COS_100, 0.46) == 0.46


def test_moussaid_pair_head_on_only_brakes():
    # j 1 m straight ahead, both still: e = D = t = (1, 0), theta = 0, B = gamma: f = -A exp(-1 / 0.35) along x
    reach = forces.moussaid_reach(A, GAMMA)
    bx, by, sx, sy = forces.moussaid_pair(1.0, 0.0, 0.0, 0.0, A, LAM, GAMMA, N, N_PRIME, reach)
    assert bx == pytest.approx(-4.5 * 0.057433, rel=1e-4)  # exp(-2.857) = 0.057433
    assert (by, sx, sy) == (0.0, 0.0, 0.0)


def test_moussaid_pair_turns_away_from_a_person_to_the_side():
    # i walks +x at 0.5 m/s, j stands 1 m to its left: D = e - lam (v_j - v_i) = (0, 1) + 2 (0.5, 0) = (1, 1),
    # t = (1, 1)/sqrt 2, theta = +45 deg, B = 0.35 sqrt 2 = 0.49497, A exp(-1 / B) = 4.5 x 0.13262 = 0.59677;
    # B theta = 0.38876: braking -0.59677 exp(-(3 x 0.38876)^2) = -0.59677 x 0.25661 along t, turning
    # -0.59677 exp(-(2 x 0.38876)^2) = -0.59677 x 0.54631 along n_left = (-1, 1)/sqrt 2 (to the right, away from j)
    reach = forces.moussaid_reach(A, GAMMA)
    bx, by, sx, sy = forces.moussaid_pair(0.0, 1.0, -0.5, 0.0, A, LAM, GAMMA, N, N_PRIME, reach)
    brake, turn = 0.59677 * 0.25661 / math.sqrt(2), 0.59677 * 0.54631 / math.sqrt(2)
    assert (bx, by) == pytest.approx((-brake, -brake), rel=1e-3)
    assert (sx, sy) == pytest.approx((turn, -turn), rel=1e-3)


def test_moussaid_pair_beyond_its_reach_gives_nothing():
    # A exp(-d / (gamma |D|)) < 0.005 m/s^2 once d > 0.35 ln(900) = 2.381 m for two still persons
    reach = forces.moussaid_reach(A, GAMMA)
    assert reach == pytest.approx(0.35 * math.log(900))
    assert forces.moussaid_pair(2.39, 0.0, 0.0, 0.0, A, LAM, GAMMA, N, N_PRIME, reach) == (0.0, 0.0, 0.0, 0.0)
    assert forces.moussaid_pair(2.37, 0.0, 0.0, 0.0, A, LAM, GAMMA, N, N_PRIME, reach)[0] < 0


def test_moussaid2009_sums_each_pair_on_both_persons_with_their_view_weights():
    # two still persons 1 m apart on x, both heading +x: i (behind) sees j ahead and is pushed back with the full
    # 0.25844 m/s^2; j is pushed forward by i behind it, out of view: 0.46 of it. A third person 6 m away is beyond
    # the 5 m interaction range.
    pos = np.array([[0.0, 0.0], [1.0, 0.0], [7.0, 0.0]])
    vel = np.zeros((3, 2))
    heading = np.tile([1.0, 0.0], (3, 1))
    walking = np.ones(3, bool)
    args = (5.0, A, LAM, GAMMA, N, N_PRIME, walking, heading, 200.0, 0.46)
    f = forces.moussaid2009(pos, vel, np.arange(3), *args)
    push = 4.5 * math.exp(-1 / 0.35)
    assert f == pytest.approx(np.array([[-push, 0], [0.46 * push, 0], [0, 0]]))
    assert np.array_equal(f, forces.moussaid2009(pos, vel, np.array([2, 1, 0]), *args))  # one pair: any order


def test_standing_persons_feel_no_turning_term():
    # the side-by-side case above: walking, i is turned to the right; standing, it is only braked
    pos, vel = np.array([[0.0, 0.0], [0.0, 1.0]]), np.array([[0.5, 0.0], [0.0, 0.0]])
    heading = np.array([[1.0, 0.0], [1.0, 0.0]])
    f = {}
    for walking in (True, False):
        f[walking] = forces.moussaid2009(pos, vel, np.arange(2), 5.0, A, LAM, GAMMA, N, N_PRIME,
                                         np.array([walking, walking]), heading, 360.0, 1.0)
    brake, turn = 0.59677 * 0.25661 / math.sqrt(2), 0.59677 * 0.54631 / math.sqrt(2)
    assert f[False][0] == pytest.approx([-brake, -brake], rel=1e-3)
    assert f[True][0] == pytest.approx([-brake + turn, -brake - turn], rel=1e-3)


def test_helbing_molnar_from_a_still_person_is_exponential_in_the_distance():
    # v_j = 0: the ellipse is a circle, b = |r|, and f = V0 / sigma exp(-|r| / sigma) along r: 2.1 / 0.3 exp(-1 / 0.3)
    # = 7 x 0.035674 = 0.24972
    pos, vel = np.array([[0.0, 0.0], [1.0, 0.0]]), np.zeros((2, 2))
    heading = np.array([[1.0, 0.0], [-1.0, 0.0]])  # facing each other: both in view
    f = forces.helbing_molnar1995(pos, vel, heading, np.array([[0, 1]]), 2.1, 0.3, 2.0, 200.0, 0.46)
    assert f == pytest.approx(np.array([[-0.24972, 0.0], [0.24972, 0.0]]), rel=1e-4)


def test_wall_force_on_the_gap_between_body_and_wall():
    # a body of radius 0.25 m 0.5 m above a wall along x: 25 exp(-(0.5 - 0.25) / 0.08) = 1.0985 m/s^2 upwards,
    # full when heading at the wall, 0.46 of it when heading away; nothing from a wall 2 m or more away
    grid = WallGrid.of(np.array([[[-5.0, 0.0], [5.0, 0.0]]]))
    pos, radius = np.array([[0.0, 0.5], [1.0, 0.5], [0.0, 2.0]]), np.full(3, 0.25)
    heading = np.array([[0.0, -1.0], [0.0, 1.0], [0.0, -1.0]])
    f = forces.wall_force(pos, radius, heading, grid, 25.0, 0.08, 2.0, 200.0, 0.46)
    assert f == pytest.approx(np.array([[0.0, 1.09846], [0.0, 0.46 * 1.09846], [0.0, 0.0]]), rel=1e-4)


def test_a_corner_shared_by_two_walls_repels_once():
    # outside the corner of two walls meeting at the origin, both walls' nearest point is the corner itself: one
    # push of 25 exp(-(0.42426 - 0.25) / 0.08) = 2.8411 m/s^2 along (-1, -1)/sqrt 2; inside the corner the two
    # walls' nearest points differ, and each pushes
    grid = WallGrid.of(np.array([[[0.0, 0.0], [5.0, 0.0]], [[0.0, 0.0], [0.0, 5.0]]]))
    pos, radius = np.array([[-0.3, -0.3], [0.5, 0.5]]), np.full(2, 0.25)
    heading = np.array([[1.0, 1.0], [-1.0, -1.0]]) / math.sqrt(2)
    f = forces.wall_force(pos, radius, heading, grid, 25.0, 0.08, 2.0, 200.0, 0.46)
    one = 25 * math.exp(-(0.3 * math.sqrt(2) - 0.25) / 0.08)
    inside = 25 * math.exp(-(0.5 - 0.25) / 0.08)
    assert f == pytest.approx(np.array([[-one / math.sqrt(2)] * 2, [inside, inside]]), rel=1e-9)


def test_disc_force_from_the_robot():
    # a person 2 m from a 0.5 m disc: gap 1.5 m, 2 / 0.6 exp(-1.5 / 0.6) = 0.27361 m/s^2 away from it
    f = forces.obstacle_disc_force(np.array([[2.0, 0.0]]), np.array([[-1.0, 0.0]]), 0.0, 0.0, 0.5, 2.0, 0.6, 200.0,
                                   0.46)
    assert f == pytest.approx(np.array([[2 / 0.6 * math.exp(-2.5), 0.0]]))


def test_group_gaze_turns_a_walker_whose_partner_is_behind():
    # i walks +x at 1 m/s with its partner 1 m straight behind: keeping them in view needs 180 - 90 = 90 degrees
    # of head rotation, so gaze gives -4 x pi/2 x v; the partner sees i ahead (no rotation); their centre is 0.5 m
    # off, not beyond (2 - 1) / 2 m, and they are farther apart than 0.25 + 0.25 + 0.3 m: no other term
    pos, vel = np.array([[0.0, 0.0], [-1.0, 0.0]]), np.array([[1.0, 0.0], [1.0, 0.0]])
    f = forces.group_forces(pos, vel, np.array([[1.0, 0.0], [1.0, 0.0]]), np.full(2, 0.25), np.array([7, 7]), 4.0,
                            3.0, 1.0)
    assert f == pytest.approx(np.array([[-4 * math.pi / 2, 0.0], [0.0, 0.0]]))


def test_push_out_moves_a_body_clear_of_each_wall_of_a_corner():
    # a body of radius 0.25 m 0.1 m above a wall ends on its surface; one 0.1 m from both walls of a corner is
    # pushed out of one (equally deep: the first wall), then out of the other
    grid = WallGrid.of(np.array([[[0.0, 0.0], [5.0, 0.0]], [[0.0, 0.0], [0.0, 5.0]]]))
    pos = np.array([[3.0, 0.1], [0.1, 0.1]])
    push_out_of_walls(pos, np.full(2, 0.25), grid)
    assert pos == pytest.approx(np.array([[3.0, 0.25], [0.25, 0.25]]))


def test_persons_go_into_their_rows_of_the_contact_space_and_come_back_in_their_order():
    # space rows: person 1, the robot (-1), person 0; the robot's row keeps what Chipmunk had
    perm = np.array([1, -1, 0])
    state = np.full((3, 4), 9.0)
    _to_space(state, np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([[0.1, 0.2], [0.3, 0.4]]), perm)
    assert state.tolist() == [[3.0, 4.0, 0.3, 0.4], [9.0] * 4, [1.0, 2.0, 0.1, 0.2]]
    moved = np.array([[5.0, 6.0], [7.0, 8.0], [1.5, 2.5]])
    assert _from_space(moved, perm, 2).tolist() == [[1.5, 2.5], [5.0, 6.0]]


def test_crossing_a_wall_is_found_and_a_parallel_move_is_not():
    grid = WallGrid.of(np.array([[[-5.0, 0.0], [5.0, 0.0]]]))
    starts = np.array([[0.0, -0.1], [0.0, 0.1], [5.0, -1.0], [5.1, -1.0]])
    ends = np.array([[0.0, 0.1], [3.0, 0.1], [5.0, 1.0], [5.1, 1.0]])
    assert grid.crossed(starts, ends).tolist() == [True, False, True, False]  # the third touches the wall's end


def test_grid_finds_exactly_the_walls_whose_grown_boxes_hold_a_point():
    # by hand: a point 0.5 m off a 10 m wall (reach 1) is near it; one whose box, 0.4 m each way, ends 0.1 m short
    # of a short segment's box is not, and is at reach 0.6. Then random maps against the boxes tested one by one.
    def near(grid, point, reach):
        out, seen = np.empty(len(grid.walls), np.int64), np.full(len(grid.walls), -1, np.int64)
        return sorted(out[:near_walls(point[0], point[1], reach, *grid.arrays(), seen, 0, out)].tolist())

    grid = WallGrid.of(np.array([[[0.0, 0.0], [10.0, 0.0]], [[20.0, 20.0], [21.0, 21.0]]]))
    assert near(grid, (5.0, 0.5), 1.0) == [0]
    assert near(grid, (20.5, 19.5), 0.4) == []
    assert near(grid, (20.5, 19.5), 0.6) == [1]
    rng = np.random.default_rng(0)
    for trial in range(30):
        m = int(rng.integers(1, 400))
        a = rng.uniform(-50, 50, (m, 2))
        segs = np.stack([a, a + rng.normal(0, 3, (m, 2))], 1)
        grid = WallGrid.of(segs, cell=float(rng.uniform(0.5, 5)))
        lo, hi = segs.min(axis=1), segs.max(axis=1)
        for point, reach in zip(rng.uniform(-55, 55, (20, 2)), rng.uniform(0, 3, 20)):
            inside = (point >= lo - reach).all(axis=1) & (point <= hi + reach).all(axis=1)
            assert near(grid, point, reach) == np.flatnonzero(inside).tolist()


def test_environment_contacts_part_overlapping_persons_half_each_inside_the_room():
    # two persons of radius 0.25 m 0.3 m apart overlap by 0.2 m: each moves 0.1 m away; a third, 0.1 m from the
    # left wall, is put back to its radius from it
    z = np.array([[1.0, 1.0], [1.3, 1.0], [0.1, 3.0]])
    _contacts(z, np.full(3, 0.25), 5.0, 5.0)
    assert z == pytest.approx(np.array([[0.9, 1.0], [1.4, 1.0], [0.25, 3.0]]))


def test_the_grid_of_a_large_crowd_finds_the_pairs_in_range():
    # 300 persons 10 m apart on a line (out of each other's reach), but for two 1 m apart at the far end: the pair of
    # test_moussaid2009_sums_each_pair_on_both_persons_with_their_view_weights, found on the grid of cells (above
    # EVERY_PAIR persons) in any order of the persons, and nothing for the others
    pos = np.column_stack([np.arange(300) * 10.0, np.zeros(300)])
    pos[299] = [2981.0, 0.0]
    vel, heading = np.zeros((300, 2)), np.tile([1.0, 0.0], (300, 1))
    args = (5.0, A, LAM, GAMMA, N, N_PRIME, np.ones(300, bool), heading, 200.0, 0.46)
    push = 4.5 * math.exp(-1 / 0.35)
    expected = np.zeros((300, 2))
    expected[298, 0], expected[299, 0] = -push, 0.46 * push
    for order in (np.arange(300), np.random.default_rng(0).permutation(300)):
        assert forces.moussaid2009(pos, vel, order, *args) == pytest.approx(expected, abs=1e-15)


def test_a_crowds_pair_forces_are_summed_in_the_order_of_the_k_d_trees_pairs():
    # pair_order is what makes the forces those summed pair by pair over the tree's list of pairs, in its order,
    # to the last bit: the sums over that list worked here one by one, for crowds on the grid (300) and not (150)
    rng = np.random.default_rng(3)
    for n in (150, 300):
        pos, vel = rng.uniform(0, 20 * n / 150, (n, 2)), rng.normal(0, 1, (n, 2))
        heading = vel / np.linalg.norm(vel, axis=1, keepdims=True)
        walking = rng.random(n) < 0.8
        reach, cos_half = forces.moussaid_reach(A, GAMMA), math.cos(math.radians(200.0) / 2)
        near = [(i, j) for i in range(n) for j in range(i + 1, n) if np.sum((pos[j] - pos[i]) ** 2) <= 25.0]
        pairs = forces.neighbour_pairs(pos, 5.0) if n > forces.EVERY_PAIR else near  # up to 200, every pair in turn
        listed = np.zeros((n, 2))
        for i, j in pairs:
            bx, by, sx, sy = forces.moussaid_pair(pos[j, 0] - pos[i, 0], pos[j, 1] - pos[i, 1], vel[j, 0] - vel[i, 0],
                                                  vel[j, 1] - vel[i, 1], A, LAM, GAMMA, N, N_PRIME, reach)
            if (bx, by, sx, sy) == (0.0, 0.0, 0.0, 0.0):
                continue
            for who, sign in ((i, 1.0), (j, -1.0)):
                fx, fy = sign * (bx + walking[who] * sx), sign * (by + walking[who] * sy)
                w = forces.seen_weight(heading[who, 0], heading[who, 1], fx, fy, cos_half, 0.46)
                listed[who] += w * fx, w * fy
        f = forces.moussaid2009(pos, vel, forces.pair_order(pos), 5.0, A, LAM, GAMMA, N, N_PRIME, walking, heading,
                                200.0, 0.46)
        assert np.abs(f).max() > 1.0
        assert np.array_equal(f, listed)


def test_leaf_order_is_the_k_d_trees():
    # 20 persons on a line x = 0..19 (a leaf holds 16): the box [0, 19] splits at 9.5 into two leaves of 10, with
    # std::partition swapping from both ends inwards: in place already, the order is the persons' own; reversed
    # (person k at x = 19 - k), the ten below 9.5 (persons 10..19) are swapped pairwise with 0..9 from the ends
    # inwards: 19, 18, .., 10, then 9, .., 0
    line = np.column_stack([np.arange(20.0), np.zeros(20)])
    assert forces.leaf_order(line).tolist() == list(range(20))
    reversed_line = line[::-1].copy()
    assert forces.leaf_order(reversed_line).tolist() == list(range(19, -1, -1))
    # along y, x all alike; 17 alike points are a leaf as they are; a point cloud as scipy's own tree orders it
    assert forces.leaf_order(line[:, ::-1].copy()).tolist() == list(range(20))
    assert forces.leaf_order(np.ones((17, 2))).tolist() == list(range(17))
    cloud = np.random.default_rng(1).uniform(0, 30, (500, 2))
    assert np.array_equal(forces.leaf_order(cloud), forces._tree(cloud).indices)


def test_rank_grid_lists_each_cells_persons_by_rank():
    # reach 1 m: cells of 1 m from the lowest corner (0.2, 0), 3 x 2 of them; ranks are places in ``order``
    pos = np.array([[0.5, 0.5], [2.5, 1.5], [0.2, 0.1], [1.0, 0.0]])
    order = np.array([3, 2, 0, 1])  # person 3 is rank 0, person 2 rank 1, ...
    start, ranks, cell, columns, rows, x0, y0 = forces._rank_grid(pos, order, 1.0)
    assert (cell, columns, rows, x0, y0) == (1.0, 3, 2, 0.2, 0.0)
    # persons 0 and 2 in cell 0 (ranks 2 and 1), 3 in cell 0 too (x 1.0 - 0.2 = 0.8), 1 in cell 1 x 3 + 2 = 5
    assert start.tolist() == [0, 3, 3, 3, 3, 3, 4]
    assert ranks.tolist() == [0, 1, 2, 3]


def test_rank_grid_takes_larger_cells_for_a_crowd_spread_far_apart():
    # two persons 2 km apart: cells of 1 m would be 2001 x 1, above 4 x 2 + 1024 cells; 2 m cells are 1001
    start, ranks, cell, columns, rows, x0, y0 = forces._rank_grid(np.array([[0.0, 0.0], [2000.0, 0.0]]),
                                                                  np.arange(2), 1.0)
    assert (cell, columns, rows) == (2.0, 1001, 1)
    assert ranks.tolist() == [0, 1] and start[1] == 1 and start[1000] == 1 and start[1001] == 2