"""Waking a standing walker when a neighbour in its way takes its next step
(``CrowdParams.wake_on_step``).

A walker that cannot step stands for ``wait_time`` and decides again. Its steps were cut
by the neighbours' committed steps, each tested as if the neighbour stood at its step's
end for ever after; that holds only until the neighbour's heel strike, when it commits
its next step and the room it leaves becomes usable (the test is made in time). In the
dense queue at a narrow door a walker standing for a fixed time misses that moment by
half a wait on average. Here a standing walker in or within 1 m of an opening decides
again at the tick after the first heel strike of a walking neighbour going the same way
(route directions within 60°) that could be in its way (within the two holding radii and
the walker's nominal step), if that comes before the end of its wait: event-driven, as
people in a queue move up as soon as the one in front moves (the event-driven update of
Seitz & Köster 2014, "How update schemes influence crowd simulations", J. Stat. Mech.
P07002, in which each pedestrian acts at its own next event time). Only when a walker
decides changes, not what it may do: the hard tests are unchanged, so no two bodies
overlap.
"""

from __future__ import annotations

import numpy as np

from crowdwalk.crowd.openings import ZONE_MARGIN, Openings
from crowdwalk.crowd.steering import Neighbours

__all__ = ["ZONE_MARGIN", "WakeOnStep"]

#: same way: the route directions' cosine at least this (within 60°)
SAME_WAY = 0.5


class WakeOnStep:
    """When the standing walkers near the openings of a graph decide again.

    Parameters
    ----------
    graph : crowdwalk.routes.RouteGraph
    max_width : float
        Corridors at most this wide [m] are openings (``CrowdParams.opening_width``).
    """

    def __init__(self, graph, max_width: float) -> None:
        self.zone = Openings(graph, max_width, ZONE_MARGIN)

    def times(self, t: float, dt: float, pos: np.ndarray, nbs: Neighbours, *,
              bound: np.ndarray, nb_bound: np.ndarray, step: np.ndarray,
              direction: np.ndarray, nb_direction: np.ndarray) -> np.ndarray:
        """(m,) the time [s] at which each of m deciders at ``pos`` (m, 2) [m] at tick
        time ``t`` [s] (ticks ``dt`` [s] apart) would decide again if it stands: the tick
        after the first heel strike of a walking same-way neighbour of ``nbs`` (route
        directions ``direction`` (m, 2), ``nb_direction`` (m, K, 2) unit, cosine at least
        ``SAME_WAY``) within ``bound`` +
        ``nb_bound`` (m,), (m, K) holding radii + ``step`` (m,) [m] of it (inf: none, or
        the decider is outside the zone).

        A neighbour at its heel strike decides in the first tick ending at or after it;
        the walker decides in the tick after that, when the neighbour's new step is
        committed.
        """
        m, k = nbs.valid.shape
        out = np.full(m, np.inf)
        if not k or nbs.remaining is None:
            return out
        rows = np.flatnonzero(self.zone.inside(pos))
        if not rows.size:
            return out
        near = np.linalg.norm(nbs.now[rows] - pos[rows, None, :], axis=-1) \
            < (bound[rows, None] + nb_bound[rows] + step[rows, None])
        walking = np.einsum("rkj,rkj->rk", nbs.velocity[rows], nbs.velocity[rows]) > 0.0
        same = np.einsum("rkj,rj->rk", nb_direction[rows], direction[rows]) >= SAME_WAY
        ok = nbs.valid[rows] & near & walking & same & (nbs.remaining[rows] > 0.0)
        first = np.where(ok, nbs.remaining[rows], np.inf).min(axis=1)
        has = np.isfinite(first)
        tick = np.ceil((t + first[has]) / dt - 1e-6)  # the neighbour's deciding tick
        got = np.full(rows.size, np.inf)
        got[has] = (tick + 1.0) * dt
        out[rows] = got
        return out
