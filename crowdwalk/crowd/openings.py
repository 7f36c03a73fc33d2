"""Openings: where the walkable area is a narrow corridor (a door, a short narrow
passage) and the zone just around its ends, for the ``opening_ease`` steering term
(:class:`~crowdwalk.crowd.params.CrowdParams`).

Inside a 0.8 m opening the soft wall term (``SteeringParams.wall_weight`` w
exp(−(clearance − r)/range)) costs 0.25 m of route progress at ±0.2 m off the axis
against 0.03 m on it, so every walker keeps to the axis and they pass one at a time;
people pass such openings in two staggered lanes, a zipper (Hoogendoorn & Daamen 2005,
Seyfried et al. 2009). Inside the zones the soft wall term is scaled down; the hard wall
limit (no body closer to a wall than its radius) is not touched.
"""

from __future__ import annotations

import numpy as np
import shapely

__all__ = ["ZONE_MARGIN", "Openings"]

#: how far into the rooms the door rules' zones (zipper, wake, mouth priority) reach from an
#: opening's ends [m]
ZONE_MARGIN = 1.0


class Openings:
    """The opening zones of a route graph: every corridor at most ``max_width`` [m] wide
    (centre line buffered by half its width, flat ends), minus the areas of the nodes
    that have one (rooms), grown by ``margin`` [m] (so the zone reaches a step or so into
    the rooms at its ends) and cut to the walkable area.

    Parameters
    ----------
    graph : crowdwalk.routes.RouteGraph
    max_width, margin : float
        [m].
    """

    def __init__(self, graph, max_width: float, margin: float) -> None:
        narrow = [d["geometry"].buffer(d["width"] / 2, cap_style="flat")
                  for *_, d in graph.layout.edges(data=True) if d["width"] <= max_width]
        rooms = [p.area for p in graph.places.values() if p.area is not None]
        zone = shapely.union_all(narrow) if narrow else shapely.Polygon()
        if rooms and not zone.is_empty:
            zone = zone.difference(shapely.union_all(rooms))
        if not zone.is_empty:
            zone = zone.buffer(margin).intersection(graph.walkable_area)
        self.zone = zone
        shapely.prepare(self.zone)

    @property
    def empty(self) -> bool:
        """True when the graph has no opening."""
        return self.zone.is_empty

    def inside(self, xy: np.ndarray) -> np.ndarray:
        """Whether points (k, 2) [m] lie in an opening zone (k,) bool."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if self.empty or not len(xy):
            return np.zeros(len(xy), bool)
        return shapely.contains_xy(self.zone, xy[:, 0], xy[:, 1])
