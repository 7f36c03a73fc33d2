"""Timed events (a scenario's ``events``): close or open a corridor, redirect a group.

Each event acts once, at the first tick at or after its time (event-driven: nothing runs
per tick in between):

- ``close``: a door :data:`DOOR_THICKNESS` thick is shut across the corridor's full width
  at ``at`` (fraction of its centre line from its first node, :func:`door_wall`), at the
  first tick from the event's time at which no body stands in the doorway (nor will at
  the end of its current step; later events wait for it). The
  door is cut out of the walkable area and the corridor leaves the routing graph in both
  directions (:meth:`crowdwalk.routes.RouteGraph.with_closed`); the clearance field the
  steering and the footstep planner read is rebuilt from the new walkable area, so the
  door blocks bodies and steps like any wall. This is how JuPedSim changes the walls of
  a running simulation (``Simulation.switch_geometry``: a new walkable geometry while
  agents stay where they are). Walkers whose way ahead runs through the corridor re-route
  from where they stand (:meth:`~crowdwalk.crowd.routing.Routes.reroute`, the forward
  re-routing); walkers not yet in the walk get the cheapest route from their origin on
  the new graph. With no way left they keep their route and wait at the door.
- ``open``: the door goes, the corridor is back in the graph; every walker reconsiders its
  way on by the same forward re-routing, and unspawned walkers get the cheapest route.
- ``redirect``: the group's walkers go to new ``destinations`` (in order), like Vadere's
  target changers (a pedestrian's target list replaced while it walks). A walker on its
  way continues from where it stands: the shortest walk (inside the walkable area) to the
  node it passed last, to its route's next node or to a node joined to the one passed,
  whichever is cheapest with the route cost from there; walkers not yet in the walk start
  on the new route; walkers who have arrived are not called back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.routing import _length
from crowdwalk.crowd.state import ACTIVE, WAITING
from crowdwalk.errors import InfeasibleError, invalid

__all__ = ["DOOR_THICKNESS", "door_wall", "EventTimeline", "AppliedEvent"]

#: Thickness of a closed door [m]: thick enough that no step (end and middle at least a
#: body radius from every wall, :mod:`crowdwalk.crowd.steering`) can straddle it.
DOOR_THICKNESS = 0.3


def door_wall(routes, corridor: tuple[str, str], at: float, *, owner: str = "Event"):
    """The closed door of ``corridor`` (its two node names) at fraction ``at`` of its
    centre line from ``corridor[0]``: a shapely polygon [m] across the corridor's whole
    width, :data:`DOOR_THICKNESS` thick, that leaves the other corridors and the node areas
    alone. Raises :class:`~crowdwalk.errors.InputError` where it cannot block the
    corridor there (it would cut another corridor or a node area)."""
    a, b = corridor
    g = routes._layout
    if g.has_edge(a, b):
        data = g.edges[a, b]
    else:
        data, at = g.edges[b, a], 1.0 - at
    line, width = data["geometry"], data["width"]
    p = np.asarray(line.interpolate(at, normalized=True).coords[0])
    d = 0.01 * line.length
    q0 = np.asarray(line.interpolate(max(at * line.length - d, 0.0)).coords[0])
    q1 = np.asarray(line.interpolate(min(at * line.length + d, line.length)).coords[0])
    along = (q1 - q0) / np.linalg.norm(q1 - q0)
    across = np.array([-along[1], along[0]])
    h, t = width / 2 + 0.5, DOOR_THICKNESS / 2
    wall = shapely.Polygon([p - h * across - t * along, p + h * across - t * along,
                            p + h * across + t * along, p - h * across + t * along])
    others = [e["geometry"].buffer(e["width"] / 2) for u, v, e in g.edges(data=True)
              if frozenset((u, v)) != frozenset(corridor)]
    others += [routes.node_area(v) for v in g.nodes]
    wall = wall.intersection(line.buffer(width / 2 + 1e-3, cap_style="flat"))
    wall = wall.difference(shapely.union_all(others)) if others else wall
    cross = shapely.LineString([p - (width / 2 - 1e-3) * across,
                                p + (width / 2 - 1e-3) * across])
    if not wall.buffer(1e-9).covers(cross):
        raise invalid(owner, "at", "where the door blocks the corridor alone (not inside "
                      "another corridor or a node area)", round(float(at), 3))
    return wall


@dataclass(frozen=True)
class AppliedEvent:
    """An event carried out: ``time`` [s] it acted, ``action``, the ``corridor`` or
    ``group`` it concerned, and the walkers it gave a new route (``walkers``)."""

    time: float
    action: str
    target: str
    walkers: int


class EventTimeline:
    """The scenario's events in time order, applied to a running simulation.

    Parameters
    ----------
    scenario : crowdwalk.scenario.Scenario
        Its ``events`` and ``groups`` (their exit choices).
    routes : crowdwalk.routes.RouteGraph
        The route graph with every corridor open.
    population : crowdwalk.population.Population
    """

    def __init__(self, scenario, routes, population) -> None:
        events = scenario.events
        order = sorted(range(len(events)), key=lambda i: events[i].time)
        self.events = [events[i] for i in order]
        self.groups = scenario.groups
        self.base = routes
        self.pop = population
        self.destinations = population.destinations.copy()  # (n,) tuples, as redirected
        self.walls: dict[frozenset, object] = {}  # closed corridors: their doors
        self.applied: list[AppliedEvent] = []
        self._next = 0

    def apply(self, sim, t: float) -> None:
        """Carry out the events due by time ``t`` [s] on ``sim``
        (:class:`~crowdwalk.crowd.simulation.CrowdSimulation`)."""
        while self._next < len(self.events) and self.events[self._next].time <= t + 1e-9:
            e = self.events[self._next]
            door = door_wall(self.base, e.corridor, e.door_at) if e.action == "close" \
                else None
            if door is not None and not _clear(sim, door, t):
                return  # a door shuts once nobody stands in it (tried again next tick)
            self._next += 1
            before = sim.state.route.copy()
            if e.action == "redirect":
                self._redirect(sim, e, t)
                target = e.group
            else:
                key = frozenset(e.corridor)
                if door is not None:
                    self.walls[key] = door
                else:
                    self.walls.pop(key, None)
                graph = self.base.with_closed(self.walls)
                sim.routes.use_graph(graph)
                sim.clearance = sim.footsteps.clearance = ClearanceField.from_area(
                    graph.walkable_area)
                self._reroute(sim, t, through=key if e.action == "close" else None)
                target = "-".join(e.corridor)
            changed = int(np.count_nonzero(sim.state.route != before))
            self.applied.append(AppliedEvent(float(t), e.action, target, changed))

    def _options(self, i: int, ahead: list[str]) -> list[tuple] | None:
        """The destination sequences walker ``i`` may take on (None: it keeps its
        destinations): one per exit of its group's exit choice, after the ordered
        destinations still ahead of it (``ahead``: its route's nodes from the one passed)."""
        g = self.groups[self.pop.group[i]]
        if g.exit_choice is None or self.destinations[i] != self.pop.destinations[i]:
            return None  # no choice, or redirected: it goes where it was sent
        rest = tuple(d for d in g.destinations if d in ahead[1:])
        return [(*rest, e) for e in g.exit_choice.among]

    def _reroute(self, sim, t: float, *, through) -> None:
        """Re-route the walkers (all, or those whose way ahead runs ``through`` a corridor)
        from where they stand, an exit-choosing walker to its cheapest exit now; give the
        unspawned ones the cheapest route from their origin."""
        st, routes = sim.state, sim.routes
        active = np.flatnonzero(st.status == ACTIVE)
        follow = []
        for i in active:  # event time only: the walkers' node lists
            nodes, at = routes.nodes_of(st.route[i])
            passed = max(int(np.searchsorted(at, st.progress[i], side="right")) - 1, 0)
            ahead = nodes[passed:]
            if through is not None and not any(frozenset(p) == through for p in zip(
                    ahead[:-1], ahead[1:], strict=True)):
                continue
            options = self._options(int(i), ahead)
            if options is None:
                follow.append(i)
            else:
                self._walk_on(sim, int(i), options, t, keep_same=True)
        if follow:
            now, _ = st.position(t, active)
            routes.reroute(st, np.asarray(follow), t=t, walkers=now)
        self._start_routes(sim, np.flatnonzero(st.status == WAITING))

    def _start_routes(self, sim, agents: np.ndarray) -> None:
        """The cheapest routes from their origins for unspawned ``agents`` (an exit-choosing
        walker's cheapest exit; those with no way keep their route)."""
        st, pop, routes = sim.state, self.pop, sim.routes
        made: dict[tuple, int] = {}
        for i in agents:  # event time only: a dict lookup per walker
            start = pop.route_start[i]
            origin = str(pop.origin[i])
            start = None if np.isnan(start).any() else tuple(start)
            options = self._options(int(i), [origin, *self.destinations[i]]) or \
                [tuple(self.destinations[i])]
            key = (origin, tuple(options), start)
            if key not in made:
                made[key] = self._cheapest_start(routes, origin, options, start)
            if made[key] >= 0:
                st.route[i] = made[key]
                st.segment[i] = routes.table.start[made[key]]
                st.progress[i] = routes.table.s0[made[key]]

    @staticmethod
    def _cheapest_start(routes, origin: str, options: list[tuple], start) -> int:
        """The route id of the cheapest destination sequence among ``options`` from
        ``origin`` (-1: none can be reached)."""
        graph, best = routes.graph, (np.inf, None)
        for dests in options:
            try:
                cost = _sequence_cost(graph, origin, dests)
            except InfeasibleError:
                continue
            best = min(best, (cost, dests), key=lambda c: c[0])
        return -1 if best[1] is None else routes.route_of(origin, best[1], start)

    def _redirect(self, sim, event, t: float) -> None:
        st = sim.state
        mine = self.pop.group == self.pop.group_names.index(event.group)
        dests = tuple(event.destinations)
        for i in np.flatnonzero(mine):
            self.destinations[i] = dests
        self._start_routes(sim, np.flatnonzero(mine & (st.status == WAITING)))
        for i in np.flatnonzero(mine & (st.status == ACTIVE)):  # event time only
            self._walk_on(sim, int(i), [dests], t, keep_same=False)

    def _walk_on(self, sim, i: int, options: list[tuple], t: float, *, keep_same: bool) -> None:
        """Walker ``i``'s cheapest way on to one of the destination sequences ``options``
        from where it stands: the shortest walk to the node it passed last, its route's
        next node or a node joined to the one passed, plus the route cost from there
        (``keep_same``: leave the route alone when that is the way it is on)."""
        st, routes = sim.state, sim.routes
        graph = routes.graph
        nodes, at = routes.nodes_of(st.route[i])
        if not nodes:
            return
        passed = min(max(int(np.searchsorted(at, st.progress[i], side="right")) - 1, 0),
                     len(nodes) - 1)
        near = dict.fromkeys([nodes[passed], *nodes[passed + 1:passed + 2],
                              *graph.graph.successors(nodes[passed])])
        walks = routes.walks_from(st.pos1[i], list(near))
        best, way = np.inf, None
        for dests in options:
            try:
                tail = _sequence_cost(graph, dests[0], dests)
            except InfeasibleError:
                continue
            first = graph.distances_to(dests[0])
            for v, walk in walks.items():
                cost = _length(walk) + first.get(v, np.inf) + tail
                if cost < best:
                    best, way = cost, (v, dests)
        if way is None:
            return
        v, dests = way
        seq, here = [v], v
        for d in dests:
            if d != here:
                seq += graph.route(here, d)[1:]
                here = d
        if keep_same and seq == nodes[passed + 1:]:
            return
        rid = routes.add(np.vstack([walks[v], graph.raw_path(seq)[1:]]), seq)
        st.route[i] = rid
        st.segment[i] = routes.table.start[rid]
        st.progress[i] = routes.table.s0[rid]
        st.best_progress[i] = -np.inf
        st.progress_time[i] = t

    def summary(self) -> list[dict]:
        """The events carried out, for ``summary.json`` (units in the key names)."""
        return [{"time_s": e.time, "action": e.action, "target": e.target,
                 "walkers_rerouted": e.walkers} for e in self.applied]


def _sequence_cost(graph, origin: str, dests: tuple) -> float:
    """Route cost [m] from ``origin`` through ``dests`` in order; raises
    :class:`~crowdwalk.errors.InfeasibleError` when a leg cannot be walked."""
    cost, here = 0.0, origin
    for d in dests:
        if d != here:
            cost += graph.route_cost(here, d)
            here = d
    return cost


def _clear(sim, door, t: float) -> bool:
    """True when no walking body (radius [m]) overlaps ``door`` now or at the end of
    its current step."""
    st = sim.state
    idx = np.flatnonzero(st.status == ACTIVE)
    if idx.size == 0:
        return True
    now, _ = st.position(t, idx)
    xy = np.concatenate([now, st.pos1[idx]])
    gap = shapely.distance(door, shapely.points(xy)) - np.tile(sim.radius[idx], 2)
    return bool(np.all(gap >= 0.0))
