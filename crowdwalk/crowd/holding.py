"""Waiting areas and queues (a scenario's ``waiting_areas``): walkers whose route passes a
node stand in its area until they are released.

The model follows JuPedSim's waiting stages. A waiting area has predefined waiting
positions and each walker who enters the area goes to the first free one (JuPedSim's
``WaitingSetStage`` and ``NotifiableQueueStage``). When every position is taken, newcomers
wait where they stand, at the edge of the area; JuPedSim sends them to the last position
instead. The walkers are released in one of two ways:

- ``release_time``: everyone at once at that time, like a waiting set switched to
  inactive. After that the area is open and walkers pass through it;
- ``release_rate``: one at a time, first come first served (in the order they entered),
  at most one every 1/rate seconds, and only once the walker has reached its position. A
  walker who finds the queue empty and the last release more than 1/rate s ago walks on
  at once. This is JuPedSim's notifiable queue popped at a rate: after each release the
  walkers behind move up one position, and walkers beyond the last position take
  the positions that come free.

Waiting positions: a hexagonal lattice :data:`SLOT_SPACING` apart inside the node's area
shrunk by :data:`SLOT_MARGIN`, filled nearest to the node first. Late walkers then walk
past free positions only. Each position holds 0.70 m², which is Fruin's (1971) queueing
level of service C (0.65–0.93 m² per person). At that spacing a walker fits between two
who stand (0.9 − 2 × 0.18 m = 0.54 m > one body), so nobody is shut in. A walker who
spawns in a waiting area waits where it was placed.

Per tick, :meth:`WaitingAreas.hold` does vectorised look-ups for the walkers deciding
then. It tests "inside the area" with ``shapely.contains_xy``, once per area. Handing out
positions and building routes happens only when a walker enters an area, and is done for
that walker alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

__all__ = ["SLOT_SPACING", "SLOT_MARGIN", "WaitingAreas", "waiting_positions"]

#: Spacing of the waiting positions [m] (hexagonal lattice: 0.70 m² each, Fruin 1971 LOS C).
SLOT_SPACING = 0.9
#: Waiting positions keep this far from the area's edge [m].
SLOT_MARGIN = 0.3
_REACHED = 0.3  # a walker this close to its position (along its route) stands there [m]
_NONE = -1


def waiting_positions(area, node_xy: np.ndarray) -> np.ndarray:
    """Waiting positions (m, 2) [m] in ``area`` (shapely polygon): a hexagonal lattice
    :data:`SLOT_SPACING` apart through ``node_xy`` (2,) [m], inside the area shrunk by
    :data:`SLOT_MARGIN`, nearest to the node first (at least the node itself)."""
    inner = area.buffer(-SLOT_MARGIN)
    a = SLOT_SPACING
    x0, y0, x1, y1 = area.bounds
    kx = int(np.ceil(max(x1 - x0, y1 - y0) / a)) + 2
    i, j = np.meshgrid(np.arange(-kx, kx + 1), np.arange(-kx, kx + 1))
    pts = node_xy + np.column_stack([(i + 0.5 * (j % 2)).ravel() * a,
                                     j.ravel() * a * np.sqrt(3) / 2])
    if not inner.is_empty:
        pts = pts[shapely.contains_xy(inner, pts[:, 0], pts[:, 1])]
    else:
        pts = np.zeros((0, 2))
    if len(pts) == 0:
        pts = np.asarray(node_xy, float)[None, :]
    return pts[np.argsort(np.linalg.norm(pts - node_xy, axis=1), kind="stable")]


@dataclass
class _Area:
    node: str
    polygon: object
    slots: np.ndarray  # (m, 2) [m]
    taken: np.ndarray  # (m,) agent at each slot, or -1
    release_time: float  # [s] (nan: by rate)
    interval: float  # [s] between releases (nan: by time)
    queue: list  # agents in the order they entered
    last_release: float = -np.inf
    entered: int = 0  # walkers who entered while it held walkers
    released: int = 0
    first_release: float = np.nan
    last_release_time: float = np.nan


class WaitingAreas:
    """The scenario's waiting areas during a run.

    Parameters
    ----------
    specs : list of crowdwalk.behaviours.WaitingAreaSpec
    routes : crowdwalk.routes.RouteGraph
    n : int
        Number of walkers.
    """

    def __init__(self, specs, routes, n: int) -> None:
        self.areas = []
        for w in specs:
            poly = routes.node_area(w.node)
            shapely.prepare(poly)
            slots = waiting_positions(poly, routes.node_xy(w.node))
            self.areas.append(_Area(
                node=w.node, polygon=poly, slots=slots,
                taken=np.full(len(slots), _NONE), queue=[],
                release_time=np.nan if w.release_time is None else float(w.release_time),
                interval=np.nan if w.release_rate is None else 1.0 / w.release_rate))
        self._index = {a.node: k for k, a in enumerate(self.areas)}
        self.done = np.zeros((n, len(self.areas)), bool)  # released from (or past) area k
        self.area = np.full(n, _NONE)  # the area a walker waits in (or walks to its slot)
        self.slot = np.full(n, _NONE)
        self.slot_s = np.full(n, np.nan)  # route arc length of its position [m]
        self.route = np.full(n, _NONE)  # the route that leads to its position
        self.placed = np.zeros(n, bool)  # waits where it spawned
        self._route_areas = np.zeros((0, 1), np.int64)  # (R, M) areas on each route
        self._known = 0

    # -- per tick ---------------------------------------------------------------------

    def release(self, sim, t: float) -> None:
        """Let go the walkers whose release is due at time ``t`` [s]."""
        for k, a in enumerate(self.areas):
            if not a.queue:
                continue
            if np.isfinite(a.release_time):
                if t >= a.release_time - 1e-9:
                    self._let_go(sim, k, list(a.queue), t)
                continue
            head = a.queue[0]
            if t >= a.last_release + a.interval - 1e-9 and self._at_slot(sim, head):
                a.last_release = t
                self._let_go(sim, k, [head], t)
                self._move_up(sim, k)

    def hold(self, sim, idx: np.ndarray, t: float) -> np.ndarray:
        """(k,) bool: which of the walkers ``idx`` (k,) deciding at time ``t`` [s] stand
        in a waiting area now; walkers entering one are given their waiting position."""
        st = sim.state
        self._learn_routes(sim.routes)
        mine = self.area[idx]
        waiting = mine >= 0
        # a walker re-routed on its way to its position (blocked) gives the position up
        lost = waiting & (st.route[idx] != self.route[idx])
        for i in idx[lost]:
            self._drop(int(i))
        waiting &= ~lost
        held = waiting & self._reached(sim, idx)
        # walkers entering an area their route passes and that is still closed
        areas = self._route_areas[st.route[idx]]  # (k, M)
        valid = areas >= 0
        safe = np.where(valid, areas, 0)
        pending = valid & ~self.done[idx[:, None], safe] & self._closed(safe, t)
        first = np.argmax(pending, axis=1)
        cand = pending.any(axis=1) & ~waiting
        target = safe[np.arange(idx.size), first]
        pos = st.pos1[idx]
        for k in np.unique(target[cand]):
            sel = np.flatnonzero(cand & (target == k))
            inside = shapely.contains_xy(self.areas[k].polygon, pos[sel, 0], pos[sel, 1])
            for j in sel[inside]:  # only when entering: one walker at a time
                held[j] = self._enter(sim, int(idx[j]), int(k), t)
        if held.any():
            st.progress_time[idx[held]] = t  # standing in line is no jam
            st.gain_time[idx[held]] = t
            st.stuck[idx[held]] = 0.0
        return held

    # -- entering and leaving ------------------------------------------------------------

    def _closed(self, areas: np.ndarray, t: float) -> np.ndarray:
        """(...) bool: areas still holding walkers at time ``t`` (not yet released by
        time)."""
        rt = np.array([a.release_time for a in self.areas])[areas]
        return ~(t >= rt - 1e-9)

    def _learn_routes(self, routes) -> None:
        """The waiting areas on the routes added to the table since the last call (each
        route's nodes, in order, without its last one: arrivals are not held)."""
        r = len(routes.table)
        if r == self._known:
            return
        rows = []
        for rid in range(self._known, r):
            nodes, _ = routes.nodes_of(rid)
            rows.append([self._index[v] for v in nodes[:-1] if v in self._index])
        width = max(self._route_areas.shape[1], max(map(len, rows), default=0), 1)
        old = np.full((self._known, width), _NONE)
        old[:, :self._route_areas.shape[1]] = self._route_areas
        new = np.full((len(rows), width), _NONE)
        for k, row in enumerate(rows):
            new[k, :len(row)] = row
        self._route_areas = np.vstack([old, new])
        self._known = r

    def _reached(self, sim, idx: np.ndarray) -> np.ndarray:
        st = sim.state
        s = self.slot_s[idx]
        return np.isfinite(s) & (st.progress[idx] >= s - _REACHED)

    def _at_slot(self, sim, i: int) -> bool:
        st = sim.state
        return bool(st.route[i] == self.route[i]
                    and st.progress[i] >= self.slot_s[i] - _REACHED)

    def _enter(self, sim, i: int, k: int, t: float) -> bool:
        """Walker ``i`` enters area ``k`` at time ``t`` [s]: it is given its waiting
        position and the route there and on. True when it waits where it stands (it
        spawned there, or every position is taken)."""
        st, a = sim.state, self.areas[k]
        if np.isnan(a.release_time) and not a.queue \
                and t >= a.last_release + a.interval - 1e-9:
            a.last_release = t  # an empty queue, the service free: walk on
            a.entered += 1
            self._count_release(a, t)
            self.done[i, k] = True
            return False
        a.queue.append(i)
        a.entered += 1
        self.area[i] = k
        self.placed[i] = st.steps[i] == 0  # spawned here: it waits where it stands
        free = np.flatnonzero(a.taken == _NONE)
        if self.placed[i] or free.size == 0:
            self._stay(sim, i)
            return True
        return self._send(sim, i, int(free[0]))

    def _stay(self, sim, i: int) -> None:
        """Walker ``i`` waits where it stands."""
        self.slot_s[i] = sim.state.progress[i]
        self.route[i] = sim.state.route[i]

    def _send(self, sim, i: int, s: int) -> bool:
        """Send walker ``i`` to position ``s`` of its area: a route from where it stands
        to there and on along its route (False: it walks there; True: no way on from the
        area, it waits where it stands)."""
        st, routes, a = sim.state, sim.routes, self.areas[self.area[i]]
        nodes, _ = routes.nodes_of(st.route[i])
        j = nodes.index(a.node) if a.node in nodes else len(nodes)
        if j + 1 >= len(nodes):
            self._stay(sim, i)
            return True
        if self.slot[i] >= 0:
            a.taken[self.slot[i]] = _NONE
        self.slot[i] = s
        a.taken[s] = i
        spot, graph, rest = a.slots[s], routes.graph, nodes[j:]
        to_spot = graph.shortest_walk(st.pos1[i], spot)
        on = graph.shortest_walk(spot, graph.node_xy(rest[1]))
        stops = [k - j for k in routes.stops_of(st.route[i]) if k > j]
        rid = routes.add(np.vstack([to_spot, on[1:], graph.raw_path(rest[1:])[1:]]), rest,
                         stops)
        table = routes.table
        vs = table.xy[table.start[rid]:table.stop[rid] + 1]
        at = int(np.argmin(np.linalg.norm(vs[:len(to_spot) + 1] - spot, axis=1)))
        self.slot_s[i] = table.s[table.start[rid] + at]
        self.route[i] = rid
        routes.assign(st, i, rid)
        return False

    def _move_up(self, sim, k: int) -> None:
        """After a release from queue ``k`` the walkers behind move up: the q-th in line
        (of those not waiting where they spawned) to the q-th position."""
        a = self.areas[k]
        line = [i for i in a.queue if not self.placed[i]]
        for q, i in enumerate(line[:len(a.slots)]):
            if self.slot[i] != q and a.taken[q] == _NONE:
                self._send(sim, i, q)

    def _let_go(self, sim, k: int, agents: list, t: float) -> None:
        st, a = sim.state, self.areas[k]
        for i in agents:
            a.queue.remove(i)
            self._free(i)
            self.done[i, k] = True
            st.progress_time[i] = st.gain_time[i] = t
            st.stuck[i] = 0.0
            self._count_release(a, t)

    def _count_release(self, a: _Area, t: float) -> None:
        a.released += 1
        a.first_release = t if np.isnan(a.first_release) else a.first_release
        a.last_release_time = t

    def _free(self, i: int) -> None:
        k, s = self.area[i], self.slot[i]
        if s >= 0:
            self.areas[k].taken[s] = _NONE
        self.area[i] = self.slot[i] = self.route[i] = _NONE
        self.slot_s[i] = np.nan
        self.placed[i] = False

    def _drop(self, i: int) -> None:
        a = self.areas[self.area[i]]
        a.queue.remove(i)
        a.entered -= 1
        self._free(i)

    def summary(self) -> list[dict]:
        """Per area: walkers who entered it and were released, and the first and last
        release [s] (for ``summary.json``)."""
        def opt(x):
            return None if not np.isfinite(x) else float(x)

        return [{"node": a.node, "positions": len(a.slots), "entered": a.entered,
                 "released": a.released, "still_waiting": len(a.queue),
                 "first_release_s": opt(a.first_release),
                 "last_release_s": opt(a.last_release_time)} for a in self.areas]
