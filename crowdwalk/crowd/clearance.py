"""Distance to the walls: a signed distance field of the walkable area on a grid.

Built once per run (rasterise the shapely walkable area, Euclidean distance transform
from ``scipy.ndimage``) and then sampled bilinearly for any number of points at once,
so a tick's wall checks cost a few array operations instead of one GEOS call per point.
The sampling is a numba kernel (one thread: the crowd splits a tick's work across cores
by rows, :mod:`crowdwalk.workers`) that gives ``scipy.ndimage.map_coordinates(order=1,
mode="constant")``'s values bit for bit (the same weights, taps and summation order;
``tests/crowd/test_clearance.py``), about 8 times faster.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
import shapely
from scipy import ndimage

__all__ = ["ClearanceField"]

#: Outside the grid the clearance is this [m] (strongly negative: not walkable).
OUTSIDE = -10.0


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

    def gradient(self, xy: np.ndarray) -> np.ndarray:
        """Gradient of the clearance (..., 2) (points away from the nearest wall)."""
        h = self.cell
        ex, ey = np.array([h, 0.0]), np.array([0.0, h])
        gx = (self(xy + ex) - self(xy - ex)) / (2 * h)
        gy = (self(xy + ey) - self(xy - ey)) / (2 * h)
        return np.stack([gx, gy], axis=-1)
