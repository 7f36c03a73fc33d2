"""The text of CSV rows, made by a compiled kernel (``footsteps.csv``'s rows).

:func:`rows_text` gives the bytes that ``RunWriter.write_footsteps`` joins in Python
(``str`` of each value: a float rounded to 5 decimals by ``np.round``, an int, a name)
for the rows it can write itself: float, int and ASCII text columns whose names
``csv.writer`` would not quote. The kernel (``nogil``) releases the GIL, so the run's
writer thread no longer holds it while formatting (py-spy ``--gil``, 10,000 walkers:
the footsteps' text was 0.14 s of GIL per simulated second, as much as a third of the
simulation thread's own).

Why the text is Python's: ``np.round(x, 5)`` is ``rint(x · 1e5) / 1e5``, the double
nearest ``K / 10^5`` for the integer ``K = rint(x · 1e5)``. For ``|K| < 10^15`` (values
below 10^10) every other decimal of at most five places lies at least 10^-5 from
``K / 10^5``, far beyond the double's spacing there, so ``repr``'s shortest round-trip
digits are ``K / 10^5``'s with trailing zeros dropped; ``repr`` writes them positionally
(``'12.5'``, ``'3.0'``, ``'0.0001'``) except below 10^-4 (``'5e-05'``), and a zero keeps
its sign (``'-0.0'``). NaN and infinities are ``'nan'``, ``'inf'``, ``'-inf'``. A larger
value, or a column of another kind, leaves the rows to the caller (None).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba as nb
import numpy as np

__all__ = ["rows_text"]

_FLOAT, _INT, _TEXT = 0, 1, 2
#: |rint(x · 1e5)| from which a float is left to Python's repr [-]
_LARGEST = 1e15
#: bytes a float takes at most here: sign, 10 integer digits, point, 5 decimals [-]
_FLOAT_WIDTH = 17
_INT_WIDTH = 20  # an int64's digits and sign [-]
_INT64_LEAST = np.iinfo(np.int64).min


def rows_text(columns: Sequence[np.ndarray]) -> bytes | None:
    """The CSV text (ASCII bytes, ``\\r\\n`` after each row) of the rows whose i-th values
    are ``columns[j][i]`` (each (k,)): ``str`` of each value as ``RunWriter.
    write_footsteps`` writes it (floats rounded to 5 decimals). None when a column is
    neither float, int nor ASCII text free of ``,"\\r\\n``, or a float is 10^10 or more
    (the caller then writes the rows itself)."""
    k = None
    kinds, slots, floats, ints, texts = [], [], [], [], []
    for col in columns:
        col = np.asarray(col)
        if col.ndim != 1 or (k is not None and col.shape[0] != k):
            return None
        k = col.shape[0]
        if col.dtype == np.float64:
            kinds.append(_FLOAT)
            slots.append(len(floats))
            floats.append(col)
        elif col.dtype.kind in "iu" and col.dtype.itemsize <= 8 and not (
                col.dtype.kind == "u" and col.dtype.itemsize == 8):
            kinds.append(_INT)
            slots.append(len(ints))
            ints.append(col.astype(np.int64, copy=False))
        elif col.dtype.kind == "U":  # code points (UCS-4), the kernel takes ASCII only
            kinds.append(_TEXT)
            slots.append(len(texts))
            texts.append(np.ascontiguousarray(col).view(np.uint32).reshape(k, -1))
        else:
            return None
    if not k:
        return b""
    widths = np.array([t.shape[1] for t in texts], np.int64)
    chars = np.concatenate(texts, axis=1) if texts else np.zeros((k, 0), np.uint32)
    start = np.concatenate([[0], np.cumsum(widths)]).astype(np.int64)
    per_row = (_FLOAT_WIDTH * len(floats) + _INT_WIDTH * len(ints) + int(widths.sum())
               + len(kinds) + 1)
    out = np.empty(k * per_row, np.uint8)
    size = _format_rows(k, np.array(kinds, np.int64), np.array(slots, np.int64),
                        np.array(floats, np.float64).reshape(len(floats), k),
                        np.array(ints, np.int64).reshape(len(ints), k), chars, start, widths,
                        out)
    return None if size < 0 else out[:size].tobytes()


@nb.njit(cache=True, nogil=True)
def _put_int(value, out, at):
    """Write the decimal digits of ``value`` (an int above int64's least) at
    ``out[at:]``; the next index."""
    if value < 0:
        out[at] = 45  # '-'
        at += 1
        value = -value
    n = 1
    rest = value // 10
    while rest > 0:
        n += 1
        rest //= 10
    for j in range(at + n - 1, at - 1, -1):
        out[j] = 48 + value % 10
        value //= 10
    return at + n


@nb.njit(cache=True, nogil=True)
def _put_float(x, out, at):
    """Write ``repr(float(np.round(x, 5)))`` at ``out[at:]``; the next index, or -1 for
    a value this does not write (10^10 or more)."""
    if np.isnan(x):
        for c in (110, 97, 110):  # 'nan'
            out[at] = c
            at += 1
        return at
    if np.isinf(x):
        if x < 0:
            out[at] = 45
            at += 1
        for c in (105, 110, 102):  # 'inf'
            out[at] = c
            at += 1
        return at
    y = np.rint(x * 1e5)
    if np.isinf(y) or abs(y) >= _LARGEST:
        return -1
    if math.copysign(1.0, y) < 0.0:
        out[at] = 45
        at += 1
    units = np.int64(abs(y))
    if 0 < units < 10:  # below 1e-4: repr's exponent form, 'De-05'
        out[at] = 48 + units
        for c in (101, 45, 48, 53):  # 'e-05'
            at += 1
            out[at] = c
        return at + 1
    at = _put_int(units // 100000, out, at)
    out[at] = 46  # '.'
    at += 1
    frac = units % 100000
    if frac == 0:
        out[at] = 48
        return at + 1
    scale = 10000
    while frac > 0:
        d = frac // scale
        out[at] = 48 + d
        at += 1
        frac -= d * scale
        scale //= 10
    return at


@nb.njit(cache=True, nogil=True)
def _format_rows(k, kinds, slots, floats, ints, chars, start, widths, out):
    """The k rows' text into ``out``; its length, or -1 when a value is left to Python
    (a float of 10^10 or more, int64's least, a name with ``,"\\r\\n``, a NUL or
    other than ASCII). ``chars`` (k, w) are the names' code points side by side."""
    at = 0
    for i in range(k):
        for c in range(kinds.size):
            if c > 0:
                out[at] = 44  # ','
                at += 1
            s = slots[c]
            if kinds[c] == 0:
                at = _put_float(floats[s, i], out, at)
                if at < 0:
                    return -1
            elif kinds[c] == 1:
                if ints[s, i] == _INT64_LEAST:
                    return -1
                at = _put_int(ints[s, i], out, at)
            else:
                for j in range(start[s], start[s] + widths[s]):
                    b = chars[i, j]
                    if b == 0:  # numpy's fixed width: the name ended (NULs to the end)
                        for r in range(j, start[s] + widths[s]):
                            if chars[i, r] != 0:
                                return -1
                        break
                    if b == 44 or b == 34 or b == 13 or b == 10 or b > 127:
                        return -1
                    out[at] = b
                    at += 1
        out[at] = 13
        out[at + 1] = 10
        at += 2
    return at
