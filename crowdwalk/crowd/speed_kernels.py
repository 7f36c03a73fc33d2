"""The route-lane headway speed (:func:`crowdwalk.crowd.speed.headway_speed` with
``lane_direction``, ``CrowdParams.headway_route_lane``) as one compiled ``nogil`` loop over
the walkers, their neighbours and their candidate directions.

Each value is the array formulation's, bit for bit (``tests/crowd/test_speed_kernels.py``,
whose reference it is): the same operations in its order; its two-term ``einsum`` dot
products are ``x0 y0 + x1 y1``, and ``min``, ``maximum`` and ``minimum`` keep a NaN (and
the sign of a zero) as numpy's do.
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["route_lane_headway"]


@nb.njit(cache=True, nogil=True)
def route_lane_headway(position, others, radius, others_radius, valid, d, e, shift, lane,
                       free_speed, time_gap, out):
    """The route-lane headway speeds (k, C) [m/s] into ``out``: the leader of a walker
    at ``position`` (k, 2) [m] stepping along candidate ``d`` (k, C, 2) is the nearest of
    its ``valid`` (k, m) neighbours at ``others`` (k, m, 2) [m] ahead along its unit route
    direction ``e`` (k, 2) whose centre is within ``lane`` (k,) [m] of the line parallel
    to ``e`` through the step's end (``shift`` (k,) [m] along ``d``); Seyfried's relation
    (gap less the two radii, ``radius`` (k,) and ``others_radius`` (k, m) [m], over
    ``time_gap`` [s]) limits the speed along ``e`` only, at most ``free_speed`` (k,)
    [m/s], free for a step across or back (d · e <= 1e-3). ``out`` holds each row's gaps
    until its speeds replace them."""
    k, n_c = d.shape[0], d.shape[1]
    n_m = others.shape[1]
    for i in range(k):
        px, py = position[i, 0], position[i, 1]
        ex, ey = e[i, 0], e[i, 1]
        for c in range(n_c):
            out[i, c] = np.inf
        for j in range(n_m):
            rx = others[i, j, 0] - px
            ry = others[i, j, 1] - py
            along = rx * ex + ry * ey
            lateral = rx * ey - ry * ex
            ahead = valid[i, j] and along > 0
            g = along - (radius[i] + others_radius[i, j])
            for c in range(n_c):
                end = shift[i] * (d[i, c, 0] * ey - d[i, c, 1] * ex)
                h = g if ahead and np.abs(lateral - end) < lane[i] else np.inf
                gap = out[i, c]
                if gap == gap and not h >= gap:  # np.min: the least, a NaN kept
                    out[i, c] = h
        v0 = free_speed[i]
        for c in range(n_c):
            gap = out[i, c]
            forward = d[i, c, 0] * ex + d[i, c, 1] * ey
            if forward > 1e-3:
                v_e = (gap if (gap >= 0.0 or gap != gap) else 0.0) / time_gap  # np.maximum
                v = v_e / forward  # forward > 1e-3: np.maximum(forward, 1e-3) is forward
                out[i, c] = v0 if (v0 <= v or v0 != v0) else v  # np.minimum(v0, v)
            else:
                out[i, c] = v0
