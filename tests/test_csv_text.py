"""crowdwalk.csv_text: the compiled CSV text is Python's, value for value."""

import csv
import io

import numpy as np

from crowdwalk.csv_text import rows_text


def _python_text(columns) -> bytes:
    """What RunWriter.write_footsteps joins in Python (floats rounded to 5 decimals)."""
    lists = [(np.round(c, 5) if c.dtype.kind == "f" else c).tolist() for c in columns]
    text = [list(map(str, c)) for c in lists]
    return ("\r\n".join(map(",".join, zip(*text, strict=True))) + "\r\n").encode()


EDGES = np.array([
    0.0, -0.0, 1e-5, -1e-5, 4.9999e-6, 5e-6, 5.00001e-6, 1.5e-5, 2.5e-5, 9e-5, -9.4999e-5,
    9.99995e-5, 1e-4, -1e-4, 1e-4 - 1e-12, 0.00015, 12.345675, 12.345665, 0.1, 0.2, 0.3,
    1 / 3, -2 / 3, 3.0, -3.0, 123456.7, 1e9, 9999999999.999994, -9999999999.999994, np.nan,
    np.inf, -np.inf])


def test_rows_text_is_pythons_text_of_every_value():
    rng = np.random.default_rng(7)
    k = 40_000
    for scale in (1e-6, 1e-3, 1.0, 1e3, 1e8):
        x = rng.standard_normal(k) * scale
        x[:EDGES.size] = EDGES
        # exactly halfway between two 5-decimal values: round half to even
        x[EDGES.size:EDGES.size + 2000] = (rng.integers(-10**7, 10**7, 2000) + 0.5) / 1e5
        columns = [rng.integers(-10**12, 10**12, k), x,
                   np.where(rng.random(k) < 0.5, "left", "right"),
                   rng.standard_normal(k) * scale,
                   np.array(["best_first_multistart", "a", "Zz_9"])[rng.integers(0, 3, k)],
                   rng.integers(0, 3, k).astype(np.int8)]
        assert rows_text(columns) == _python_text(columns)


def test_rows_text_reads_back_as_csv():
    columns = [np.arange(3), np.array([0.5, -0.0, 1e-5]), np.array(["left", "right", "x"])]
    rows = list(csv.reader(io.StringIO(rows_text(columns).decode(), newline="")))
    assert rows == [["0", "0.5", "left"], ["1", "-0.0", "right"], ["2", "1e-05", "x"]]


def test_rows_text_leaves_other_values_to_the_caller():
    for column in (np.array([1e10]), np.array([-2e10]), np.array([1.0], np.float32),
                   np.array(["a,b"]), np.array(['say "x"']), np.array(["a\nb"]),
                   np.array(["é"]), np.array(["a\x00b"]), np.array([True]),
                   np.array([object()], dtype=object), np.array([np.iinfo(np.int64).min])):
        assert rows_text([np.arange(1), column]) is None
    assert rows_text([np.arange(2), np.arange(3)]) is None  # columns of two lengths
    assert rows_text([np.zeros(0), np.zeros(0, int)]) == b""
