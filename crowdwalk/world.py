"""The world a scenario describes: its terrain and its route graph."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from shapely.geometry import Polygon

from crowdwalk.errors import InputError, invalid
from crowdwalk.routes import RouteGraph
from crowdwalk.scenario import Scenario
from crowdwalk.terrain import Terrain

__all__ = ["World", "build_world"]


@dataclass(frozen=True, eq=False)
class World:
    """A built scenario: ``terrain`` (:class:`~crowdwalk.terrain.Terrain`) and ``routes``
    (:class:`~crowdwalk.routes.RouteGraph`, costs sampled on that terrain)."""

    scenario: Scenario
    terrain: Terrain
    routes: RouteGraph


def build_world(scenario: Scenario) -> World:
    """Build the terrain and the route graph of a validated ``scenario``.

    Raises :class:`~crowdwalk.errors.InputError` for geometry that does not fit together
    (a corridor leaving the terrain or climbing a wall, a spawn polygon off the walkable
    area, more agents or grid nodes than memory holds), located as ``file:line: ...``.
    """
    from crowdwalk.checks import check_resources, located

    try:
        check_resources(scenario)
        return _build_world(scenario)
    except InputError as exc:
        raise located(scenario, exc) from None


def _build_world(scenario: Scenario) -> World:
    terrain = scenario.terrain.build()
    routes = scenario.routes.build(terrain, [o.geometry() for o in scenario.obstacles])
    for i, g in enumerate(scenario.groups):
        if not isinstance(g.spawn, str):
            poly = Polygon(g.spawn)
            if not poly.is_valid or poly.area <= 0:
                raise invalid(f"Scenario.groups[{i}]", "spawn",
                              "a valid polygon with positive area [m²]", g.spawn)
            if not terrain.area.covers(poly):
                raise invalid(f"Scenario.groups[{i}]", "spawn",
                              f"inside the terrain extent {terrain.bounds} [m]", g.spawn)
            if not routes._walkable_tolerant.covers(poly):
                raise invalid(f"Scenario.groups[{i}]", "spawn",
                              "inside the walkable area (a node's area or a corridor) [m]",
                              g.spawn)
    _check_reachable(scenario, routes)
    _check_behaviours(scenario, routes)
    return World(scenario, terrain, routes)


def _check_reachable(scenario: Scenario, routes: RouteGraph) -> None:
    """Every group can walk from its spawn through its destinations, in order."""
    names = list(routes.graph.nodes)
    xy = np.array([routes.node_xy(n) for n in names]).reshape(-1, 2)
    for i, g in enumerate(scenario.groups):
        if isinstance(g.spawn, str):
            here = g.spawn
        else:  # a spawn polygon joins the graph at the node nearest to it
            centre = np.asarray(Polygon(g.spawn).representative_point().coords[0])
            here = names[int(np.argmin(np.linalg.norm(xy - centre, axis=1)))]
        for j, dest in enumerate(g.destinations):
            if dest != here and here not in routes.distances_to(dest):
                raise invalid(f"Scenario.groups[{i}]", f"destinations[{j}]",
                              f"reachable from {here!r} (check one-way corridors and "
                              "disconnected parts)", dest)
            here = dest


def _check_behaviours(scenario: Scenario, routes: RouteGraph) -> None:
    """Events name existing corridors, in an order that can happen (open what is closed,
    close what is open), and every door closes its corridor alone."""
    from crowdwalk.crowd.events import door_wall

    closed: set[frozenset] = set()
    order = sorted(range(len(scenario.events)), key=lambda i: scenario.events[i].time)
    for i in order:
        e = scenario.events[i]
        if e.corridor is None:
            continue
        owner = f"Scenario.events[{i}]"
        if not routes.graph.has_edge(*e.corridor) and not routes.graph.has_edge(
                *e.corridor[::-1]):
            raise invalid(owner, "corridor", "two nodes joined by a corridor", list(e.corridor))
        key = frozenset(e.corridor)
        if (e.action == "close") == (key in closed):
            state = "open" if e.action == "close" else "closed"
            raise invalid(owner, "action", f"for a corridor that is {state} at {e.time:g} s "
                          "(close an open corridor, open a closed one)", e.action)
        if e.action == "close":
            door_wall(routes, e.corridor, e.door_at, owner=owner)
            closed.add(key)
        else:
            closed.discard(key)
