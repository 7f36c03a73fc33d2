"""The neighbours of the deciding agents: one ``cKDTree`` per tick, queried (and the
neighbours' motion gathered) for parts of the deciders in threads at once."""

from __future__ import annotations

from functools import partial

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
    dist, nb = tree.query(me, k=k, distance_upper_bound=reach)
    m = len(deciders)
    nb = np.atleast_2d(nb).reshape(m, k)
    valid = nb < walkers.size
    nb_safe = np.where(valid, nb, 0)
    agent = walkers[nb_safe]
    valid &= agent != deciders[:, None]
    t1 = st.t1[agent]
    span = t1 - st.t0[agent]
    moving = (t1 > t) & (span > 0)
    pos1 = st.pos1[agent]
    vel = np.where(moving[..., None], (pos1 - st.pos0[agent])
                   / np.where(span > 0, span, 1.0)[..., None], 0.0)
    return Neighbours(valid=valid, now=now[nb_safe], end=pos1, velocity=vel,
                      heading=st.heading[agent], radius=radius[agent],
                      remaining=np.where(moving, t1 - t, 0.0),
                      yaw_now=st.yaw(t, agent.ravel()).reshape(agent.shape),
                      yaw_end=st.yaw1[agent], shape=packed[agent])
