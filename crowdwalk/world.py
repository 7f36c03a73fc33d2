"""The world a scenario describes: its terrain and its route graph."""

from __future__ import annotations

from dataclasses import dataclass

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
    (a corridor leaving the terrain or climbing a wall, a spawn polygon off the ground).
    """
    terrain = scenario.terrain.build()
    routes = scenario.routes.build(terrain)
    from crowdwalk.errors import invalid

    for i, g in enumerate(scenario.groups):
        if not isinstance(g.spawn, str):
            from shapely.geometry import Polygon

            poly = Polygon(g.spawn)
            if not poly.is_valid or poly.area <= 0:
                raise invalid(f"Scenario.groups[{i}]", "spawn",
                              "a valid polygon with positive area [m²]", g.spawn)
            if not terrain.area.covers(poly):
                raise invalid(f"Scenario.groups[{i}]", "spawn",
                              f"inside the terrain extent {terrain.bounds} [m]", g.spawn)
    return World(scenario, terrain, routes)
