"""Distance to the walls: a signed distance field of the walkable area on a grid.

Built once per run (rasterise the shapely walkable area, Euclidean distance transform
from ``scipy.ndimage``) and then sampled bilinearly for any number of points at once,
so a tick's wall checks cost a few array operations instead of one GEOS call per point.
The sampling is a numba kernel (one thread: the crowd splits a tick's work across cores
by rows, :mod:`crowdwalk.workers`) that gives ``scipy.ndimage.map_coordinates(order=1,
mode="constant")``'s values bit for bit (the same weights, taps and summation order;
``tests/crowd/test_clearance.py``), about 8 times faster.

The steering's hard wall test of every candidate step (:meth:`ClearanceField.step_walls`)
is one kernel too: it stops a run of step lengths at the first blocked one and skips the
samples that a lower bound of the field (the least node of the grid block around a point,
:attr:`ClearanceField.block_least`) shows to be far from the walls, with the same
decisions as sampling everything.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numba as nb
import numpy as np
import shapely
from scipy import ndimage

__all__ = ["ClearanceField"]

#: Outside the grid the clearance is this [m] (strongly negative: not walkable).
OUTSIDE = -10.0
#: Grid cells per side of a block of :attr:`ClearanceField.block_least` [-].
BLOCK = 8
#: What :attr:`ClearanceField.block_least` keeps below the least node [m] (covers the
#: rounding of the bilinear sum, ~1e-14 m here).
BLOCK_MARGIN = 1e-9


@nb.njit(cache=True, nogil=True, inline="always")
def _bilinear(dist, ox, oy, cell, x, y):
    """``map_coordinates(dist, [[row], [col]], order=1, mode="constant", cval=OUTSIDE)``
    at the grid coordinates of (x, y), as scipy computes it: a point outside
    [0, n - 1] on either axis (or NaN) is OUTSIDE; per axis the weights are 1 - f and
    1 - (1 - f) (``get_spline_interpolation_weights``), a tap past the last node is
    mirrored, and the four taps are summed row-major from 0.0, each ``value * w_row *
    w_col``."""
    ny, nx = dist.shape
    r = (y - oy) / cell
    c = (x - ox) / cell
    if not (r >= 0.0 and r <= ny - 1 and c >= 0.0 and c <= nx - 1):
        return OUTSIDE
    r0 = np.floor(r)
    c0 = np.floor(c)
    wr0 = 1.0 - (r - r0)
    wr1 = 1.0 - wr0
    wc0 = 1.0 - (c - c0)
    wc1 = 1.0 - wc0
    i = int(r0)
    j = int(c0)
    i1 = i + 1 if i + 1 < ny else max(ny - 2, 0)
    j1 = j + 1 if j + 1 < nx else max(nx - 2, 0)
    t = 0.0
    t += dist[i, j] * wr0 * wc0
    t += dist[i, j1] * wr0 * wc1
    t += dist[i1, j] * wr1 * wc0
    t += dist[i1, j1] * wr1 * wc1
    return t


@nb.njit(cache=True, nogil=True)
def _sample(dist, ox, oy, cell, xy, out):
    for p in range(out.shape[0]):
        out[p] = _bilinear(dist, ox, oy, cell, xy[p, 0], xy[p, 1])


@nb.njit(cache=True, nogil=True, inline="always")
def _at_least(dist, least, ox, oy, cell, x, y, floor):
    """The clearance at (x, y) as :func:`_bilinear` gives it, or +inf where the point's
    block shows it to be at least ``floor`` [m] (then it is not sampled)."""
    ny, nx = dist.shape
    r = (y - oy) / cell
    c = (x - ox) / cell
    if r >= 0.0 and r < ny - 1 and c >= 0.0 and c < nx - 1:  # both taps in the grid
        if least[int(r) // BLOCK, int(c) // BLOCK] >= floor:
            return np.inf
    return _bilinear(dist, ox, oy, cell, x, y)


@nb.njit(cache=True, nogil=True)
def _step_walls(dist, least, ox, oy, cell, position, stance, ends, dirs, lengths, radius,
                reach, foot_clearance, wall_ok, near):
    for a in range(wall_ok.shape[0]):
        _walls_of(a, dist, least, ox, oy, cell, position, stance, ends, dirs, lengths, radius,
                  reach, foot_clearance, wall_ok, near)


@nb.njit(cache=True, nogil=True)
def _walls_of(a, dist, least, ox, oy, cell, position, stance, ends, dirs, lengths, radius,
              reach, foot_clearance, wall_ok, near):
    """:meth:`ClearanceField.step_walls` of walker (row) ``a``: its rows of ``wall_ok``
    and ``near`` (m, C, L)."""
    _, n_c, n_l = wall_ok.shape
    ny, nx = dist.shape
    px, py = position[a, 0], position[a, 1]
    r = min(radius[a], _bilinear(dist, ox, oy, cell, px, py) - 1e-6)
    # every point a candidate samples (ends, midpoints, quarters, footholds) lies in
    # the box of the ends, the position and the footholds: where each block under
    # that box is at least the largest floor, every sample is +inf (not sampled), so
    # every candidate is clear, as the tests below would find it
    x0 = x1 = px
    y0 = y1 = py
    top = max(max(r, reach[a]), foot_clearance)
    for c in range(n_c):
        for l in range(n_l):
            ex, ey = ends[a, c, l, 0], ends[a, c, l, 1]
            fx = stance[a, 0] + lengths[l] * dirs[a, c, 0]
            fy = stance[a, 1] + lengths[l] * dirs[a, c, 1]
            x0, x1 = min(x0, min(ex, fx)), max(x1, max(ex, fx))
            y0, y1 = min(y0, min(ey, fy)), max(y1, max(ey, fy))
            dx, dy = ex - px, ey - py
            top = max(top, r + 0.25 * np.sqrt(dx * dx + dy * dy))
    r0, r1, c0, c1 = (y0 - oy) / cell, (y1 - oy) / cell, (x0 - ox) / cell, (x1 - ox) / cell
    clear = r0 >= 0.0 and r1 < ny - 1 and c0 >= 0.0 and c1 < nx - 1
    if clear:
        for bi in range(int(r0) // BLOCK, int(r1) // BLOCK + 1):
            for bj in range(int(c0) // BLOCK, int(c1) // BLOCK + 1):
                if not least[bi, bj] >= top:
                    clear = False
                    break
            if not clear:
                break
    if clear:
        wall_ok[a] = True
        near[a] = np.inf
        return
    for c in range(n_c):
        blocked = False
        for l in range(n_l):
            if blocked:  # a shorter step is blocked: so is this one (not tested)
                wall_ok[a, c, l] = False
                near[a, c, l] = np.inf
                continue
            ex, ey = ends[a, c, l, 0], ends[a, c, l, 1]
            at_end = _at_least(dist, least, ox, oy, cell, ex, ey, max(r, reach[a]))
            dx, dy = ex - px, ey - py
            span = 0.25 * np.sqrt(dx * dx + dy * dy)
            half = _at_least(dist, least, ox, oy, cell, 0.5 * (ex + px), 0.5 * (ey + py),
                             max(r + span, reach[a]))
            # and at the sweep's quarters where the body passes near a wall (the
            # clearance changes by at most the distance moved)
            if half < r + span:
                q1 = _bilinear(dist, ox, oy, cell, 0.75 * px + 0.25 * ex,
                               0.75 * py + 0.25 * ey)
                q3 = _bilinear(dist, ox, oy, cell, 0.25 * px + 0.75 * ex,
                               0.25 * py + 0.75 * ey)
                half = min(half, min(q1, q3))
            ok = at_end >= r and half >= r
            if ok:  # the new foothold itself must lie inside the walkable area
                fx = stance[a, 0] + lengths[l] * dirs[a, c, 0]
                fy = stance[a, 1] + lengths[l] * dirs[a, c, 1]
                ok = _at_least(dist, least, ox, oy, cell, fx, fy,
                               foot_clearance) >= foot_clearance
            wall_ok[a, c, l] = ok
            near[a, c, l] = min(at_end, half)
            blocked = not ok


@dataclass(frozen=True)
class ClearanceField:
    """Signed distance to the walkable area's boundary [m] on a regular grid.

    Attributes
    ----------
    origin : (2,) float
        Grid node [0, 0] [m].
    cell : float
        Grid spacing [m].
    distance : (ny, nx) float
        Positive inside the walkable area, negative outside [m].
    """

    origin: np.ndarray
    cell: float
    distance: np.ndarray

    #: Within this distance of the boundary the grid holds exact distances [m].
    exact_band = 0.6

    @classmethod
    def from_area(cls, area, cell: float = 0.05, max_cells: int = 4_000_000) -> ClearanceField:
        """Rasterise a shapely (multi)polygon ``area`` [m] at ``cell`` spacing [m]; the
        spacing grows when the grid would exceed ``max_cells`` nodes."""
        xmin, ymin, xmax, ymax = area.bounds
        margin = 1.0
        width, height = xmax - xmin + 2 * margin, ymax - ymin + 2 * margin
        cell = max(cell, float(np.sqrt(width * height / max_cells)))
        nx, ny = int(np.ceil(width / cell)) + 1, int(np.ceil(height / cell)) + 1
        origin = np.array([xmin - margin, ymin - margin])
        gx = origin[0] + cell * np.arange(nx)
        gy = origin[1] + cell * np.arange(ny)
        xx, yy = np.meshgrid(gx, gy)
        shapely.prepare(area)
        inside = shapely.contains_xy(area, xx, yy)
        d_in = ndimage.distance_transform_edt(inside) * cell
        d_out = ndimage.distance_transform_edt(~inside) * cell
        # distance_transform_edt measures node to the nearest node of the other class;
        # the boundary lies half a cell between them
        dist = np.where(inside, d_in - 0.5 * cell, -(d_out - 0.5 * cell))
        # ... which is up to a cell off where the boundary runs through nodes (a 1 m door
        # on the grid came out 5 cm narrow): near the walls, where the steering tests body
        # radii and foot clearances, the exact distance to the boundary (shapely)
        near = np.abs(dist) < cls.exact_band + cell
        exact = shapely.distance(shapely.points(xx[near], yy[near]), area.boundary)
        dist[near] = np.where(inside[near], exact, -exact)
        return cls(origin=origin, cell=cell, distance=dist)

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        """Signed clearance [m] at points ``xy`` (..., 2) [m]; result (...). Outside the
        grid the clearance is strongly negative."""
        xy = np.asarray(xy, dtype=float)
        flat = np.ascontiguousarray(xy.reshape(-1, 2))
        if not flat.flags.writeable:  # one kernel signature (a read-only view compiles anew)
            flat = flat.copy()
        out = np.empty(flat.shape[0])
        _sample(self.distance, float(self.origin[0]), float(self.origin[1]), float(self.cell),
                flat, out)
        return out.reshape(xy.shape[:-1])

    @cached_property
    def block_least(self) -> np.ndarray:
        """(by, bx) a lower bound of the clearance [m] at any point of each block of
        :data:`BLOCK` × :data:`BLOCK` cells (the least node of the block and of the
        blocks after it, which hold the far taps, less :data:`BLOCK_MARGIN`): bilinear
        sampling gives a weighted mean of four nodes, never less than the least."""
        d = self.distance
        ny, nx = d.shape
        by, bx = -(-ny // BLOCK), -(-nx // BLOCK)
        pad = np.full((by * BLOCK, bx * BLOCK), np.inf)
        pad[:ny, :nx] = d
        least = pad.reshape(by, BLOCK, bx, BLOCK).min(axis=(1, 3))
        grown = np.full((by + 1, bx + 1), np.inf)
        grown[:by, :bx] = least
        least = np.minimum(np.minimum(grown[:-1, :-1], grown[1:, :-1]),
                           np.minimum(grown[:-1, 1:], grown[1:, 1:]))
        return least - BLOCK_MARGIN * (1.0 + np.abs(least))

    def step_walls(self, position: np.ndarray, stance: np.ndarray, ends: np.ndarray,
                   dirs: np.ndarray, lengths: np.ndarray, radius: np.ndarray,
                   reach: np.ndarray, foot_clearance: float) -> tuple[np.ndarray, np.ndarray]:
        """The steering's hard wall test of m walkers' candidate steps.

        A step of length ``lengths[l]`` (L,) [m] along ``dirs`` (m, C, 2) moves the body
        from ``position`` (m, 2) to ``ends`` (m, C, L, 2) [m]; it is clear where the
        clearance at its end, halfway and (where the midpoint is within a quarter sweep
        of it) at its quarters is at least the body's ``radius`` (m,) [m] (or, nearer
        the wall already, what is left of it), and the new foothold ``stance + length
        dir`` at least ``foot_clearance`` [m] from the walls.

        Returns ``wall_ok`` (m, C, L) bool — after the first blocked length of a run
        every longer one is False (not tested: only the clear lengths from the short end
        count) — and ``near`` (m, C, L) [m]: the least clearance at the end and halfway
        where it is less than ``reach`` (m,) [m], else a value not less than ``reach``.
        """
        f = np.ascontiguousarray
        m, n_c, n_l = ends.shape[:3]
        wall_ok = np.empty((m, n_c, n_l), bool)
        near = np.empty((m, n_c, n_l))
        _step_walls(self.distance, self.block_least, float(self.origin[0]),
                    float(self.origin[1]), float(self.cell), f(position, float),
                    f(stance, float), f(ends, float), f(dirs, float), f(lengths, float),
                    f(radius, float), f(reach, float), float(foot_clearance), wall_ok, near)
        return wall_ok, near

    def gradient(self, xy: np.ndarray) -> np.ndarray:
        """Gradient of the clearance (..., 2) (points away from the nearest wall)."""
        h = self.cell
        ex, ey = np.array([h, 0.0]), np.array([0.0, h])
        gx = (self(xy + ex) - self(xy - ex)) / (2 * h)
        gy = (self(xy + ey) - self(xy - ey)) / (2 * h)
        return np.stack([gx, gy], axis=-1)
