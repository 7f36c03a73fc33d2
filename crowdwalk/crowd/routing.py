"""The agents' routes: their polylines (:class:`Routes`, built once at set-up), progress
along them and the steering target ahead, and re-routing around congestion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd.navigation import RouteTable
from crowdwalk.crowd.routing_kernels import steering_rows

__all__ = ["Routes", "RouteProgress", "route_progress", "steering_targets"]


def _length(line: np.ndarray) -> float:
    """Length [m] of a polyline (k, 2) [m]."""
    return float(np.sum(np.linalg.norm(np.diff(line, axis=0), axis=1)))


class Routes:
    """Route polylines of a population on a route graph.

    One polyline per distinct (origin, destinations, start): the smoothed graph paths to
    each destination in turn, concatenated, in one :class:`RouteTable`; with the route
    nodes' arc lengths along each (for re-routing from the last node passed) and which
    of them are stops (the destinations, in order, that the route has to visit: a new
    route made from where a walker stands visits those still ahead).

    Parameters
    ----------
    graph : crowdwalk.routes.RouteGraph
    population : crowdwalk.population.Population

    Attributes
    ----------
    table : RouteTable
    of_agent : (n,) int
        Each agent's route at the start.
    """

    def __init__(self, graph, population) -> None:
        self.graph = graph
        self.table = RouteTable()
        self._nodes: dict[int, tuple[list[str], np.ndarray]] = {}
        self._stops: dict[int, np.ndarray] = {}  # per route: its stops' indices in its nodes
        self._edges: dict | None = None
        keys: dict[tuple, int] = {}
        n = len(population)
        route = np.zeros(n, dtype=np.int64)
        starts = population.route_start
        for i in range(n):  # setup only: a dict lookup per agent
            start = starts[i]
            key = (str(population.origin[i]), tuple(population.destinations[i]),
                   None if np.isnan(start).any() else tuple(start))
            if key not in keys:
                keys[key] = self.route_of(*key)
            route[i] = keys[key]
        self.of_agent = route

    def use_graph(self, graph) -> None:
        """Route on ``graph`` from now on (a :class:`~crowdwalk.routes.RouteGraph` of the
        same places, e.g. with corridors closed); routes already in the table stay."""
        self.graph = graph
        self._edges = None

    def nodes_of(self, rid: int) -> tuple[list[str], np.ndarray]:
        """Route ``rid``'s node names and their global arc lengths along it (k,) [m]."""
        return self._nodes.get(int(rid), ([], np.zeros(0)))

    def stops_of(self, rid: int) -> np.ndarray:
        """Route ``rid``'s stops: indices (m,) int into its nodes, increasing; the last is
        its last node."""
        nodes, _ = self.nodes_of(rid)
        return self._stops.get(int(rid), np.array([len(nodes) - 1], dtype=np.int64))

    def stops_ahead(self, rid: int, passed: int) -> list[str]:
        """The stops of route ``rid`` still to visit by a walker whose last node passed is
        index ``passed`` of its nodes (-1: none yet), in order."""
        nodes, _ = self.nodes_of(rid)
        return [nodes[k] for k in self.stops_of(rid) if k > passed]

    def passed(self, rid: int, progress: float) -> int:
        """Index into route ``rid``'s nodes of the last node passed at ``progress`` [m]
        (global arc length). The route's first node counts as passed unless it is a stop
        not yet reached (-1; a route made on the way may start at a stop)."""
        nodes, at = self.nodes_of(rid)
        k = int(np.searchsorted(at, progress, side="right")) - 1
        return k if k >= 0 or self.stops_of(rid)[0] == 0 else 0

    def add(self, line: np.ndarray, nodes: list[str], stops=None) -> int:
        """Add a route polyline (k, 2) [m] through route ``nodes`` (in order) that visits
        the stops ``stops`` (indices into ``nodes``; None: its last node only); its id."""
        rid = self.table.add(line)
        self._remember_nodes(rid, nodes)
        stops = [len(nodes) - 1] if stops is None or not len(stops) else stops
        self._stops[rid] = np.unique(np.asarray(stops, dtype=np.int64))
        return rid

    def assign(self, state, i: int, rid: int) -> None:
        """Walker ``i`` (``state``: :class:`~crowdwalk.crowd.state.AgentState`) follows
        route ``rid`` from its start."""
        state.route[i] = rid
        state.segment[i] = self.table.start[rid]
        state.progress[i] = self.table.s0[rid]
        state.best_progress[i] = -np.inf

    def route_of(self, origin: str, destinations: tuple, start) -> int:
        """The route (its id) from ``origin`` (or ``start`` (2,) [m] in its area, None: the
        node) through ``destinations`` in order."""
        here, parts, nodes, stops = origin, [], [origin], []
        for k, dest in enumerate(destinations):
            if dest == here:
                continue
            kw = {"start": np.asarray(start)} if (k == 0 and start is not None) else {}
            line = self.graph.path(here, dest, **kw)
            parts.append(line if not parts else line[1:])
            nodes += self.graph.route(here, dest)[1:]
            stops.append(len(nodes) - 1)
            here = dest
        if not parts:  # already at the destination
            p = self.graph.node_xy(origin) if start is None else np.asarray(start)
            parts = [np.stack([p, p])]
        return self.add(np.concatenate(parts), nodes, stops)

    def _remember_nodes(self, rid: int, nodes: list[str]) -> None:
        """Store a route's node names and their global arc lengths along it [m]."""
        vs = self.table.xy[self.table.start[rid]:self.table.stop[rid] + 1]
        ss = self.table.s[self.table.start[rid]:self.table.stop[rid] + 1]
        at, k0 = [], 0
        for v in nodes:  # nodes in route order; search forward only
            d = np.linalg.norm(vs[k0:] - self.graph.node_xy(v), axis=1)
            k0 += int(np.argmin(d))
            at.append(ss[k0])
        self._nodes[rid] = (nodes, np.asarray(at))

    def _edge_samples(self) -> dict:
        """Points about 1 m apart along every corridor of the route graph (k, 2) [m] and
        its width [m], by edge (computed once per graph)."""
        if self._edges is None:
            self._edges = {}
            for u, v, data in self.graph.graph.edges(data=True):
                line = data["geometry"]
                k = max(2, int(np.ceil(line.length)) + 1)
                pts = np.array([line.interpolate(f, normalized=True).coords[0]
                                for f in np.linspace(0, 1, k)])
                self._edges[(u, v)] = (pts, data["width"])
        return self._edges

    def walks_from(self, here: np.ndarray, nodes) -> dict[str, np.ndarray]:
        """The shortest walks (k, 2) [m] from ``here`` to each of ``nodes`` that can be
        walked (a wall, such as a closed door, may leave none)."""
        out = {}
        for v in nodes:
            walk = self.graph.shortest_walk(here, self.graph.node_xy(v))
            if len(walk) > 2 or self.graph.sees(walk[0], walk[-1]):
                out[v] = walk
        return out

    def sees_route(self, state, i: int) -> bool:
        """Whether walker ``i`` sees its route line: the straight way from where it stands
        to its projection on the route or to the route's next vertex lies inside the
        walkable area."""
        st, tb = state, self.table
        rid, here = int(st.route[i]), st.pos1[i]
        on = tb.point_at(np.array([rid]), np.array([st.progress[i]]))[0]
        nxt = tb.xy[min(int(st.segment[i]) + 1, int(tb.stop[rid]))]
        return self.graph.sees(here, on) or self.graph.sees(here, nxt)

    def farthest_visible(self, state, agents: np.ndarray, reach: float) -> np.ndarray:
        """For walkers ``agents`` (k,): the farthest point (k, 2) [m] of their route
        within ``reach`` [m] ahead of their progress (0.5 m apart) that they see from where
        they stand (NaN where none is seen)."""
        st, tb = state, self.table
        agents = np.asarray(agents, dtype=np.intp)
        ahead = np.arange(reach, -1e-9, -0.5)  # farthest first
        rid = np.repeat(st.route[agents].astype(np.intp), ahead.size)
        pts = tb.point_at(rid, np.add.outer(st.progress[agents], ahead).ravel())
        seen = self.graph.sees_all(np.repeat(st.pos1[agents], ahead.size, axis=0), pts)
        seen = seen.reshape(agents.size, ahead.size)
        first = np.argmax(seen, axis=1)
        out = pts.reshape(agents.size, ahead.size, 2)[np.arange(agents.size), first]
        out[~seen.any(axis=1)] = np.nan
        return out

    def reroute(self, state, blocked: np.ndarray, *, t: float, walkers: np.ndarray) -> None:
        """Agents ``blocked`` without progress for ``reroute_after`` seconds look for a
        cheaper way on **from where they stand**: to the next node of their route or one
        of the other nodes joined to the node they passed last (not to nodes behind them),
        each by the shortest walk inside the walkable area
        (:meth:`crowdwalk.routes.RouteGraph.shortest_walk`) plus the queue on the
        corridor from the node passed to it, then along the route graph through **every
        stop still ahead, in order** (:meth:`stops_ahead`: an intermediate destination is
        never skipped, however much shorter the way to the last one), every corridor's
        cost raised by the time its current occupants (``walkers`` (w, 2) [m]) need to get
        through it (queue length over a specific flow of 1.3 persons/(s·m), Weidmann 1993;
        converted to metres at 1.34 m/s). The way from the next stop on is the same for
        every choice, so the choice is by the cost to the next stop. Back to the node
        passed last only when there is no other way. The agent switches (``state``'s route
        fields) only when that differs from its way on, or when it no longer sees its
        route line (:meth:`sees_route`; rare: a Python loop over the blocked agents
        only)."""
        import networkx as nx

        st = state
        g = self.graph.graph
        tree = cKDTree(walkers)
        extra = {}
        for (u, v), (pts, width) in self._edge_samples().items():
            near = tree.query_ball_point(pts, r=max(0.5 * width, 0.5))
            count = len(set().union(*near)) if len(near) else 0
            extra[(u, v)] = count / (1.3 * width) * 1.34

        def against(b, a, data):  # the reversed graph's edge b <- a is a -> b
            return data.get("cost", data.get("length", 1.0)) + extra.get((a, b), 0.0)

        fields: dict[str, tuple[dict, dict]] = {}  # per stop: cost and path to it

        def field(stop: str) -> tuple[dict, dict]:
            if stop not in fields:
                fields[stop] = nx.single_source_dijkstra(g.reverse(copy=False), stop,
                                                         weight=against)
            return fields[stop]

        for i in blocked:
            st.progress_time[i] = t  # look again only after another ``reroute_after``
            rid = int(st.route[i])
            nodes, at = self._nodes.get(rid, ([], np.zeros(0)))
            if len(nodes) < 2:
                continue
            passed = min(self.passed(rid, st.progress[i]), len(nodes) - 2)
            stops = self.stops_ahead(rid, passed)
            if not stops:
                continue
            base, ahead = nodes[max(passed, 0)], nodes[passed + 1:]
            cost, paths = field(stops[0])
            here = st.pos1[i]
            behind = set(nodes[:passed + 1])
            near = [v for v in dict.fromkeys([ahead[0], *g.successors(base)])
                    if v not in behind and v in cost]
            walks = self.walks_from(here, near)
            if not walks and passed >= 0 and base in cost:  # no way on but back
                walks = self.walks_from(here, [base])
            if not walks:
                continue
            # the walk to v runs along the corridor from the node passed: its queue counts
            best = min(walks, key=lambda v: _length(walks[v])
                       + extra.get((base, v), 0.0) + cost[v])
            alt, at_stop = list(reversed(paths[best])), [None]
            at_stop[0] = len(alt) - 1
            ok = True
            for prev, stop in zip(stops[:-1], stops[1:], strict=True):
                c, p = field(stop)
                if prev not in c:
                    ok = False
                    break
                alt += list(reversed(p[prev]))[1:]
                at_stop.append(len(alt) - 1)
            # the same nodes on are the same way only while the corridor from the node
            # passed to the next is open (a door shut in it leaves the old line blocked)
            # and the walker sees its route line (pushed through a side door into a room,
            # its line runs behind the room's wall: a new line from where it stands)
            if not ok or (alt == ahead and (passed < 0 or g.has_edge(base, ahead[0]))
                          and self.sees_route(st, i)):
                continue
            self.assign(st, i, self.add(np.vstack([walks[best],
                                                   self.graph.raw_path(alt)[1:]]), alt,
                                        at_stop))
            st.reroutes[i] += 1


@dataclass(frozen=True, eq=False)
class RouteProgress:
    """Where k deciding agents are along their routes: ``segment`` (k,) int, ``progress``
    (k,) [m] global arc length, ``gained`` (k,) bool (a new best by ``progress_step``),
    ``arrived`` (k,) bool."""

    segment: np.ndarray
    progress: np.ndarray
    gained: np.ndarray
    arrived: np.ndarray


def route_progress(table: RouteTable, *, route: np.ndarray, segment: np.ndarray,
                   best: np.ndarray, xy: np.ndarray, params) -> RouteProgress:
    """Project agents at ``xy`` (k, 2) [m] onto their ``route`` (k,) from their current
    ``segment`` (k,); progress beyond their ``best`` (k,) [m] by ``progress_step``
    counts as getting on; within ``arrive_distance`` of the route's end (along it or
    straight) they have arrived."""
    seg, s, _ = table.project(route, segment, xy)
    gained = s >= best + params.progress_step
    end = table.xy[table.stop[route]]
    arrived = ((table.s1[route] - s <= params.arrive_distance)
               | (np.linalg.norm(end - xy, axis=1) <= params.arrive_distance))
    return RouteProgress(seg, s, gained, arrived)


def _rows(table: RouteTable, route, progress, xy, heading, radius, clearance, params,
          lane_only: bool):
    """:func:`~crowdwalk.crowd.routing_kernels.steering_rows` of k walkers: target (k, 2)
    [m], direction (k, 2) and whether the lane runs into a wall (k,) bool."""
    f = np.ascontiguousarray
    k = len(route)
    target, direction = np.empty((k, 2)), np.empty((k, 2))
    blind = np.empty(k, bool)
    h = np.asarray(heading, float)
    steering_rows(table.s, f(table.xy), table.start, table.stop, table.s0, table.s1,
                  clearance.distance, float(clearance.origin[0]), float(clearance.origin[1]),
                  float(clearance.cell), f(route, np.int64), f(progress, float), f(xy, float),
                  f(np.cos(h)), f(np.sin(h)), f(radius, float), float(params.target_distance),
                  float(params.centre_pull), bool(params.lane_keep), bool(params.line_up),
                  lane_only, target, direction, blind)
    return target, direction, blind


def lane_runs_into_wall(table: RouteTable, *, route: np.ndarray, progress: np.ndarray,
                        xy: np.ndarray, radius: np.ndarray, clearance, params) -> np.ndarray:
    """(k,) bool: the walkers at ``xy`` whose lane (parallel to the route,
    ``target_distance`` ahead, as :func:`steering_targets` lays it) runs into a wall at its
    end or halfway, closer than the walker's ``radius`` [m] (a door or bend ahead off the
    walker's axis)."""
    return _rows(table, route, progress, xy, np.zeros(len(route)), radius, clearance, params,
                 True)[2]


def steering_targets(table: RouteTable, *, route: np.ndarray, progress: np.ndarray,
                     xy: np.ndarray, heading: np.ndarray, radius: np.ndarray, clearance,
                     params) -> tuple[np.ndarray, np.ndarray]:
    """Steering targets (k, 2) [m] and unit route directions (k, 2) of agents at ``xy``.

    Agents walk parallel to the route (a lane), pulled gently towards its centre line
    (``centre_pull`` over ``target_distance``): steering at the centre-line point ahead
    would funnel everybody into one file — unless that lane runs into a wall (the
    ``clearance`` at the target or halfway is below the agent's ``radius``): then they
    head for the centre line. An agent at its target keeps its ``heading`` [rad].

    ``lane_keep``: where the lane runs into a wall, the lane ahead as far off the centre
    line as fits (0.6, 0.45, 0.3, 0.2, 0.1 m; its target and halfway clear by the radius):
    a walker approaching a door off its axis keeps to its side (two interleaved files,
    the zipper of Hoogendoorn & Daamen 2005 and Seyfried et al. 2009) instead of all
    funnelling into one. ``line_up`` (where no lane fits): lining up with the door, the
    centre-line point farthest ahead (1.5, 1.0, 0.6, 0.3 m, down to the walker's own
    projection, straight across) whose line from the walker clears the walls at its
    quarters too — not a point under the walker's own body (its projection when the
    centre line runs beneath it beside a wall: no direction, and it stands for good) —
    instead of the point ``target_distance`` ahead, whose line grazes the jamb, so that a
    walker beside an opening moves across to it rather than along the wall into the door
    post's corner. One compiled loop over the rows
    (:mod:`crowdwalk.crowd.routing_kernels`).
    """
    target, direction, _ = _rows(table, route, progress, xy, heading, radius, clearance,
                                 params, False)
    return target, direction
