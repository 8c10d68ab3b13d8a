"""CSV rows of plain decimals parsed from their bytes (the very floats Python's float gives, or None to fall back) and
written as printf writes them (the very text Python's % gives, or None to fall back)."""

import numpy as np
import pytest

from evaluation.decimals import format_rows, parse, plain_decimals


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


def test_formats_are_plain_only_as_d_and_fixed_point():
    assert plain_decimals(["%d", "%.2f", "%.0f", "%.9f"]).tolist() == [-1, 2, 0, 9]
    for fmt in (["%d", "%.4g"], ["%s"], ["%.10f"], ["%5.2f"], ["%r"]):
        assert plain_decimals(fmt) is None


def test_written_as_printf_writes_them_worked_by_hand():
    table = np.array([[0.125, 0.375, -0.0, 2.5, -2.7],      # binary ties: half to even (0.12, 0.38); -0 keeps its sign
                      [1.005, -0.00001, 5e-324, 0.5, 7.0],  # 1.005 is 1.00499999999999989...: below the half
                      [12345.678949999999, 0.999999, 9.995, 1.5, 123.0]])
    got = format_rows(table, np.array([2, 2, 4, 0, -1]))
    assert got == ("0.12,0.38,-0.0000,2,-2\n"
                   "1.00,-0.00,0.0000,0,7\n"
                   "12345.68,1.00,9.9950,2,123\n")


def test_written_text_is_pythons_on_many_values():
    # random values, values rounded near a half at each precision, exact binary halves, subnormals, signed zeros
    fmt = ["%d", "%.2f", "%.4f", "%.6f", "%.1f", "%.0f", "%.9f"]
    decimals = plain_decimals(fmt)
    limit = np.where(decimals < 0, 2.0 ** 53, 2.0 ** 53 / 10.0 ** np.maximum(decimals, 0))
    rng = np.random.default_rng(3)
    n = (3000, len(fmt))
    for t in (rng.normal(0, 50, n), np.round(rng.normal(0, 100, n), 3) + 5e-4,
              rng.integers(-4000, 4000, n) / 2.0 ** rng.integers(0, 12, n),
              rng.normal(0, 1, n) * 10.0 ** rng.integers(-320, 16, n)):
        t = np.where(np.abs(t) < limit, t, np.sign(t) * limit * rng.random(n))  # the largest it writes
        t[rng.random(n) < 0.01] = -0.0
        assert format_rows(t, decimals) == (",".join(fmt) + "\n") * len(t) % tuple(t.ravel().tolist())


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf, 2.0 ** 53 / 100])
def test_values_it_does_not_write_are_left_to_python(value):
    assert format_rows(np.array([[1.0, value]]), np.array([-1, 2])) is None
