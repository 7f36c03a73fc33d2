"""The neighbours of the deciding agents: one ``cKDTree`` per tick, queried (and the
neighbours' motion gathered, by one numba kernel) for parts of the deciders in threads at
once."""

from __future__ import annotations

from functools import partial

import numba as nb
import numpy as np
from scipy.spatial import cKDTree

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
    tree = cKDTree(now)
    me, _ = st.position(t, deciders)
    gather = partial(_gather, state=st, t=t, tree=tree, now=now, walkers=walkers,
                     packed=shape.packed(), radius=shape.radius, k=k, reach=reach)
    if threads is None:
        return gather(deciders, me)
    return threads.map(gather, len(deciders), deciders, me)


def _gather(deciders, me, *, state, t, tree, now, walkers, packed, radius, k,
            reach) -> Neighbours:
    """:func:`gather_neighbours` for the deciders ``deciders`` (m,) at ``me`` (m, 2)."""
    st = state
    _, found = tree.query(me, k=k, distance_upper_bound=reach)
    m = len(deciders)
    found = np.ascontiguousarray(np.atleast_2d(found).reshape(m, k), dtype=np.int64)
    out = _Gathered(m, k)
    _gather_motion(found, np.ascontiguousarray(deciders, dtype=np.int64), walkers, float(t),
                   now, st.pos0, st.pos1, st.t0, st.t1, st.heading, st.yaw0, st.yaw1,
                   radius, packed, *out.arrays())
    return Neighbours(valid=out.valid, now=out.now, end=out.end, velocity=out.velocity,
                      heading=out.heading, radius=out.radius, remaining=out.remaining,
                      yaw_now=out.yaw_now, yaw_end=out.yaw_end, shape=out.shape,
                      agent=walkers[np.minimum(found, walkers.size - 1)])


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
