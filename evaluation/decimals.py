"""CSV rows of plain decimals (what a run writes: -12.3456, 7, 0) parsed straight from their bytes, and written
as printf's ``%d`` and ``%.kf`` write them, compiled.

Why: scoring a run reads its CSVs a few times over, and ``np.loadtxt`` costs about 2 us a field, most of a run's
scoring time; writing them with Python's ``%`` costs about 120-190 ns a field (1.4 s of a 120 s run).

Reading: a plain decimal of at most 2^53 in its digits, d, with k digits after the point, is d / 10^k: both exact in
a float64 (k <= 22), so their quotient is the correctly rounded value, the very float ``loadtxt`` (or ``float``)
gives. Anything else (an exponent, inf or nan, spaces, a comment, a blank line, a row of another width) makes
``parse`` give up, and the caller reads that chunk the general way, with its error messages.

Writing: ``%.kf`` of x is the integer nearest x 10^k (half to even), the decimal point put k digits from its end,
and x's sign (also where it rounds to 0: -0.0000). x = m 2^-s exactly (frexp), so x 10^k = m 10^k / 2^s: the
product m 10^k (below 2^83) in two 64-bit words, shifted right by s, its remainder against 2^(s-1), gives the
rounding with no float error, so the text is Python's, byte for byte. ``%d`` of x is int(x), truncated. A value
not finite, or whose text would pass 2^53 in its digits, makes ``format_rows`` give up, and the caller writes
that block with Python's ``%``.
"""

from __future__ import annotations

import math
import re

import numpy as np

from pipeline.compiled import kernel

_EXACT = 2 ** 53
_POWERS = np.array([10.0 ** k for k in range(23)])  # exact: 10^22 < 2^53 x 2^22
_PLAIN = re.compile(r"%(?:d|\.(\d)f)")
FIELD_BYTES = 20  # the longest field written: a sign, 16 digits, a point and a comma or newline


def parse(text: str, columns: int) -> np.ndarray | None:
    """The rows of ``text`` (lines ending in newlines) as a float array [rows, columns], or None where any field is
    not a plain decimal or any row has another number of fields."""
    data = np.frombuffer(text.encode(), np.uint8)
    rows = int(np.count_nonzero(data == 10))
    if rows == 0 or data[-1] != 10:
        return None
    out = np.empty((rows, columns))
    return out if _parse(data, columns, _POWERS, out) else None


@kernel
def _parse(data, columns, powers, out):
    """Fill ``out`` from the bytes ``data`` of whole lines; False at the first field that is not a plain decimal
    (an optional minus, digits, an optional point and digits) or a row without exactly ``columns`` fields."""
    row, column, at = 0, 0, 0
    while at < len(data):
        negative = data[at] == 45  # '-'
        if negative:
            at += 1
        digits, mantissa, after, point = 0, 0, 0, False
        while at < len(data):
            c = data[at]
            if 48 <= c <= 57:
                mantissa = mantissa * 10 + (c - 48)
                if mantissa > _EXACT:
                    return False
                digits += 1
                after += point
            elif c == 46 and not point:  # '.'
                point = True
            else:
                break
            at += 1
        if digits == 0 or after > 22 or at == len(data):
            return False
        value = mantissa / powers[after]
        out[row, column] = -value if negative else value
        c = data[at]
        at += 1
        if c == 44:  # ','
            column += 1
            if column == columns:
                return False
        elif c == 10:  # newline: the row is done
            if column != columns - 1:
                return False
            row, column = row + 1, 0
        else:
            return False
    return row == len(out)


def plain_decimals(fmt: list[str]) -> np.ndarray | None:
    """Each of the column formats ``fmt`` as the digits after its point (-1 for ``%d``), or None unless every one
    is ``%d`` or ``%.kf`` (k <= 9)."""
    found = [_PLAIN.fullmatch(f) for f in fmt]
    if not all(found):
        return None
    return np.array([-1 if m.group(1) is None else int(m.group(1)) for m in found], np.int64)


def format_rows(table: np.ndarray, decimals: np.ndarray) -> str | None:
    """The rows of ``table`` [rows, columns] (float64) as CSV text, each column as ``%d`` (-1 in ``decimals``) or
    ``%.kf`` (k) writes it, every row ending in a newline; None where a value is not finite or too large."""
    table = np.ascontiguousarray(table, np.float64)
    out = np.empty(table.size * FIELD_BYTES, np.uint8)
    n = _format(table, decimals, out)
    return None if n < 0 else out[:n].tobytes().decode("ascii")


_MASK32 = np.uint64(0xFFFFFFFF)


@kernel
def _scaled(a, k):
    """The integer nearest a 10^k, half to even, exactly, for 0 <= a with a 10^k < 2^53 (module docstring)."""
    if a == 0.0:
        return np.uint64(0)
    fraction, exponent = math.frexp(a)
    m = np.uint64(fraction * 9007199254740992.0)  # 2^53: exact
    s = 53 - exponent
    t = np.uint64(10 ** k)
    if s <= 0:
        return (m << np.uint64(-s)) * t
    if s > 84:  # m 10^k < 2^83 < 2^(s - 1): below a half
        return np.uint64(0)
    upper, lower = (m >> np.uint64(32)) * t, (m & _MASK32) * t  # m 10^k = upper 2^32 + lower
    lo = (upper << np.uint64(32)) + lower
    hi = (upper >> np.uint64(32)) + np.uint64(lo < lower)
    if s < 64:
        shift = np.uint64(s)
        q = (hi << (np.uint64(64) - shift)) | (lo >> shift)
        rest, half = lo & ((np.uint64(1) << shift) - np.uint64(1)), np.uint64(1) << (shift - np.uint64(1))
        above, tie = rest > half, rest == half
    elif s == 64:
        q, half = hi, np.uint64(1) << np.uint64(63)
        above, tie = lo > half, lo == half
    else:
        shift = np.uint64(s - 64)
        q = hi >> shift
        rest, half = hi & ((np.uint64(1) << shift) - np.uint64(1)), np.uint64(1) << (shift - np.uint64(1))
        above, tie = rest > half or (rest == half and lo > 0), rest == half and lo == 0
    if above or (tie and q & np.uint64(1)):
        q += np.uint64(1)
    return q


@kernel
def _digits(q, out, at, width):
    """The decimal digits of q at out[at:], at least ``width`` of them (zeros in front); the new end."""
    n = 0
    v = q
    while v > 0 or n < width:
        n += 1
        v //= np.uint64(10)
    end = at + n
    for i in range(end - 1, at - 1, -1):
        out[i] = 48 + q % np.uint64(10)
        q //= np.uint64(10)
    return end


@kernel
def _format(table, decimals, out):
    """``format_rows`` into the bytes ``out``: their count, or -1 at a value it does not write."""
    rows, columns = table.shape
    at = 0
    for i in range(rows):
        for j in range(columns):
            x, k = table[i, j], decimals[j]
            if not abs(x) < (_EXACT if k < 0 else _EXACT / 10.0 ** k):  # also NaN
                return -1
            if k < 0:
                whole = int(x)  # toward zero, as Python's %d of a float
                if whole < 0:
                    out[at] = 45  # '-'
                    at += 1
                at = _digits(np.uint64(abs(whole)), out, at, 1)
            else:
                if math.copysign(1.0, x) < 0:
                    out[at] = 45
                    at += 1
                q = _scaled(abs(x), k)
                unit = np.uint64(10 ** k)
                at = _digits(q // unit, out, at, 1)
                if k:
                    out[at] = 46  # '.'
                    at = _digits(q % unit, out, at + 1, k)
            out[at] = 44 if j < columns - 1 else 10  # ',' or a newline
            at += 1
    return at
