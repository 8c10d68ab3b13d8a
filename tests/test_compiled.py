"""The compiled kernels' shared sums (pipeline/compiled.py) against hand-worked values: numpy's pairwise order, which
the kernels keep so that their results equal what numpy gave (and what the classifiers were trained on)."""

import numpy as np

from pipeline.compiled import pairwise, segment_sum

BIG = 2.0 ** 53  # from here on the spacing of doubles is 2: BIG + 1 is a tie, rounded to the even BIG


def test_eight_running_sums_then_their_pairs():
    # 2^53, seven ones, -2^53: the eight running sums start at the first eight values and the ninth is added after
    # ((2^53 + 1) + (1 + 1)) + ((1 + 1) + (1 + 1)) = (2^53 + 2) + 4; one running sum would lose every 1 (0), the
    # exact sum is 7
    values = np.array([BIG, 1, 1, 1, 1, 1, 1, 1, -BIG])
    assert pairwise(values, 0, 9) == 6.0 == values.sum()
    assert pairwise(values, 1, 7) == 7.0  # below 8 values: one running sum


def test_a_reduceat_sum_is_the_first_value_plus_the_rest_pairwise():
    # [1, 2^53, -2^53] as np.add.reduceat sums a segment: 1 + (2^53 - 2^53) = 1; in order it would be 0
    values = np.array([5.0, 1.0, BIG, -BIG])
    assert segment_sum(values, 1, 3) == 1.0 == np.add.reduceat(values, [1])[0]
    assert segment_sum(values, 0, 1) == 5.0


def test_above_128_values_the_halves_are_summed_apart():
    # 256 values, split by numpy into 128 + 128: 2^53 and 127 ones, then -2^53 and 127 ones.
    # First half: running sum r0 = 2^53 plus 15 ones, each a tie rounded to the even 2^53; r1..r7 = 16 each; the
    # pairs give ((2^53 + 16) + 32) + 64 = 2^53 + 112. Second half: below 2^53 in size doubles are 1 apart, so r0 =
    # -2^53 + 15 exactly and the half is -2^53 + 127. The whole: 239 (one running sum: 127; exact: 254)
    values = np.ones(256)
    values[0], values[128] = BIG, -BIG
    assert pairwise(values, 0, 128) == BIG + 112
    assert pairwise(values, 128, 128) == -BIG + 127
    assert pairwise(values, 0, 256) == 239.0 == values.sum()


def test_by_label_is_a_counting_sort():
    from pipeline.compiled import by_label

    # labels 2, -1, 0, 2, 0 with k = 3: label 0 holds elements 2 and 4, label 1 none, label 2 elements 0 and 3;
    # element 1 (-1) is left out
    start, order = by_label(np.array([2, -1, 0, 2, 0]), 3)
    assert start.tolist() == [0, 2, 2, 4] and order.tolist() == [2, 4, 0, 3]
    # with k = 2, label 2 is beyond the table and left out as -1 is
    start, order = by_label(np.array([2, -1, 0, 2, 0]), 2)
    assert start.tolist() == [0, 2, 2] and order.tolist() == [2, 4]


def test_union_root_finds_the_root_and_halves_the_path():
    from pipeline.compiled import union_root

    # the chain 3 -> 2 -> 1 -> 0: the root is 0; on the way 3 is pointed at 1 (its grandparent), and 1 stays at 0
    parent = np.array([0, 0, 1, 2])
    assert union_root(parent, 3) == 0
    assert parent.tolist() == [0, 0, 1, 1]
    assert union_root(parent, 0) == 0
