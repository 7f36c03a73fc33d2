"""Priority at the mouth of a narrow opening (``CrowdParams.mouth_priority``).

In front of a 0.8 m mouth the long clogs are arches of three: two walkers at the wall
corners, each heading into the opening, whose committed step ends cut each other's next
step, and one behind them on the axis with about a centimetre to pass between them. In the
cellular-automaton models of bottleneck flow such a conflict is resolved by letting one of
the walkers move and the other wait; the flow falls with the share of conflicts in which
nobody moves (the "friction" of Kirchner, Nishinari & Schadschneider 2003, "Friction
effects and clogging in a cellular automaton model for pedestrian dynamics", Phys. Rev. E
67, 056122). Here, in front of the mouth (in the opening zone but not in the narrow
corridor itself), the walker nearer the mouth point (the end of the opening's centre line,
on its axis) has priority; of two at the same distance (within ``TIE``) the one of lower
index. A walker that decides keeps clear, in its hard step test, of the *next* step of every
same-way neighbour in front of the mouth with priority over it (a reservation: a body
moving from where the neighbour is to one nominal step beyond the end of its committed
step, along its walking direction, over the rest of that step and one more, and standing
there afterwards). Of the two corner walkers (equally near) one goes first; the walker
on the axis behind them comes after both when it is farther from the mouth point.

A reservation only adds constraints to the hard test (the neighbours' real committed
steps are tested as before, and the exact check of the step taken is unchanged), so no
two bodies overlap. Priority is a strict order (distance, then index), so of two walkers
one at most gives way to the other.
"""

from __future__ import annotations

import numpy as np
import shapely

from crowdwalk.crowd.openings import ZONE_MARGIN, Openings
from crowdwalk.crowd.steering import Neighbours
from crowdwalk.crowd.wake import SAME_WAY

__all__ = ["REACH", "TIE", "ZONE_MARGIN", "MouthPriority", "with_reservations"]

#: only walkers this close to the mouth point take part [m] (the zone's margin)
REACH = 1.0
#: two walkers this close in distance to the mouth point are ordered by index [m]
TIE = 0.05


class MouthPriority:
    """The reservations of the walkers with priority in front of the openings of a graph.

    Parameters
    ----------
    graph : crowdwalk.routes.RouteGraph
    max_width : float
        Corridors at most this wide [m] are openings (``CrowdParams.opening_width``).
    """

    def __init__(self, graph, max_width: float) -> None:
        self.zone = Openings(graph, max_width, ZONE_MARGIN)
        self.narrow = Openings(graph, max_width, 0.0)
        lines = [d["geometry"] for *_, d in graph.layout.edges(data=True)
                 if d["width"] <= max_width]
        axis = shapely.union_all(lines) if lines else shapely.LineString()
        self.axis = axis.intersection(self.narrow.zone.buffer(1e-6))
        shapely.prepare(self.axis)

    def mouth_distance(self, xy: np.ndarray) -> np.ndarray:
        """(k,) distance [m] of points (k, 2) to the openings' centre lines (in front of
        a mouth: to the mouth point)."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if self.axis.is_empty or not len(xy):
            return np.full(len(xy), np.inf)
        return shapely.distance(self.axis, shapely.points(xy))

    def approach(self, xy: np.ndarray, direction: np.ndarray) -> np.ndarray:
        """(k,) whether walkers at points (k, 2) [m] of route direction ``direction``
        (k, 2) unit are in front of a mouth, heading into it: in an opening zone, not in
        the narrow corridor, within ``REACH`` of the mouth point and the route direction
        within 60° (``SAME_WAY``) of the way to it."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        out = self.zone.inside(xy) & ~self.narrow.inside(xy)
        if not out.any():
            return out
        rows = np.flatnonzero(out)
        ends = shapely.get_coordinates(
            shapely.shortest_line(shapely.points(xy[rows]), self.axis)).reshape(-1, 2, 2)
        way = ends[:, 1] - xy[rows]
        dist = np.linalg.norm(way, axis=1)
        into = np.einsum("kj,kj->k", way, direction[rows]) >= SAME_WAY * dist
        out[rows] = (dist <= REACH) & into
        return out

    def priority(self, me: np.ndarray, pos: np.ndarray, direction: np.ndarray,
                 nbs: Neighbours, nb_direction: np.ndarray) -> np.ndarray:
        """(m, K) whether each neighbour of ``nbs`` (``agent`` set) has priority over the
        decider ``me`` (m,) (agent indices) at ``pos`` (m, 2) [m], of route direction
        ``direction`` (m, 2) unit: both in front of a mouth heading into it
        (:meth:`approach`), the same way (``nb_direction`` (m, K, 2) unit), the neighbour
        nearer the mouth point (within ``TIE``: of lower index)."""
        m, k = nbs.valid.shape
        valid = np.zeros((m, k), bool)
        front = self.approach(pos, direction)
        if front.any() and k:
            rows = np.flatnonzero(front)
            near = nbs.valid[rows]
            nb_xy = nbs.now[rows][near]
            nb_front = np.zeros(near.shape, bool)
            nb_front[near] = self.approach(nb_xy, nb_direction[rows][near])
            nb_d = np.full(near.shape, np.inf)
            nb_d[near] = self.mouth_distance(nb_xy)
            d = self.mouth_distance(pos[rows])[:, None]
            tie = np.abs(nb_d - d) <= TIE
            first = np.where(tie, nbs.agent[rows] < me[rows, None], nb_d < d)
            same = np.einsum("rkj,rj->rk", nb_direction[rows], direction[rows]) >= SAME_WAY
            valid[rows] = near & nb_front & same & first
        return valid

    def reservations(self, me: np.ndarray, pos: np.ndarray, direction: np.ndarray,
                     nbs: Neighbours, *, bound: np.ndarray, nb_direction: np.ndarray,
                     nb_step: np.ndarray, nb_time: np.ndarray) -> Neighbours:
        """The reserved next steps (m, K) that the deciders ``me`` (m,) (agent indices)
        at ``pos`` (m, 2) [m], of route direction ``direction`` (m, 2) unit, keep clear
        of: one per neighbour of ``nbs`` (``agent`` set) that has priority over the
        decider (:meth:`priority`), else not ``valid``.

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
        valid = self.priority(me, pos, direction, nbs, nb_direction)
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
