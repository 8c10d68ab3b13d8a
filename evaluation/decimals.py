"""Parsing CSV rows of plain decimals (what a run writes: -12.3456, 7, 0) straight from their bytes, compiled.

Why: scoring a run reads its CSVs a few times over, and ``np.loadtxt`` costs about 2 us a field, most of a
run's scoring time. A plain decimal of at most 2^53 in its digits, d, with k digits after the point, is d / 10^k:
both exact in a float64 (k <= 22), so their quotient is the correctly rounded value, the very float ``loadtxt``
(or ``float``) gives. Anything else (an exponent, inf or nan, spaces, a comment, a blank line, a row of another
width) makes ``parse`` give up, and the caller reads that chunk the general way, with its error messages.
"""

from __future__ import annotations

import numpy as np

from pipeline.compiled import kernel

_EXACT = 2 ** 53
_POWERS = np.array([10.0 ** k for k in range(23)])  # exact: 10^22 < 2^53 x 2^22


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
