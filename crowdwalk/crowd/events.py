"""Timed events (a scenario's ``events``): close or open a corridor, redirect a group.

Each event acts once, at the first tick at or after its time. It is event-driven:
nothing runs per tick in between.

- ``close`` shuts a door :data:`DOOR_THICKNESS` thick across the corridor's full width,
  at ``at`` (a fraction of its centre line from its first node; :func:`door_wall`). The
  door shuts at the first tick when no body stands in the doorway, now or at the end of
  its current step; later events wait for it. Then:

  - the door is cut out of the walkable area, and the corridor leaves the routing graph
    in both directions (:meth:`crowdwalk.routes.RouteGraph.with_closed`);
  - the clearance field that the steering and the footstep planner read is updated
    around the door (:func:`with_walls`), so
    the door blocks bodies and steps like any wall. JuPedSim changes the walls of a
    running simulation the same way (``Simulation.switch_geometry``: new walls, the
    agents stay where they are);
  - walkers whose way ahead runs through the corridor re-route from where they stand,
    by the forward re-routing (:meth:`~crowdwalk.crowd.routing.Routes.reroute`). A
    walker whose group has an ``exit_choice`` takes its nearest exit still reachable
    (walk plus route cost). With no way left, a walker keeps its route and waits at the
    door;
  - walkers not yet in the walk get the cheapest route from their origin.
- ``open`` removes the door and puts the corridor back in the graph. Every walker
  reconsiders its way on in the same way.
- ``redirect`` sends the group's walkers to new ``destinations``, in order. A walker on
  its way goes on from where it stands. It takes the shortest walk to whichever is
  cheapest, with the route cost from there: the node it passed last, its route's next
  node, or a node joined to the one passed. Walkers not yet in the walk start on the new
  route; walkers who have arrived are not called back. Vadere's ``TargetChanger``
  replaces a pedestrian's targets the same way, but when the pedestrian enters an area;
  here it happens at a time.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import shapely

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.routing import _length
from crowdwalk.crowd.state import ACTIVE, WAITING
from crowdwalk.errors import InfeasibleError, invalid

__all__ = ["DOOR_THICKNESS", "WALL_REACH", "door_wall", "with_walls", "EventTimeline",
           "AppliedEvent"]

#: Thickness of a closed door [m]: thick enough that no step (end and middle at least a
#: body radius from every wall, :mod:`crowdwalk.crowd.steering`) can straddle it.
DOOR_THICKNESS = 0.3
#: How far from a closed door the clearance field is recomputed [m] (beyond it the
#: clearance exceeds every body radius and foot clearance the steering tests).
WALL_REACH = 3.0


def door_wall(routes, corridor: tuple[str, str], at: float, *, owner: str = "Event"):
    """The closed door of ``corridor`` (its two node names) at fraction ``at`` of its
    centre line from ``corridor[0]``: a shapely polygon [m] across the corridor's whole
    width, :data:`DOOR_THICKNESS` thick, that leaves the other corridors and the node areas
    alone. Raises :class:`~crowdwalk.errors.InputError` where it cannot block the
    corridor there (it would cut another corridor or a node area)."""
    a, b = corridor
    g = routes.layout
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
    reach = shapely.Point(p).buffer(h + t)  # what the wall could touch
    others = [e["geometry"] for u, v, e in g.edges(data=True)
              if frozenset((u, v)) != frozenset(corridor)]
    widths = np.array([e["width"] for u, v, e in g.edges(data=True)
                       if frozenset((u, v)) != frozenset(corridor)])
    near = shapely.distance(np.array(others, dtype=object), reach) < widths / 2 \
        if others else np.zeros(0, bool)
    cut = [o.buffer(w / 2) for o, w, k in zip(others, widths, near, strict=True) if k]
    areas = [routes.node_area(v) for v in g.nodes]
    cut += [a for a in areas if a.distance(reach) <= 0.0]
    wall = wall.intersection(line.buffer(width / 2 + 1e-3, cap_style="flat"))
    wall = wall.difference(shapely.union_all(cut)) if cut else wall
    cross = shapely.LineString([p - (width / 2 - 1e-3) * across,
                                p + (width / 2 - 1e-3) * across])
    if not wall.buffer(1e-9).covers(cross):
        raise invalid(owner, "at", "where the door blocks the corridor alone (not inside "
                      "another corridor or a node area)", round(float(at), 3))
    return wall


def with_walls(field: ClearanceField, walls: list) -> ClearanceField:
    """``field`` (the clearance of a walkable area) with ``walls`` (shapely polygons [m]
    inside it) cut out: within :data:`WALL_REACH` of each wall the clearance is the
    smaller of the area's and the distance to the wall (negative inside it), which is
    the distance to the boundary of the area without the walls. Farther away the field
    is unchanged. Rasterising the whole area again would take about 12 s for the
    stadium's 1.5 million grid nodes."""
    dist = field.distance.copy()
    ny, nx = dist.shape
    for wall in walls:
        x0, y0, x1, y1 = wall.bounds
        i0, j0 = np.floor((np.array([x0, y0]) - WALL_REACH - field.origin) / field.cell)
        i1, j1 = np.ceil((np.array([x1, y1]) + WALL_REACH - field.origin) / field.cell)
        i0, i1 = int(np.clip(i0, 0, nx)), int(np.clip(i1 + 1, 0, nx))
        j0, j1 = int(np.clip(j0, 0, ny)), int(np.clip(j1 + 1, 0, ny))
        xx, yy = np.meshgrid(field.origin[0] + field.cell * np.arange(i0, i1),
                             field.origin[1] + field.cell * np.arange(j0, j1))
        pts = shapely.points(xx, yy)
        inside = shapely.contains_xy(wall, xx, yy)
        to_wall = np.where(inside, -shapely.distance(wall.boundary, pts),
                           shapely.distance(wall, pts))
        sub = dist[j0:j1, i0:i1]
        dist[j0:j1, i0:i1] = np.where(sub > 0, np.minimum(sub, to_wall), sub)
    return ClearanceField(origin=field.origin, cell=field.cell, distance=dist)


@dataclass(frozen=True)
class AppliedEvent:
    """An event carried out: ``time`` [s] it acted, ``action``, the ``corridor`` or
    ``group`` it concerned, the walkers it gave a new route (``walkers``) and the wall
    time it took (``wall`` [s])."""

    time: float
    action: str
    target: str
    walkers: int
    wall: float


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
        self._open_field = None  # the clearance field with every corridor open
        self._graphs: dict[frozenset, object] = {}  # route graph per set of closed corridors
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
            w0 = time.perf_counter()
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
                shut = frozenset(self.walls)
                if shut not in self._graphs:  # walkable area, walks: computed once each
                    self._graphs[shut] = self.base.with_closed(self.walls)
                old, graph = sim.routes.graph, self._graphs[shut]
                sim.routes.use_graph(graph)
                if self._open_field is None:
                    self._open_field = sim.clearance
                sim.clearance = sim.footsteps.clearance = with_walls(
                    self._open_field, list(self.walls.values()))
                self._reroute(sim, t, through=key if e.action == "close" else None,
                              before=old)
                target = "-".join(e.corridor)
            changed = int(np.count_nonzero(sim.state.route != before))
            self.applied.append(AppliedEvent(float(t), e.action, target, changed,
                                             time.perf_counter() - w0))

    def _options(self, i: int, stops: list[str]) -> list[tuple] | None:
        """The destination sequences walker ``i`` may take on (None: it keeps its
        destinations): one per exit of its group's exit choice, after the ordered
        destinations still ahead of it (``stops``: its route's stops still to visit, the
        last its exit)."""
        g = self.groups[self.pop.group[i]]
        if g.exit_choice is None or self.destinations[i] != self.pop.destinations[i]:
            return None  # no choice, or redirected: it goes where it was sent
        rest = tuple(stops[:-1])
        return [(*rest, e) for e in g.exit_choice.among]

    def _reroute(self, sim, t: float, *, through, before) -> None:
        """Re-route walkers from where they stand, an exit-choosing walker to its cheapest
        exit now: after a close those whose way ahead runs ``through`` the corridor, after
        an open those whose way on from the node they passed last is cheaper on the new
        graph than on the graph ``before``. Unspawned walkers get the cheapest route from
        their origin."""
        st, routes = sim.state, sim.routes
        active = np.flatnonzero(st.status == ACTIVE)
        follow = []
        for i in active:  # event time only: the walkers' node lists
            nodes, at = routes.nodes_of(st.route[i])
            if not nodes:
                continue
            passed = routes.passed(st.route[i], st.progress[i])
            ahead = nodes[max(passed, 0):]
            stops = routes.stops_ahead(st.route[i], passed) or [nodes[-1]]
            options = self._options(int(i), stops)
            if through is not None:
                if not any(frozenset(p) == through for p in zip(ahead[:-1], ahead[1:],
                                                                   strict=True)):
                    continue
            elif _best_cost(routes.graph, ahead[0], options or [tuple(stops)]) >= \
                    _best_cost(before, ahead[0], options or [tuple(stops)]) - 1e-6:
                continue  # the opened corridor shortens nothing for this walker
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
            options = self._options(int(i), list(self.destinations[i])) or \
                [tuple(self.destinations[i])]
            key = (origin, tuple(options), start)
            if key not in made:
                made[key] = self._cheapest_start(routes, origin, options, start)
            if made[key] >= 0:
                routes.assign(st, i, made[key])

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
        here = st.pos1[i]
        bounds = []  # (a lower bound of the cost: the straight line, entry node, destinations)
        for dests in options:
            try:
                tail = _sequence_cost(graph, dests[0], dests)
            except InfeasibleError:
                continue
            first = graph.distances_to(dests[0])
            bounds += [(float(np.linalg.norm(graph.node_xy(v) - here)) + first[v] + tail,
                        first[v] + tail, v, dests) for v in near if v in first]
        best, way, walks = np.inf, None, {}
        for bound, rest, v, dests in sorted(bounds, key=lambda b: b[0]):
            if bound >= best:
                break  # no walk is shorter than the straight line
            if v not in walks:
                walks[v] = routes.walks_from(here, [v]).get(v)
            if walks[v] is not None and _length(walks[v]) + rest < best:
                best, way = _length(walks[v]) + rest, (v, dests)
        if way is None:
            return
        v, dests = way
        seq, here, stops = [v], v, []
        for d in dests:
            if d != here:
                seq += graph.route(here, d)[1:]
                here = d
            stops.append(len(seq) - 1)  # every destination stays a stop of the new route
        if keep_same and seq == nodes[passed + 1:]:
            return
        routes.assign(st, i, routes.add(np.vstack([walks[v], graph.raw_path(seq)[1:]]), seq,
                                        stops))
        st.progress_time[i] = t

    def summary(self) -> list[dict]:
        """The events carried out, for ``summary.json`` (units in the key names)."""
        return [{"time_s": e.time, "action": e.action, "target": e.target,
                 "walkers_rerouted": e.walkers, "wall_s": e.wall} for e in self.applied]


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
    """True when no walking body (its holding disc) overlaps ``door`` now or at the end of
    its current step."""
    st = sim.state
    idx = np.flatnonzero(st.status == ACTIVE)
    if idx.size == 0:
        return True
    now, _ = st.position(t, idx)
    xy = np.concatenate([now, st.pos1[idx]])
    gap = shapely.distance(door, shapely.points(xy)) - np.tile(sim.shape.bound[idx], 2)
    return bool(np.all(gap >= 0.0))


def _best_cost(graph, node: str, options: list[tuple]) -> float:
    """The least route cost [m] from ``node`` through one of the destination sequences
    ``options`` (inf: none can be reached)."""
    best = np.inf
    for dests in options:
        try:
            best = min(best, _sequence_cost(graph, node, dests))
        except InfeasibleError:
            pass
    return best
