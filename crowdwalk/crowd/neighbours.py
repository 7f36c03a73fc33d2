"""The neighbours of the deciding agents: one uniform grid of the walkers per tick (a
counting sort, compiled), queried for the k nearest and the neighbours' motion gathered by
numba kernels that release the GIL, for parts of the deciders in threads at once.

A grid, not ``scipy.spatial.cKDTree``: building the tree holds the GIL (4.4 ms per tick at
10,000 walkers, about 8 % of the loop on one core; docs/architecture.md, "Neighbour grid"),
and the grid gives the same neighbours in the same order (nearest first; equal distances by
index)."""

from __future__ import annotations

from functools import partial

import numba as nb
import numpy as np

from crowdwalk.crowd.shape import BodyShape
from crowdwalk.crowd.steering import Neighbours

__all__ = ["gather_neighbours"]


def gather_neighbours(state, deciders: np.ndarray, *, t: float, walkers: np.ndarray,
                      shape: BodyShape, count: int, reach: float,
                      threads=None) -> Neighbours:
    """The nearest ``count`` walking agents within ``reach`` [m] of each of ``deciders``
    (k,) at time ``t`` [s], with their committed motion and outline (:class:`Neighbours`).

    ``walkers`` (w,) are the walking agents' indices, ``shape`` (n) every agent's outline;
    ``threads`` (a :class:`crowdwalk.workers.RowThreads`, optional) gathers parts of the
    deciders at once (the same result).
    """
    st = state
    k = min(count + 1, walkers.size)
    now, _ = st.position(t, walkers)
    grid = _Grid(now, reach)
    me, _ = st.position(t, deciders)
    gather = partial(_gather, state=st, t=t, grid=grid, now=now, walkers=walkers,
                     packed=shape.packed(), radius=shape.radius, k=k, reach=reach)
    if threads is None:
        return gather(deciders, me)
    return threads.map(gather, len(deciders), deciders, me, light=True)


def _gather(deciders, me, *, state, t, grid, now, walkers, packed, radius, k,
            reach) -> Neighbours:
    """:func:`gather_neighbours` for the deciders ``deciders`` (m,) at ``me`` (m, 2)."""
    st = state
    m = len(deciders)
    found = np.full((m, k), walkers.size, np.int64)
    _nearest(np.ascontiguousarray(me, dtype=float), now, grid.origin, grid.cell,
             grid.shape, grid.start, grid.order, float(reach) ** 2, found)
    out = _Gathered(m, k)
    _gather_motion(found, np.ascontiguousarray(deciders, dtype=np.int64), walkers, float(t),
                   now, st.pos0, st.pos1, st.t0, st.t1, st.heading, st.yaw0, st.yaw1,
                   radius, packed, *out.arrays())
    return Neighbours(valid=out.valid, now=out.now, end=out.end, velocity=out.velocity,
                      heading=out.heading, radius=out.radius, remaining=out.remaining,
                      yaw_now=out.yaw_now, yaw_end=out.yaw_end, shape=out.shape,
                      agent=walkers[np.minimum(found, walkers.size - 1)])


class _Grid:
    """The walkers at ``now`` (w, 2) [m] sorted into square cells of at least ``reach`` [m]
    (at most about 2^20 cells): walker ``order[start[c]:start[c + 1]]`` lie in cell c,
    c = ix · shape[1] + iy."""

    def __init__(self, now: np.ndarray, reach: float) -> None:
        lo, hi = _bounds(now) if now.size else (np.zeros(2), np.zeros(2))
        extent = hi - lo
        self.cell = max(float(reach), float(extent.max()) / 1024.0, 1e-9)
        self.origin = lo
        self.shape = np.floor(extent / self.cell).astype(np.int64) + 1
        self.start, self.order = _bin(now, lo, self.cell, self.shape)


@nb.njit(cache=True, nogil=True)
def _bounds(now):
    """``now.min(axis=0), now.max(axis=0)`` of the walkers at ``now`` (w, 2) (w > 0), in
    one pass (numpy reduces a first axis of an (w, 2) array slowly); NaN if any is."""
    lo, hi = np.empty(2), np.empty(2)
    for c in range(2):
        a, b, nan = np.inf, -np.inf, False
        for i in range(now.shape[0]):
            v = now[i, c]
            if v != v:
                nan = True
            if v < a:
                a = v
            if v > b:
                b = v
        lo[c], hi[c] = (np.nan, np.nan) if nan else (a, b)
    return lo, hi


@nb.njit(cache=True, nogil=True)
def _bin(now, origin, cell, shape):
    """Counting sort of the walkers at ``now`` (w, 2) into the cells: (start, order)."""
    w = now.shape[0]
    key = np.empty(w, np.int64)
    start = np.zeros(shape[0] * shape[1] + 1, np.int64)
    for i in range(w):
        ix = min(int((now[i, 0] - origin[0]) / cell), shape[0] - 1)
        iy = min(int((now[i, 1] - origin[1]) / cell), shape[1] - 1)
        key[i] = ix * shape[1] + iy
        start[key[i] + 1] += 1
    for c in range(1, start.size):
        start[c] += start[c - 1]
    fill = start[:-1].copy()
    order = np.empty(w, np.int64)
    for i in range(w):  # in index order within a cell
        order[fill[key[i]]] = i
        fill[key[i]] += 1
    return start, order


@nb.njit(cache=True, nogil=True)
def _nearest(me, now, origin, cell, shape, start, order, bound2, found):
    """The K nearest walkers (index into ``now``) closer than sqrt(``bound2``) [m] to each
    of ``me`` (m, 2), nearest first, equal squared distances by index, into ``found``
    (m, K) (already ``now.shape[0]`` where there are fewer)."""
    m, k = found.shape
    if k == 0:
        return
    best = np.empty(k)
    for r in range(m):
        fx = (me[r, 0] - origin[0]) / cell
        fy = (me[r, 1] - origin[1]) / cell
        # the cells within one cell of the decider's (cells are at least the reach wide)
        x0, x1 = max(int(np.floor(fx)) - 1, 0), min(int(np.floor(fx)) + 1, shape[0] - 1)
        y0, y1 = max(int(np.floor(fy)) - 1, 0), min(int(np.floor(fy)) + 1, shape[1] - 1)
        n_best = 0
        for ix in range(x0, x1 + 1):
            for iy in range(y0, y1 + 1):
                c = ix * shape[1] + iy
                for j in range(start[c], start[c + 1]):
                    q = order[j]
                    dx = me[r, 0] - now[q, 0]
                    dy = me[r, 1] - now[q, 1]
                    d = dx * dx + dy * dy
                    if d >= bound2:
                        continue
                    if n_best == k and (d > best[k - 1] or (d == best[k - 1]
                                                             and q > found[r, k - 1])):
                        continue
                    # insert (d, q) into the sorted list
                    p = min(n_best, k - 1)
                    while p > 0 and (best[p - 1] > d or (best[p - 1] == d
                                                         and found[r, p - 1] > q)):
                        best[p] = best[p - 1]
                        found[r, p] = found[r, p - 1]
                        p -= 1
                    best[p] = d
                    found[r, p] = q
                    n_best = min(n_best + 1, k)


class _Gathered:
    """The (m, K) arrays of one :class:`Neighbours`, to be filled by the kernel."""

    def __init__(self, m: int, k: int) -> None:
        self.valid = np.empty((m, k), bool)
        self.now, self.end, self.velocity = (np.empty((m, k, 2)) for _ in range(3))
        self.heading, self.radius, self.remaining, self.yaw_now, self.yaw_end = (
            np.empty((m, k)) for _ in range(5))
        self.shape = np.empty((m, k, 3))

    def arrays(self) -> tuple[np.ndarray, ...]:
        return (self.valid, self.now, self.end, self.velocity, self.heading, self.radius,
                self.remaining, self.yaw_now, self.yaw_end, self.shape)


@nb.njit(cache=True, nogil=True)
def _gather_motion(found, deciders, walkers, t, now, pos0, pos1, t0, t1, heading, yaw0, yaw1,
                   radius, packed, valid, o_now, o_end, o_vel, o_heading, o_radius,
                   o_remaining, o_yaw_now, o_yaw_end, o_shape):
    """The neighbours' motion at time ``t`` [s] for the query result ``found`` (m, K) (index
    into ``walkers``; ``walkers.size``: none), as numpy computed it before (element for
    element the same operations: :class:`AgentState`'s ``yaw``; a missing neighbour reads
    walker 0, marked invalid)."""
    m, k = found.shape
    w = walkers.shape[0]
    for r in range(m):
        for c in range(k):
            q = found[r, c]
            ok = q < w
            if not ok:
                q = 0
            a = walkers[q]
            valid[r, c] = ok and a != deciders[r]
            ta, tb = t0[a], t1[a]
            span = tb - ta
            moving = (tb > t) and (span > 0)
            o_now[r, c, 0] = now[q, 0]
            o_now[r, c, 1] = now[q, 1]
            o_end[r, c, 0] = pos1[a, 0]
            o_end[r, c, 1] = pos1[a, 1]
            div = span if span > 0 else 1.0
            for d in range(2):
                o_vel[r, c, d] = (pos1[a, d] - pos0[a, d]) / div if moving else 0.0
            o_heading[r, c] = heading[a]
            o_radius[r, c] = radius[a]
            o_remaining[r, c] = tb - t if moving else 0.0
            f = min(max((t - ta) / div, 0.0), 1.0)
            o_yaw_now[r, c] = yaw0[a] + f * (yaw1[a] - yaw0[a])
            o_yaw_end[r, c] = yaw1[a]
            for d in range(3):
                o_shape[r, c, d] = packed[a, d]
