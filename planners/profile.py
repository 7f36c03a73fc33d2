"""The ground profile along a walking path: height as a function of arc length."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from planners.errors import invalid

__all__ = ["GroundProfile", "HeightRaster", "RASTER_CELL", "cell_index"]

#: Cell of the conservative height raster used for swing collision checks [m].
RASTER_CELL = 1.0 / 256.0  # dyadic, so cells align exactly with every agent's origin

#: Rows closer than this in s [m] form a vertical height change.
_VERTICAL = 1e-12


@dataclass(frozen=True, eq=False)
class GroundProfile:
    """Piecewise-linear ground heights along a path.

    Parameters
    ----------
    s : array_like, shape (m,)
        Non-decreasing arc length of the vertices [m]. Two rows with the same ``s``
        (within 1e-12 m) are a vertical height change (a stair riser, the side of a
        block). ``s = 0`` is where the current stance foot (its ankle) stands.
    z : array_like, shape (m,)
        Ground height of the vertices [m].

    Notes
    -----
    Outside ``[s[0], s[-1]]`` the height continues flat at the end heights. At a vertical
    change the height is right-continuous: ``height(s_jump)`` is the height after it.
    """

    s: np.ndarray
    z: np.ndarray

    def __post_init__(self) -> None:
        s = _as_vector(self.s, "s")
        z = _as_vector(self.z, "z")
        if s.size == 0:
            raise invalid("GroundProfile", "s", "a non-empty array [m]", s.tolist())
        if z.size != s.size:
            raise invalid("GroundProfile", "z", f"of the same length as s ({s.size})", z.size)
        decreasing = np.flatnonzero(np.diff(s) < 0)
        if decreasing.size:
            i = int(decreasing[0])
            raise invalid(
                "GroundProfile", "s", "non-decreasing [m]",
                f"s[{i}]={s[i]:g} > s[{i + 1}]={s[i + 1]:g}",
            )
        if s.size == 1:  # a single point is a flat ground at that height
            s = np.array([s[0], s[0] + 1.0])
            z = np.array([z[0], z[0]])
        s.setflags(write=False)
        z.setflags(write=False)
        object.__setattr__(self, "s", s)
        object.__setattr__(self, "z", z)

    # -- construction ------------------------------------------------------------------

    @classmethod
    def flat(cls, length: float = 10.0, height: float = 0.0, start: float = -2.0):
        """A flat ground from ``start`` to ``start + length`` [m] at ``height`` [m]."""
        return cls(np.array([start, start + length]), np.array([height, height]))

    @classmethod
    def stairs(
        cls, rise: float, tread: float, count: int, first_edge: float = 0.5,
        length: float = 10.0, start: float = -2.0,
    ):
        """A flight of ``count`` steps [m]: first riser at ``first_edge`` [m].

        ``rise`` > 0 goes up, < 0 goes down; each tread is ``tread`` deep [m].
        """
        s = [start]
        z = [0.0]
        for i in range(count):
            edge = first_edge + i * tread
            s += [edge, edge]
            z += [i * rise, (i + 1) * rise]
        s.append(max(start + length, first_edge + count * tread + 1.0))
        z.append(count * rise)
        return cls(np.array(s), np.array(z))

    def shifted(self, ds: float = 0.0, dz: float = 0.0) -> GroundProfile:
        """The same profile translated by ``ds`` along the path and ``dz`` up [m]."""
        return GroundProfile(self.s + ds, self.z + dz)

    # -- queries -----------------------------------------------------------------------

    @cached_property
    def _slopes(self) -> np.ndarray:
        """Slope (m,) of the segment starting at each vertex; 0 for vertical changes."""
        ds = np.diff(self.s)
        dz = np.diff(self.z)
        slope = np.zeros(self.s.size)
        slope[:-1] = np.divide(dz, ds, out=np.zeros_like(dz), where=ds > _VERTICAL)
        return slope

    def height(self, s: np.ndarray | float) -> np.ndarray:
        """Ground height [m] at arc lengths ``s`` [m] (any shape), right-continuous."""
        return self._height_on(*self._locate(s))

    def _locate(self, s) -> tuple[np.ndarray, np.ndarray]:
        """Arc lengths ``s`` [m] clamped to the start, and the vertex beginning the segment
        each lies on (right-continuous at vertical changes)."""
        q = np.maximum(np.asarray(s, dtype=float), self.s[0])
        return q, np.searchsorted(self.s, q, side="right") - 1

    def _height_on(self, q: np.ndarray, i: np.ndarray) -> np.ndarray:
        """Height [m] at ``q`` [m] on the segments beginning at vertices ``i``."""
        return self.z[i] + self._slopes[i] * (q - self.s[i])

    @cached_property
    def jumps(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertical height changes: arc lengths (j,) [m] and signed rises (j,) [m]."""
        same = np.flatnonzero(np.diff(self.s) <= _VERTICAL)
        return self.s[same], self.z[same + 1] - self.z[same]

    @cached_property
    def _range_max_table(self) -> np.ndarray:
        """:func:`_range_max_table` of the vertex heights."""
        return _range_max_table(self.z)

    def max_height(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Highest ground [m] over the closed intervals ``[a, b]`` [m] (same shapes).

        Exact for the piecewise-linear profile, including both sides of vertical
        changes; vectorised with a sparse range-maximum table.
        """
        return self.span_heights(a, b)[0]

    def span_heights(self, a: np.ndarray, b: np.ndarray):
        """:meth:`max_height` over ``[a, b]`` together with ``height(a)`` and
        ``height(b)`` [m], which it needs anyway (one search per end)."""
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        qa, ia = self._locate(a)
        qb, ib = self._locate(b)
        height_a, height_b = self._height_on(qa, ia), self._height_on(qb, ib)
        empty = b < a  # the interval is [a, a]
        best = np.maximum(height_a, np.where(empty, height_a, height_b))
        lo = np.searchsorted(self.s, a, side="left")
        # vertices lo..hi-1 lie in [a, max(a, b)]
        hi = np.where(np.maximum(a, b) < self.s[0], 0, np.where(empty, ia, ib) + 1)
        count = hi - lo
        k = np.log2(np.maximum(count, 1)).astype(int)
        table = self._range_max_table
        last = table.shape[1] - 1
        inner = np.maximum(table[k, np.minimum(lo, last)],
                           table[k, np.clip(hi - (1 << k), 0, last)])
        return np.where(count > 0, np.maximum(best, inner), best), height_a, height_b

    def raster(self, start: float, stop: float, cell: float = 0.01) -> HeightRaster:
        """A conservative raster of this profile over ``[start, stop]`` [m].

        Each cell of width ``cell`` [m] holds the exact highest ground inside it, so
        :meth:`HeightRaster.max_height` never underestimates (it may overestimate by up
        to one cell's rise).
        """
        count = max(1, int(np.ceil((stop - start) / cell)))
        edges = start + cell * np.arange(count + 1)
        # the same maximum as max_height(edges[:-1], edges[1:]) -- the heights at both
        # cell edges and at the vertices inside -- found from the vertices' cells rather
        # than by searching every edge: vertex v lies in the closed cells k with
        # edges[k] <= s_v <= edges[k + 1]
        last = count + 1
        f = np.clip(np.ceil((self.s - start) / cell), 0, last).astype(np.intp)
        # f: the first edge >= s_v (corrected where rounding put it one edge off)
        f += (f < last) & (edges[np.minimum(f, count)] < self.s)
        f -= (f > 0) & (edges[np.clip(f - 1, 0, count)] >= self.s)
        g = np.where((f < last) & (edges[np.minimum(f, count)] == self.s), f, f - 1)
        # g: the last edge <= s_v; vertex v is at or below edge k when f_v <= k
        at_or_below = np.cumsum(np.bincount(f, minlength=last + 1))[:last]
        i = np.maximum(at_or_below - 1, np.searchsorted(self.s, self.s[0], side="right") - 1)
        at_edges = self._height_on(np.maximum(edges, self.s[0]), i)  # = self.height(edges)
        cells = np.maximum(at_edges[:-1], at_edges[1:])
        inside = (f <= count) & (g >= 0)
        np.maximum.at(cells, np.maximum(f[inside] - 1, 0), self.z[inside])
        np.maximum.at(cells, np.minimum(g[inside], count - 1), self.z[inside])
        return HeightRaster(start, cell, cells, self.s)

    def vertices_between(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Number of profile vertices in the closed intervals ``[a, b]`` [m] (same shapes)."""
        return np.searchsorted(self.s, b, side="right") - np.searchsorted(self.s, a, side="left")

    def __repr__(self) -> str:
        return (f"GroundProfile({self.s.size} vertices, s=[{self.s[0]:g}, {self.s[-1]:g}] m, "
                f"z=[{self.z.min():g}, {self.z.max():g}] m)")


def _range_max_table(values: np.ndarray, levels: int | None = None) -> np.ndarray:
    """Sparse table (levels, n) for range-maximum queries: row k holds the maximum of
    ``values`` (n,) over the 2**k entries from each index (fewer at the end). All
    ``floor(log2(n)) + 1`` levels by default, or the first ``levels`` of them."""
    n = values.size
    top = int(np.floor(np.log2(n))) + 1
    levels = top if levels is None else min(levels, top)
    table = np.empty((levels, n))
    table[0] = values
    width = 1
    for k in range(1, levels):
        table[k, : n - 2 * width + 1] = np.maximum(
            table[k - 1, : n - 2 * width + 1], table[k - 1, width: n - width + 1])
        table[k, n - 2 * width + 1:] = table[k - 1, n - 2 * width + 1:]
        width *= 2
    return table


def _as_vector(values, field: str) -> np.ndarray:
    try:
        arr = np.array(values, dtype=float).reshape(-1) if np.ndim(values) <= 1 else None
    except (TypeError, ValueError):
        raise invalid("GroundProfile", field, "an array of numbers [m]", values) from None
    if arr is None:
        raise invalid("GroundProfile", field, "one-dimensional [m]", np.shape(values))
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        i = int(bad[0])
        raise invalid("GroundProfile", field, "finite [m]", f"{field}[{i}]={arr[i]}")
    return arr


def cell_index(x: np.ndarray, start: float, cell: float, count: int) -> np.ndarray:
    """Raster cell of each arc length ``x`` [m] (any shape): the last k in 0..count-1
    whose left edge ``start + cell * k`` [m] (computed as :meth:`GroundProfile.raster`
    computes its edges) is <= x, 0 before the raster.

    Exact: ``floor((x - start) / cell)`` in floating point can be one cell off where
    ``x`` lies within rounding of an edge (``x - start`` rounds), and a query would then
    miss the cell holding a vertical change just before that edge; the index is
    corrected against the edge itself. :func:`planners.swing._cell` is the compiled
    twin (bitwise the same indices).
    """
    x = np.asarray(x, dtype=float)
    k = np.clip((x - start) * (1.0 / cell), 0.0, count - 1.0).astype(np.intp)
    k -= (k > 0) & (start + cell * k > x)
    k += (k < count - 1) & (start + cell * (k + 1) <= x)
    return k


class HeightRaster:
    """Cell maxima of a ground profile with O(1) range-maximum queries.

    Parameters
    ----------
    start : float
        Arc length of the first cell's left edge [m].
    cell : float
        Cell width [m].
    heights : ndarray, shape (c,)
        Highest ground in each cell [m].
    vertex_s : ndarray, shape (m,)
        Arc lengths of the profile's vertices [m] (outside ones count in the end cells).
    """

    def __init__(self, start: float, cell: float, heights: np.ndarray, vertex_s: np.ndarray):
        self.start = float(start)
        self.cell = float(cell)
        c = heights.size
        cells = cell_index(vertex_s, self.start, self.cell, c)
        self.vertex_cum = np.concatenate([[0], np.cumsum(np.bincount(cells, minlength=c))])
        self.heights = heights
        # the levels of the range-maximum table are built as queries need them (swing
        # queries span a few dozen cells, the raster tens of thousands)
        self._table = heights[None, :]
        self._log2 = np.zeros(c + 1, dtype=np.intp)
        self._log2[2:] = np.floor(np.log2(np.arange(2, c + 1))).astype(np.intp)

    def vertices_between(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Number of profile vertices in the cells covering ``[a, b]`` [m] (>= the number
        in the interval itself: a conservative count)."""
        c = self.vertex_cum.size - 1
        ia = cell_index(a, self.start, self.cell, c)
        ib = np.maximum(cell_index(b, self.start, self.cell, c), ia)
        return self.vertex_cum[ib + 1] - self.vertex_cum[ia]

    def table(self, levels: int) -> np.ndarray:
        """The range-maximum table (at least ``levels`` levels, as many as the cells
        allow) of the cell heights, shape (L, c): row k holds the maximum of the 2**k
        cells from each cell."""
        if self._table.shape[0] < levels:
            self._table = _range_max_table(self.heights, levels)
        return self._table

    def max_height(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Highest ground [m] over ``[a, b]`` [m] (same shapes), never underestimated.

        Queries outside the raster use its end cells.
        """
        c = self._table.shape[1]
        flat = self._table.ravel()
        ia = cell_index(a, self.start, self.cell, c)
        ib = np.maximum(cell_index(b, self.start, self.cell, c), ia)
        k = self._log2[ib - ia + 1]
        if k.size and k.max() >= self._table.shape[0]:
            self._table = _range_max_table(self.heights, int(k.max()) + 1)
            flat = self._table.ravel()
        row = k * c
        return np.maximum(flat.take(row + ia), flat.take(row + ib - (1 << k) + 1))
