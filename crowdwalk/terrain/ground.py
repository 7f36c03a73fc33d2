"""The composed ground: a flat base plus features in override order."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba as nb
import numpy as np
import shapely
import trimesh
from shapely.geometry import Polygon

from crowdwalk.errors import invalid
from crowdwalk.terrain.features import (
    Block,
    Feature,
    StairFlight,
    TerrainKind,
    _is_box,
    _points,
    _ring_segments,
)

__all__ = ["Terrain"]


class _EdgeIndex:
    """Break segments (k, 2, 2) [m] with a bounding-box test, or an STRtree when many."""

    def __init__(self, edges: np.ndarray):
        self.edges = edges
        self.lo, self.hi = edges.min(axis=1), edges.max(axis=1)
        self.tree = shapely.STRtree(shapely.linestrings(edges)) if len(edges) > 256 else None

    def pairs(self, a: np.ndarray, b: np.ndarray):
        """Candidate (segment, edge) index pairs whose bounding boxes overlap."""
        if self.tree is not None:
            boxes = shapely.box(*np.minimum(a, b).T - 1e-9, *np.maximum(a, b).T + 1e-9)
            i, j = self.tree.query(boxes)
            yield i, j
            return
        chunk = max(1, 200_000 // max(len(self.edges), 1))
        for c0 in range(0, len(a), chunk):
            aa, bb = a[c0:c0 + chunk, None, :], b[c0:c0 + chunk, None, :]
            near = ((np.maximum(aa, bb) >= self.lo - 1e-9).all(-1)
                    & (np.minimum(aa, bb) <= self.hi + 1e-9).all(-1))
            i, j = np.nonzero(near)
            yield i + c0, j


@nb.njit(cache=True, nogil=True)
def _crossings_boxed(a, b, edges, lo, hi):
    """:func:`_crossings` without an STRtree: every (segment, edge) pair in row-major
    order whose bounding boxes overlap, tested as the numpy code does (element for
    element the same operations)."""
    m, ne = a.shape[0], edges.shape[0]
    cap = max(16, 2 * m)
    seg = np.empty(cap, np.int64)
    ts = np.empty(cap)
    h = 0
    tol = 1e-12
    for i in range(m):
        ax, ay, bx, by = a[i, 0], a[i, 1], b[i, 0], b[i, 1]
        x0, x1, y0, y1 = min(ax, bx), max(ax, bx), min(ay, by), max(ay, by)
        dx, dy = bx - ax, by - ay
        for j in range(ne):
            if not (x1 >= lo[j, 0] - 1e-9 and y1 >= lo[j, 1] - 1e-9
                    and x0 <= hi[j, 0] + 1e-9 and y0 <= hi[j, 1] + 1e-9):
                continue
            rx, ry = edges[j, 0, 0] - ax, edges[j, 0, 1] - ay
            ex, ey = edges[j, 1, 0] - edges[j, 0, 0], edges[j, 1, 1] - edges[j, 0, 1]
            den = dx * ey - dy * ex
            ok = np.abs(den) > 1e-15
            if not ok:
                den = 1.0
            t = (rx * ey - ry * ex) / den
            u = (rx * dy - ry * dx) / den
            if ok and t >= -tol and t <= 1 + tol and u >= -tol and u <= 1 + tol:
                if h == cap:
                    cap *= 2
                    seg2 = np.empty(cap, np.int64)
                    ts2 = np.empty(cap)
                    seg2[:h] = seg[:h]
                    ts2[:h] = ts[:h]
                    seg, ts = seg2, ts2
                seg[h] = i
                ts[h] = min(max(t, 0.0), 1.0)
                h += 1
    return seg[:h].copy(), ts[:h].copy()


def _crossings(a: np.ndarray, b: np.ndarray, index: _EdgeIndex):
    """Where segments a→b (m, 2) [m] cross the indexed edges: (segment index (h,),
    parameter t ∈ [0, 1] along it (h,))."""
    if index.tree is None:
        f = np.ascontiguousarray
        return _crossings_boxed(f(a, float), f(b, float), f(index.edges, float),
                                f(index.lo, float), f(index.hi, float))
    seg_idx, ts = [], []
    edges = index.edges
    e0, e = edges[:, 0], edges[:, 1] - edges[:, 0]
    tol = 1e-12
    for i, j in index.pairs(a, b):
        if len(i) == 0:
            continue
        d = b[i] - a[i]
        r = e0[j] - a[i]
        ej = e[j]
        den = d[:, 0] * ej[:, 1] - d[:, 1] * ej[:, 0]
        ok = np.abs(den) > 1e-15
        den = np.where(ok, den, 1.0)
        t = (r[:, 0] * ej[:, 1] - r[:, 1] * ej[:, 0]) / den
        u = (r[:, 0] * d[:, 1] - r[:, 1] * d[:, 0]) / den
        ok &= (t >= -tol) & (t <= 1 + tol) & (u >= -tol) & (u <= 1 + tol)
        seg_idx.append(i[ok])
        ts.append(np.clip(t[ok], 0.0, 1.0))
    if not seg_idx:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    return np.concatenate(seg_idx), np.concatenate(ts)


class _FeatureGrid:
    """A uniform grid over the extent listing the features whose bounding box touches each
    cell, so that a query tests each feature only on the points near it (many obstacles).
    Features spanning many cells are tested on all points (their bounding-box test is
    cheaper than gathering)."""

    MAX_CELLS = 64

    def __init__(self, extent, features):
        x0, y0, x1, y1 = extent
        bb = np.array([f.bbox for f in features])
        size = np.maximum(bb[:, 2] - bb[:, 0], bb[:, 3] - bb[:, 1])
        self.cell = max(float(np.median(size)), math.sqrt((x1 - x0) * (y1 - y0) / 65536))
        self.origin = np.array([x0, y0])
        self.shape = (max(1, math.ceil((x1 - x0) / self.cell)),
                      max(1, math.ceil((y1 - y0) / self.cell)))
        lo = self._cell_xy(bb[:, :2])
        hi = self._cell_xy(bb[:, 2:])
        self.cells: list[np.ndarray | None] = []
        for (i0, j0), (i1, j1) in zip(lo, hi, strict=True):
            if (i1 - i0 + 1) * (j1 - j0 + 1) > self.MAX_CELLS:
                self.cells.append(None)
                continue
            ii, jj = np.meshgrid(np.arange(i0, i1 + 1), np.arange(j0, j1 + 1))
            self.cells.append((ii + self.shape[0] * jj).ravel())

    def _cell_xy(self, xy: np.ndarray) -> np.ndarray:
        ij = np.floor((xy - self.origin) / self.cell).astype(np.int64)
        return np.clip(ij, 0, np.array(self.shape) - 1)

    def candidates(self, xy: np.ndarray):
        """A function: feature index → indices of the points in its cells (or None)."""
        ij = self._cell_xy(xy)
        cid = ij[:, 0] + self.shape[0] * ij[:, 1]
        order = np.argsort(cid, kind="stable")
        sorted_cid = cid[order]

        def points_of(i: int):
            cells = self.cells[i]
            if cells is None:
                return None
            start = np.searchsorted(sorted_cid, cells, "left")
            stop = np.searchsorted(sorted_cid, cells, "right")
            if len(cells) == 1:
                return order[start[0]:stop[0]]
            return np.concatenate([order[a:b] for a, b in zip(start, stop, strict=True)])

        return points_of


#: With at most this many features :meth:`Terrain._by_owner` compares the owners with each
#: feature instead of sorting them (the same groups in the same order) [-].
_FEW_FEATURES = 16


@nb.njit(cache=True, nogil=True)
def _in_boxes(xy, boxes):  # pragma: no cover - compiled
    """(F, n) bool: point j in feature i's closed bbox (``features._in_bbox``'s tests)."""
    n, nf = xy.shape[0], boxes.shape[0]
    out = np.zeros((nf, n), np.bool_)
    for j in range(n):
        x, y = xy[j, 0], xy[j, 1]
        for i in range(nf):
            if x >= boxes[i, 0] and x <= boxes[i, 2] and y >= boxes[i, 1] and y <= boxes[i, 3]:
                out[i, j] = True
    return out


@nb.njit(cache=True, nogil=True)
def _owner_groups(own, nf):  # pragma: no cover - compiled
    """The points of each owner 0..nf-1, ascending (``np.flatnonzero(own == f)`` for every
    f): indices (m,) and bounds (nf + 1,) of each owner's run in them."""
    starts = np.zeros(nf + 1, np.int64)
    for j in range(own.shape[0]):
        if own[j] >= 0:
            starts[own[j] + 1] += 1
    for f in range(nf):
        starts[f + 1] += starts[f]
    order = np.empty(starts[nf], np.int64)
    fill = starts[:nf].copy()
    for j in range(own.shape[0]):
        f = own[j]
        if f >= 0:
            order[fill[f]] = j
            fill[f] += 1
    return order, starts


@dataclass(frozen=True, eq=False)
class Terrain:
    """A flat base plane over ``extent`` plus features composed in override order.

    Parameters
    ----------
    extent : (xmin, ymin, xmax, ymax) of the ground [m]
    base : height of the flat base plane [m]
    features : features; where footprints overlap the last one listed wins.
    """

    extent: tuple[float, float, float, float]
    base: float = 0.0
    features: tuple[Feature, ...] = ()

    def __post_init__(self):
        ext = tuple(float(v) for v in self.extent)
        if len(ext) != 4 or not (ext[2] > ext[0] and ext[3] > ext[1]):
            raise invalid("Terrain", "extent", "(xmin, ymin, xmax, ymax) with max > min [m]",
                          self.extent)
        object.__setattr__(self, "extent", ext)
        object.__setattr__(self, "features", tuple(self.features))
        if not np.isfinite(self.base):
            raise invalid("Terrain", "base", "a finite height [m]", self.base)
        inside = self.area.buffer(1e-9)
        for i, f in enumerate(self.features):
            if not inside.covers(shapely.box(*f.bbox)):
                raise invalid("Terrain", f"features[{i}]", f"inside the extent {ext} [m]",
                              tuple(round(v, 3) for v in f.bbox))

    @classmethod
    def flat(cls, extent, base: float = 0.0) -> Terrain:
        """Flat ground at height ``base`` [m] over ``extent`` [m]."""
        return cls(extent, base)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the ground [m]."""
        return self.extent

    @functools.cached_property
    def area(self) -> Polygon:
        """The ground's extent as a shapely polygon [m]."""
        return shapely.box(*self.extent)

    # -- point queries --

    @functools.cached_property
    def _grid(self) -> _FeatureGrid | None:
        return _FeatureGrid(self.extent, self.features) if len(self.features) > 16 else None

    @functools.cached_property
    def _boxes(self) -> np.ndarray | None:
        """(F, 4) bboxes of the features when there are at most :data:`_FEW_FEATURES` and
        each is a :class:`Block` that is its own bbox or a :class:`StairFlight` (then
        :meth:`owner` tests them all in one compiled pass), else None."""
        if not self.features or len(self.features) > _FEW_FEATURES:
            return None
        for f in self.features:
            if not (isinstance(f, StairFlight)
                    or (isinstance(f, Block) and _is_box(f.footprint, f.bbox))):
                return None
        return np.array([f.bbox for f in self.features], dtype=float)

    def _owner_of_boxes(self, xy: np.ndarray) -> np.ndarray:
        """:meth:`owner` where :attr:`_boxes` holds: the closed-bbox tests of every
        feature in one pass (``_in_bbox``'s comparisons), then a flight's own test on the
        points in its bbox (``StairFlight._on_flight``, as its ``covers`` does)."""
        own = np.full(len(xy), -1, dtype=np.int64)
        inside = _in_boxes(xy, self._boxes)
        for i, f in enumerate(self.features):
            if isinstance(f, StairFlight):
                idx = np.flatnonzero(inside[i])
                if idx.size:
                    own[idx[f._on_flight(xy[idx])]] = i
            else:
                own[inside[i]] = i
        return own

    def owner(self, xy) -> np.ndarray:
        """Index of the feature that decides each point's height, −1 for the base; (n,)."""
        xy = _points(xy)
        if self._boxes is not None:
            return self._owner_of_boxes(xy)
        own = np.full(len(xy), -1, dtype=np.int64)
        if self._grid is None or len(xy) < 64:
            for i, f in enumerate(self.features):
                own[f.covers(xy)] = i
            return own
        candidates = self._grid.candidates(xy)
        for i, f in enumerate(self.features):  # in order: later features override
            idx = candidates(i)
            if idx is None:
                own[f.covers(xy)] = i
            elif len(idx):
                own[idx[f.covers(xy[idx])]] = i
        return own

    def _by_owner(self, own: np.ndarray):
        """(feature index, point indices) for every feature that owns points, in feature
        order, the indices ascending."""
        if len(self.features) <= _FEW_FEATURES:  # a comparison per feature: no sort
            if len(self.features) > 1:  # grouped in one compiled pass
                order, starts = _owner_groups(own, len(self.features))
                for f in range(len(self.features)):
                    if starts[f + 1] > starts[f]:
                        yield f, order[starts[f]:starts[f + 1]]
                return
            for f in range(len(self.features)):
                k = np.flatnonzero(own == f)
                if len(k):
                    yield f, k
            return
        idx = np.flatnonzero(own >= 0)
        if len(idx) == 0:
            return
        order = idx[np.argsort(own[idx], kind="stable")]
        feats, starts = np.unique(own[order], return_index=True)
        stops = np.append(starts[1:], len(order))
        for f, a, b in zip(feats, starts, stops, strict=True):
            yield int(f), order[a:b]

    def _surface(self, xy: np.ndarray, ref: np.ndarray, own: np.ndarray) -> np.ndarray:
        z = np.full(len(xy), float(self.base))
        for i, k in self._by_owner(own):
            f = self.features[i]
            # a block's top is flat: its surface's value, without gathering its points
            z[k] = float(f.top) if isinstance(f, Block) else f.surface(xy[k], ref[k])
        return z

    def height(self, xy) -> np.ndarray:
        """Ground height z [m] at points ``xy`` (n, 2) [m]; (n,)."""
        xy = _points(xy)
        return self._surface(xy, xy, self.owner(xy))

    def normal(self, xy) -> np.ndarray:
        """Unit upward surface normal (n, 3) at ``xy`` (n, 2) [m] (of the tread or top face
        at an edge, never of a riser)."""
        xy = _points(xy)
        own = self.owner(xy)
        g = np.zeros((len(xy), 2))
        for i, k in self._by_owner(own):
            g[k] = self.features[i].gradient(xy[k])
        n = np.column_stack([-g, np.ones(len(xy))])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def kind(self, xy) -> np.ndarray:
        """Terrain-type code (:class:`TerrainKind`) of each point (n, 2) [m]; (n,) int."""
        own = self.owner(xy)
        codes = np.array([int(f.kind) for f in self.features] + [int(TerrainKind.FLAT)])
        return codes[own]

    def footing(self, xy, direction, *, stride) -> tuple[np.ndarray, np.ndarray]:
        """What footholds ``xy`` (k, 2) [m] stand on, for steps along unit ``direction``
        (k, 2): the terrain kind (k,) int (:meth:`kind`) and whether the foothold is on
        an obstacle (k,) bool — a block whose chord through the foothold along the
        direction is at most ``stride`` (k,) [m], so that it could have been stepped
        over (Chen & Li Fig. 11), not a terrace or a sidewalk one walks along."""
        xy = _points(xy)
        own = self.owner(xy)
        codes = np.array([int(f.kind) for f in self.features] + [int(TerrainKind.FLAT)])
        kind = codes[own]
        obstacle = np.zeros(len(xy), bool)
        block = np.flatnonzero(kind == TerrainKind.BLOCK)
        if block.size:
            reach = 2.0  # [m] either side: longer than any chord that counts
            stride = np.asarray(stride, float)
            # a foothold farther than half the stride from its block's outline stands on
            # a chord longer than the stride (the line through it holds the part within
            # that distance either side): not an obstacle, no chord cut (the margin
            # covers the rounding of both lengths, ~1e-12 m)
            outline = self._outlines[own[block]]
            inside = shapely.distance(shapely.points(xy[block]), outline)
            cut = block[2.0 * np.minimum(inside, reach) <= stride[block] + 1e-6]
            if cut.size:
                d = np.asarray(direction, float)[cut]
                lines = shapely.linestrings(np.stack([xy[cut] - reach * d,
                                                      xy[cut] + reach * d], axis=1))
                polys = np.array([self.features[k].footprint for k in own[cut]],
                                 dtype=object)
                chord = shapely.length(shapely.intersection(lines, polys))
                obstacle[cut] = chord <= stride[cut]
        return kind, obstacle

    @functools.cached_property
    def _outlines(self) -> np.ndarray:
        """(features,) object: each block's footprint outline (None for the others)."""
        return np.array([f.footprint.boundary if f.kind == TerrainKind.BLOCK else None
                         for f in self.features], dtype=object)

    # -- profile --

    @functools.cached_property
    def _breaks(self) -> _EdgeIndex:
        parts = [f.breaks() for f in self.features]
        return _EdgeIndex(np.concatenate(parts) if parts else np.zeros((0, 2, 2)))

    def profile_arrays(self, polyline) -> tuple[np.ndarray, np.ndarray]:
        """Ground profile along ``polyline`` (k, 2) [m]: arc length s (m,) [m] from the first
        point and height z (m,) [m], piecewise linear; two rows with equal s are a vertical
        height change. Exact at every edge (floating-point precision)."""
        return self.profiles([polyline])[0]

    def profiles(self, polylines) -> list[tuple[np.ndarray, np.ndarray]]:
        """:meth:`profile_arrays` for many polylines in one batched pass (one terrain query
        for all of them): a list of (s, z) pairs [m]. ``polylines`` is a sequence of
        (k, 2) arrays [m], or an (m, 2, 2) array of straight lines (prepared without a
        Python loop)."""
        s, z, bounds, singles = self._profile_rows(polylines)
        out = [(s[i:j], z[i:j]) for i, j in zip(bounds[:-1], bounds[1:], strict=True)]
        for li, z1 in singles.items():
            out[li] = (np.zeros(1), z1)
        return out

    def profiles_packed(self, polylines) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`profiles` concatenated: s and z (V,) [m] of every profile in turn and the
        number of rows of each (m,) (line i's rows follow lines 0..i-1's), without a
        Python loop over the lines."""
        s, z, bounds, singles = self._profile_rows(polylines)
        sizes = np.diff(bounds)
        if singles:  # lines of one point (no rows of their own): their one row in place
            at = np.fromiter(singles, np.int64)  # ascending
            s = np.insert(s, bounds[at], 0.0)
            z = np.insert(z, bounds[at], np.concatenate(list(singles.values())))
            sizes[at] = 1
        return s, z, sizes

    def _profile_rows(self, polylines):
        """The rows of :meth:`profiles` but the one-point lines': s, z (V,) [m], each
        line's bounds (m + 1,) into them, and {line: its height (1,) [m]} of the lines of
        one point (no rows), ascending."""
        if isinstance(polylines, np.ndarray) and polylines.shape[1:] == (2, 2):
            lines = polylines.astype(float, copy=False)  # m straight lines, stacked
            a, b, line_of, s_seg0, singles = _straight_segments(lines)
        else:
            lines = [_points(pl, "Terrain", "polyline") for pl in polylines]
            a, b, line_of, s_seg0, singles = _polyline_segments(lines)
        heights = {li: self.height(pt) for li, pt in singles.items()}
        if a.size == 0:
            return np.zeros(0), np.zeros(0), np.zeros(len(lines) + 1, np.int64), heights
        seg_len = np.linalg.norm(b - a, axis=1)
        m = len(a)
        index = self._breaks
        hit_seg, hit_t = _crossings(a, b, index) if len(index.edges) else (
            np.zeros(0, dtype=np.int64), np.zeros(0))
        seg = np.concatenate([np.arange(m), np.arange(m), hit_seg])
        t = np.concatenate([np.zeros(m), np.ones(m), hit_t])
        order = np.lexsort((t, seg))
        seg, t = seg[order], t[order]
        s = s_seg0[seg] + t * seg_len[seg]
        pts = a[seg] + t[:, None] * (b[seg] - a[seg])
        # pieces between consecutive cut points of the same segment, each on one plane
        i0 = np.flatnonzero((seg[1:] == seg[:-1]) & (s[1:] - s[:-1] > 1e-12))
        mid = 0.5 * (pts[i0] + pts[i0 + 1])
        own = self.owner(mid)
        za = self._surface(pts[i0], mid, own)
        zb = self._surface(pts[i0 + 1], mid, own)
        n = len(i0)
        s_rows = np.empty(2 * n)
        z_rows = np.empty(2 * n)
        s_rows[0::2], s_rows[1::2] = s[i0], s[i0 + 1]
        z_rows[0::2], z_rows[1::2] = za, zb
        row_line = np.repeat(line_of[seg[i0]], 2)
        # drop a row that repeats the previous one (continuous ground at a cut)
        same_line = np.concatenate([[False], row_line[1:] == row_line[:-1]])
        dup = same_line & np.concatenate([[False], (np.abs(np.diff(s_rows)) <= 1e-12)
                                          & (np.abs(np.diff(z_rows)) <= 1e-12)])
        s_rows, z_rows, row_line = s_rows[~dup], z_rows[~dup], row_line[~dup]
        # snap the two rows of a vertical change to exactly the same s
        same_line = np.concatenate([[False], row_line[1:] == row_line[:-1]])
        step = same_line & np.concatenate([[False], np.abs(np.diff(s_rows)) <= 1e-12])
        s_rows[step] = s_rows[np.flatnonzero(step) - 1]
        bounds = np.searchsorted(row_line, np.arange(len(lines) + 1))
        return s_rows, z_rows, bounds, heights

    def profile(self, polyline):
        """Ground profile along ``polyline`` (k, 2) [m] as a ``planners.GroundProfile``
        (s = 0 at the polyline's first point)."""
        s, z = self.profile_arrays(polyline)
        from planners.profile import GroundProfile

        return GroundProfile(s, z)

    # -- mesh (crowdwalk.terrain.meshing) --

    @functools.cached_property
    def _arrangement(self):
        """All feature outlines and the extent, noded into one line network [m]."""
        lines = [_ring_segments(self.area)] + [f.outline() for f in self.features]
        return shapely.union_all(shapely.linestrings(np.concatenate(lines)))

    def steps(self, min_height: float = 0.0) -> np.ndarray:
        """Edges where the ground changes height by more than ``min_height`` [m] (risers,
        curbs, block sides, walls) as segments (m, 2, 2) [m]."""
        from crowdwalk.terrain.meshing import height_steps

        return height_steps(self, min_height)

    def mesh(self) -> trimesh.Trimesh:
        """The whole ground as one triangle mesh [m] (see :mod:`crowdwalk.terrain.meshing`)."""
        from crowdwalk.terrain.meshing import ground_mesh

        return ground_mesh(self)


def _straight_segments(lines: np.ndarray):
    """:func:`_polyline_segments` for m straight lines (m, 2, 2) [m], vectorised."""
    seg = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    long = seg > 1e-9
    singles = {int(li): lines[li, :1] for li in np.flatnonzero(~long)}
    return (lines[long, 0], lines[long, 1], np.flatnonzero(long), np.zeros(int(long.sum())),
            singles)


def _polyline_segments(lines):
    """Segments of polylines (list of (k, 2)) [m]: starts and ends (S, 2), line index and
    arc length of each start along its line (S,) [m], and the lines that are one point
    ({line: (1, 2)}); repeated points are dropped."""
    a_list, b_list, line_of, s0_list, singles = [], [], [], [], {}
    for li, pl in enumerate(lines):
        if len(pl) < 2:
            raise invalid("Terrain", "polyline", "at least 2 points [m]", len(pl))
        seg = np.linalg.norm(np.diff(pl, axis=0), axis=1)
        keep = np.concatenate([[True], seg > 1e-9])  # drop repeated points
        pl, seg = pl[keep], seg[seg > 1e-9]
        if len(pl) < 2:
            singles[li] = pl[:1]
            continue
        a_list.append(pl[:-1])
        b_list.append(pl[1:])
        line_of.append(np.full(len(seg), li))
        s0_list.append(np.concatenate([[0.0], np.cumsum(seg)[:-1]]))
    if not a_list:
        return np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0), singles
    return (np.concatenate(a_list), np.concatenate(b_list), np.concatenate(line_of),
            np.concatenate(s0_list), singles)
