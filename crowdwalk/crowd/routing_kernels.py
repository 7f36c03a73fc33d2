"""The steering targets (:func:`crowdwalk.crowd.routing.steering_targets`) as one compiled
``nogil`` loop over the deciding walkers.

Each row does the array formulation's operations in its order, so the targets and
directions are its values bit for bit (``tests/crowd/test_routing_kernels.py``): the
route's points are ``np.interp``'s (numpy's ``arr_interp``: the last vertex at or before
the arc length, that vertex's value where it is hit exactly, else slope times offset plus
value), the clearance is :func:`crowdwalk.crowd.clearance._bilinear`, norms are
``sqrt(x x + y y)`` (``np.linalg.norm`` over a last axis of two), and the headings'
cosines and sines come in from numpy. A candidate target's tests stop at the first that
accepts it (the array code tested every candidate; the tests have no side effects).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from crowdwalk.crowd.clearance import _bilinear

__all__ = ["LANE_CAPS", "LINE_UP_REACH", "LINE_UP_QUARTERS", "steering_rows"]

#: lane_keep: how far off the centre line the lane ahead is tried, in order [m].
LANE_CAPS = (0.6, 0.45, 0.3, 0.2, 0.1)
#: line_up: the centre-line points tried, this far ahead of the walker's progress [m].
LINE_UP_REACH = (1.5, 1.0, 0.6, 0.3, 0.0)
#: line_up: where the line to a candidate is tested against the walls (fractions).
LINE_UP_QUARTERS = (0.25, 0.5, 0.75)


@nb.njit(cache=True, nogil=True, inline="always")
def _interp(s, xy, c, lo, hi, x):
    """``np.interp(x, s, xy[:, c])`` for an ``x`` within ``[s[lo], s[hi]]`` (or NaN): the
    last vertex j in [lo, hi] with s[j] <= x is the one numpy's search finds."""
    if x != x:
        return x
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if s[mid] <= x:
            lo = mid
        else:
            hi = mid - 1
    j = lo
    if j == s.shape[0] - 1 or s[j] == x:
        return xy[j, c]
    slope = (xy[j + 1, c] - xy[j, c]) / (s[j + 1] - s[j])
    res = slope * (x - s[j]) + xy[j, c]
    if res != res:
        res = slope * (x - s[j + 1]) + xy[j + 1, c]
        if res != res and xy[j, c] == xy[j + 1, c]:
            res = xy[j, c]
    return res


@nb.njit(cache=True, nogil=True, inline="always")
def _point_at(s, xy, start, stop, s0, s1, route, x):
    """``RouteTable.point_at``: the point at global arc length ``x`` [m], clipped to the
    route (``np.clip``: NaN stays NaN)."""
    lo, hi = s0[route], s1[route]
    if x < lo:
        x = lo
    if x > hi:
        x = hi
    a, b = start[route], stop[route]
    return _interp(s, xy, 0, a, b, x), _interp(s, xy, 1, a, b, x)


@nb.njit(cache=True, nogil=True, inline="always")
def _nan_min(a, b):
    """``np.minimum`` of two floats (NaN wins)."""
    if a != a or b != b:
        return np.nan
    return a if a <= b else b


@nb.njit(cache=True, nogil=True)
def steering_rows(s, xy_tab, start, stop, s0, s1, dist, ox, oy, cell, route, progress, xy,
                  cos_h, sin_h, radius, target_distance, centre_pull, lane_keep, line_up,
                  lane_only, target, direction, lane_blind):
    """:func:`crowdwalk.crowd.routing.steering_targets` of k rows into ``target``,
    ``direction`` (k, 2) and ``lane_blind`` (k,) (whether the lane runs into a wall, as
    ``_lane`` finds it); ``lane_only``: the lane test alone (``target`` and ``direction``
    not written)."""
    caps = LANE_CAPS
    reaches = LINE_UP_REACH
    quarters = LINE_UP_QUARTERS
    for i in range(route.shape[0]):
        r = route[i]
        x, y = xy[i, 0], xy[i, 1]
        rad = radius[i]
        px, py = _point_at(s, xy_tab, start, stop, s0, s1, r, progress[i])
        ax, ay = _point_at(s, xy_tab, start, stop, s0, s1, r, progress[i] + target_distance)
        tx = x + (ax - px) + centre_pull * (px - x)
        ty = y + (ay - py) + centre_pull * (py - y)
        blind = (_bilinear(dist, ox, oy, cell, tx, ty) < rad
                 or _bilinear(dist, ox, oy, cell, 0.5 * (tx + x), 0.5 * (ty + y)) < rad)
        lane_blind[i] = blind
        if lane_only:
            continue
        if blind and lane_keep:
            ux, uy = tx - ax, ty - ay
            size = np.sqrt(ux * ux + uy * uy)
            if not size >= 1e-9:  # np.maximum(size, 1e-9): NaN stays NaN
                size = size if size != size else 1e-9
            for cap in caps:
                f = _nan_min(1.0, cap / size)
                cx, cy = ax + ux * f, ay + uy * f
                if (_bilinear(dist, ox, oy, cell, cx, cy) >= rad
                        and _bilinear(dist, ox, oy, cell, 0.5 * (cx + x), 0.5 * (cy + y)) >= rad):
                    tx, ty = cx, cy
                    blind = False
                    break
        if blind and line_up:
            for reach in reaches:
                cx, cy = _point_at(s, xy_tab, start, stop, s0, s1, r, progress[i] + reach)
                dx, dy = cx - x, cy - y
                ok = (_bilinear(dist, ox, oy, cell, cx, cy) >= rad
                      and np.sqrt(dx * dx + dy * dy) >= rad)
                for f in quarters:
                    if not ok:
                        break
                    ok = _bilinear(dist, ox, oy, cell, x + f * dx, y + f * dy) >= rad
                if ok:
                    tx, ty = cx, cy
                    blind = False
                    break
        if blind:
            tx, ty = ax, ay
        target[i, 0], target[i, 1] = tx, ty
        dx, dy = tx - x, ty - y
        n = np.sqrt(dx * dx + dy * dy)
        if n < 1e-9:
            direction[i, 0], direction[i, 1] = cos_h[i], sin_h[i]
        else:
            d = n if n > 1e-12 else 1.0  # a NaN norm divides by 1.0, as the array code did
            direction[i, 0], direction[i, 1] = dx / d, dy / d
