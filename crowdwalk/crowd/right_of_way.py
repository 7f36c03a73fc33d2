"""Right of way in front of and inside narrow openings (``CrowdParams.right_of_way``).

Where two walkers converge on the same opening, each one's committed step end cuts the
other's next step (the swept-body test: a step may not end where a neighbour's committed
step ends), so both take short steps and half the decisions in front of a 0.8 m mouth
are stands. In the cellular-automaton models of bottleneck flow such a conflict is
resolved by letting one of the walkers move and the other wait; the flow falls with the
share of conflicts in which nobody moves (the "friction" μ of Kirchner, Nishinari &
Schadschneider 2003, "Friction effects and clogging in a cellular automaton model for
pedestrian dynamics", Phys. Rev. E 67, 056122; Yanagisawa et al. 2009, Phys. Rev. E 80,
036110, on the outflow of an exit). Here the walker nearer the opening has right of way:
a walker that decides gives way to every same-way neighbour ahead of it in the zone, by
keeping clear, in its hard step test, of that neighbour's *next* step as well (a
reservation: a body moving from where the neighbour is to one nominal step beyond the
end of its committed step, along its walking direction, over the rest of that step and
one more, and standing there afterwards). The walker behind then shortens or waits rather than putting its
step end into the path of the one ahead.

A reservation only adds constraints to the hard test (the neighbours' real committed
steps are tested as before, and the exact check of the step taken is unchanged), so no
two bodies overlap. Who is ahead is decided along the sum of the two walkers' route
directions, so of two walkers one at most gives way to the other.
"""

from __future__ import annotations

import numpy as np

from crowdwalk.crowd.openings import Openings
from crowdwalk.crowd.steering import Neighbours

__all__ = ["ZONE_MARGIN", "RightOfWay", "with_reservations"]

#: how far into the rooms the zone reaches from the openings' ends [m] (the zipper's and
#: the headway free zone's margin)
ZONE_MARGIN = 1.0
#: a neighbour is ahead when it leads by more than this along the two route directions [m]
AHEAD = 0.05
#: same way: the two route directions' cosine at least this (within 60°)
SAME_WAY = 0.5


class RightOfWay:
    """The reservations of the walkers with right of way near the openings of a graph.

    Parameters
    ----------
    graph : crowdwalk.routes.RouteGraph
    max_width : float
        Corridors at most this wide [m] are openings (``CrowdParams.opening_width``).
    """

    def __init__(self, graph, max_width: float) -> None:
        self.zone = Openings(graph, max_width, ZONE_MARGIN)

    def reservations(self, pos: np.ndarray, direction: np.ndarray, nbs: Neighbours, *,
                     bound: np.ndarray, nb_direction: np.ndarray, nb_step: np.ndarray,
                     nb_time: np.ndarray) -> Neighbours:
        """The reserved next steps (m, K) that the deciders at ``pos`` (m, 2) [m], of
        route direction ``direction`` (m, 2) unit, keep clear of: one per neighbour of
        ``nbs`` that has right of way over the decider (both in the zone, the same way,
        the neighbour ahead), else not ``valid``.

        ``bound`` (m,): the deciders' holding radii [m]; ``nb_direction`` (m, K, 2): the
        neighbours' route directions (unit); ``nb_step``, ``nb_time`` (m, K): their
        nominal step [m] and its time [s]. A reservation is a body of the neighbour's
        outline moving in a straight line from where the neighbour is now to ``nb_step``
        beyond the end of its committed step along its walking direction
        (``nbs.heading``), over its remaining time plus ``nb_time``, then standing (it
        starts where the neighbour is, so it is clear of the decider now). A decider
        does not give up room it stands in: no reservation whose next step (from the
        committed end on) comes within the two holding radii of the decider.
        """
        m, k = nbs.valid.shape
        valid = np.zeros((m, k), bool)
        inside = self.zone.inside(pos)
        if inside.any() and k:
            rows = np.flatnonzero(inside)
            near = nbs.valid[rows]
            nb_in = self.zone.inside(nbs.now[rows][near]).reshape(-1)
            axis = direction[rows][:, None, :] + nb_direction[rows]  # (r, K, 2)
            lead = np.einsum("rkj,rkj->rk", nbs.now[rows] - pos[rows][:, None, :], axis)
            same = np.einsum("rkj,rj->rk", nb_direction[rows], direction[rows]) >= SAME_WAY
            norm = np.linalg.norm(axis, axis=-1)
            ok = same & (lead > AHEAD * norm)
            ok[near] &= nb_in
            valid[rows] = ok & near
        h = np.zeros((m, k)) if nbs.heading is None else nbs.heading
        step = np.where(valid, nb_step, 0.0)[..., None] * np.stack([np.cos(h), np.sin(h)],
                                                                   axis=-1)
        if valid.any():  # the decider stands in the way already: it keeps its room
            hold = nbs.outlines()
            need = bound[:, None] + np.maximum(hold[..., 0], hold[..., 1] + hold[..., 2])
            valid &= _segment_point(nbs.end, nbs.end + step, pos[:, None, :]) >= need
        remaining = np.zeros((m, k)) if nbs.remaining is None else nbs.remaining
        _, yaw_end = nbs.yaws()
        return Neighbours(valid=valid, now=nbs.now, end=nbs.end + step,
                          velocity=np.zeros((m, k, 2)), radius=nbs.radius, heading=h,
                          remaining=np.where(valid, remaining + nb_time, 0.0),
                          yaw_now=yaw_end, yaw_end=yaw_end, shape=nbs.outlines(),
                          agent=nbs.agent)


def _segment_point(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(...) distance [m] from points ``p`` to the segments ``a b`` (..., 2)."""
    ab, ap = b - a, p - a
    den = np.einsum("...j,...j->...", ab, ab)
    s = np.clip(np.einsum("...j,...j->...", ap, ab) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    return np.linalg.norm(ap - s[..., None] * ab, axis=-1)


def with_reservations(nbs: Neighbours, reserved: Neighbours | None) -> Neighbours:
    """``nbs`` followed by the reservations (m, K + K') for the hard step test (the
    reservations only where ``valid``); ``nbs`` itself without any."""
    if reserved is None or not reserved.valid.any():
        return nbs
    cat = np.concatenate
    yn, ye = nbs.yaws()
    rn, re = reserved.yaws()
    rem = nbs.remaining if nbs.remaining is not None else np.zeros(nbs.valid.shape)
    return Neighbours(
        valid=cat([nbs.valid, reserved.valid], axis=1),
        now=cat([nbs.now, reserved.now], axis=1), end=cat([nbs.end, reserved.end], axis=1),
        velocity=cat([nbs.velocity, reserved.velocity], axis=1),
        radius=cat([nbs.radius, reserved.radius], axis=1),
        heading=None if nbs.heading is None else cat([nbs.heading, reserved.heading], axis=1),
        remaining=cat([rem, reserved.remaining], axis=1),
        yaw_now=cat([yn, rn], axis=1), yaw_end=cat([ye, re], axis=1),
        shape=cat([nbs.outlines(), reserved.outlines()], axis=1))
