"""The neighbours of the deciding agents: one ``cKDTree`` query per tick."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd.shape import BodyShape
from crowdwalk.crowd.steering import Neighbours

__all__ = ["gather_neighbours"]


def gather_neighbours(state, deciders: np.ndarray, *, t: float, walkers: np.ndarray,
                      shape: BodyShape, count: int, reach: float) -> Neighbours:
    """The nearest ``count`` walking agents within ``reach`` [m] of each of ``deciders``
    (k,) at time ``t`` [s], with their committed motion and outline (:class:`Neighbours`).

    ``walkers`` (w,) are the walking agents' indices, ``shape`` (n) every agent's outline.
    """
    st = state
    k = min(count + 1, walkers.size)
    now, _ = st.position(t, walkers)
    tree = cKDTree(now)
    me, _ = st.position(t, deciders)
    dist, nb = tree.query(me, k=k, distance_upper_bound=reach)
    m = len(deciders)
    nb = np.atleast_2d(nb).reshape(m, k)
    valid = nb < walkers.size
    nb_safe = np.where(valid, nb, 0)
    agent = walkers[nb_safe]
    valid &= agent != deciders[:, None]
    span = st.t1[agent] - st.t0[agent]
    moving = (st.t1[agent] > t) & (span > 0)
    vel = np.where(moving[..., None], (st.pos1[agent] - st.pos0[agent])
                   / np.where(span > 0, span, 1.0)[..., None], 0.0)
    return Neighbours(valid=valid, now=now[nb_safe], end=st.pos1[agent], velocity=vel,
                      heading=st.heading[agent], radius=shape.radius[agent],
                      remaining=np.where(moving, st.t1[agent] - t, 0.0),
                      yaw_now=st.yaw(t, agent.ravel()).reshape(agent.shape),
                      yaw_end=st.yaw1[agent], shape=shape.packed(agent))
