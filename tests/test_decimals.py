"""CSV rows of plain decimals parsed from their bytes: the very floats Python's float gives, or None to fall back."""

import numpy as np
import pytest

from evaluation.decimals import parse


def test_plain_decimals_are_the_floats_float_reads():
    # by hand: -0 keeps its sign; 0.1 is the float nearest a tenth; 9007199254740992 (2^53) is exact
    got = parse("-0,0.1,9007199254740992\n1.,.5,-12.3456\n", 3)
    assert got.tolist() == [[-0.0, 0.1, 2.0 ** 53], [1.0, 0.5, -12.3456]]
    assert np.signbit(got[0, 0])
    # many random decimals of every length a run writes (digits below 2^53), bit for bit
    rng = np.random.default_rng(0)
    values = rng.normal(0, 10.0 ** rng.integers(-3, 4, 3000)) * rng.integers(0, 2, 3000)
    fields = [f"{v:.{k}f}" for v, k in zip(values, rng.integers(0, 11, 3000))]
    text = "".join(",".join(fields[i:i + 6]) + "\n" for i in range(0, 3000, 6))
    expected = np.array([float(f) for f in fields]).reshape(-1, 6)
    assert np.array_equal(parse(text, 6).view(np.int64), expected.view(np.int64))


@pytest.mark.parametrize("text", ["1e5,2\n", "nan,2\n", "inf,2\n", " 1,2\n", "1,2\n\n", "1,2,3\n", "1\n", "1,2",
                                  "1,2\r\n", "1,2 # note\n", "1,,\n", "1.2.3,4\n", "--1,2\n", "99999999999999999,1\n",
                                  "0.00000000000000000000001,1\n"])
def test_anything_else_is_left_to_the_general_reader(text):
    assert parse(text, 2) is None
