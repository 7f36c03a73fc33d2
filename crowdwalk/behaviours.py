"""Scenario sections for the behaviours other pedestrian simulators offer.

- ``obstacles``: walls and obstacles as polygons or WKT, cut out of the walkable area as
  holes (a WKT line is a wall of ``thickness`` [m]);
- ``groups[].exit_choice``: after its ordered ``destinations`` an agent picks one exit
  among several — the ``nearest`` by route cost, the ``least_congested`` (route time
  plus the queue of the walkers who chose it before, over the exit's capacity), or at
  random by ``weights``;
- ``events``: at a time [s], ``close`` or ``open`` a corridor, or ``redirect`` a group
  to new destinations;
- ``waiting_areas``: a node where walkers whose route passes it stand until a release
  time [s], or are let go one by one at a rate [1/s] (a queue);
- ``groups[].density``: start positions on a hexagonal lattice at that density [1/m²];
- ``groups[].spawn_times.process``: ``regular`` arrivals (one every 1/rate s) or
  ``poisson`` arrivals (exponential gaps of mean 1/rate s);
- ``measurement``: lines and areas that :mod:`crowdwalk.analysis` evaluates with PedPy.

All of them are frozen pydantic models validated with the rest of the scenario file
(:mod:`crowdwalk.scenario`); :func:`cross_errors` checks the node names they use.
"""

from __future__ import annotations

from typing import Annotated, Literal

import shapely
from pydantic import BaseModel, ConfigDict, Field, model_validator

__all__ = [
    "ObstacleSpec",
    "ExitChoice",
    "EventSpec",
    "WaitingAreaSpec",
    "MeasurementLine",
    "MeasurementArea",
    "MeasurementSpec",
    "cross_errors",
]

Vec2 = tuple[float, float]
Polygon2 = Annotated[list[Vec2], Field(min_length=3, description="polygon vertices [m]")]
Positive = Annotated[float, Field(gt=0)]
NonNeg = Annotated[float, Field(ge=0)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)


class ObstacleSpec(_Model):
    """A wall or obstacle: a ``polygon`` [m], or ``wkt`` (Polygon, MultiPolygon, or a
    (Multi)LineString drawn as a wall ``thickness`` [m] thick). It is a hole in the
    walkable area."""

    name: str = ""
    polygon: Polygon2 | None = None
    wkt: str | None = None
    thickness: Positive = Field(0.2, description="wall thickness of a WKT line [m]")

    @model_validator(mode="after")
    def _one_shape(self):
        if (self.polygon is None) == (self.wkt is None):
            raise ValueError("give either polygon or wkt")
        geom = self.geometry()
        if geom.is_empty or not geom.is_valid or geom.area <= 0:
            raise ValueError("must be a valid shape with positive area")
        return self

    def geometry(self):
        """The obstacle as a shapely (Multi)Polygon [m]."""
        if self.polygon is not None:
            return shapely.Polygon(self.polygon)
        try:
            geom = shapely.from_wkt(self.wkt)
        except shapely.errors.GEOSException as exc:
            raise ValueError(f"wkt is not valid WKT ({exc})") from None
        if geom.geom_type in ("LineString", "MultiLineString"):
            return geom.buffer(self.thickness / 2, cap_style="flat", join_style="mitre")
        if geom.geom_type not in ("Polygon", "MultiPolygon"):
            raise ValueError(f"wkt must be a polygon or a line; got a {geom.geom_type}")
        return geom


class ExitChoice(_Model):
    """One exit among ``among`` (route nodes), chosen when the agent enters."""

    among: list[str] = Field(min_length=2, description="candidate exits (route nodes)")
    rule: Literal["nearest", "least_congested", "weights"] = "nearest"
    weights: list[NonNeg] | None = Field(None, description="one per exit, for rule weights")

    @model_validator(mode="after")
    def _weights(self):
        if self.rule == "weights":
            if self.weights is None or len(self.weights) != len(self.among):
                raise ValueError("rule weights needs one weight per exit in among")
            if sum(self.weights) <= 0:
                raise ValueError("weights must not all be 0")
        elif self.weights is not None:
            raise ValueError("weights are only used with rule: weights")
        return self


class EventSpec(_Model):
    """At ``time`` [s]: ``close`` the corridor between the two nodes of ``corridor`` (a
    door shut across it at fraction ``at`` of its length from the first node), ``open``
    it again, or ``redirect`` the walkers of ``group`` to ``destinations`` (in order)."""

    time: NonNeg = Field(description="[s]")
    action: Literal["close", "open", "redirect"]
    corridor: tuple[str, str] | None = None
    at: float | None = Field(None, gt=0, lt=1, description="door position (close), "
                             "fraction of the corridor from its first node; default 0.5")
    group: str | None = None
    destinations: list[str] = []

    @model_validator(mode="after")
    def _fields(self):
        if self.action in ("close", "open"):
            if self.corridor is None or self.group is not None or self.destinations:
                raise ValueError(f"{self.action} needs corridor (two nodes) and nothing else")
            if self.action == "open" and self.at is not None:
                raise ValueError("at is only used with close (the door opens where it is)")
        elif self.group is None or not self.destinations or self.corridor is not None \
                or self.at is not None:
            raise ValueError("redirect needs group and destinations, and nothing else")
        return self

    @property
    def door_at(self) -> float:
        """Where the door of a ``close`` is, as a fraction of the corridor [-]."""
        return 0.5 if self.at is None else self.at


class WaitingAreaSpec(_Model):
    """Walkers whose route passes ``node`` stand in its area until ``release_time`` [s],
    or leave one at a time at ``release_rate`` [1/s] (first come, first served)."""

    node: str
    release_time: NonNeg | None = Field(None, description="[s]")
    release_rate: Positive | None = Field(None, description="[1/s]")

    @model_validator(mode="after")
    def _one(self):
        if (self.release_time is None) == (self.release_rate is None):
            raise ValueError("give either release_time or release_rate")
        return self


class MeasurementLine(_Model):
    """A line [m] across which PedPy counts the flow; speed and density next to it."""

    name: str = Field(min_length=1)
    line: tuple[Vec2, Vec2]

    @model_validator(mode="after")
    def _length(self):
        (x0, y0), (x1, y1) = self.line
        if (x1 - x0) ** 2 + (y1 - y0) ** 2 < 1e-6:
            raise ValueError("line must have two distinct end points")
        return self


class MeasurementArea(_Model):
    """An area [m] in which PedPy measures density and speed over time."""

    name: str = Field(min_length=1)
    polygon: Polygon2

    @model_validator(mode="after")
    def _valid(self):
        poly = shapely.Polygon(self.polygon)
        if not poly.is_valid or poly.area <= 0:
            raise ValueError("polygon must be valid with positive area")
        if poly.convex_hull.area - poly.area > 1e-9 * poly.area:
            raise ValueError("polygon must be convex (PedPy measures in convex areas)")
        return self


class MeasurementSpec(_Model):
    """Measurement lines and areas analysed into the run folder's ``analysis/``."""

    lines: list[MeasurementLine] = []
    areas: list[MeasurementArea] = []


def cross_errors(scenario, known: set[str]) -> list[tuple[tuple, str]]:
    """Unknown node or group names in the behaviour sections, as (field path, message)."""
    errs: list[tuple[tuple, str]] = []
    groups = {g.name for g in scenario.groups}

    def node(loc: tuple, name: str) -> None:
        if name not in known:
            errs.append((loc, f"must be one of the route nodes {sorted(known)}; got {name!r}"))

    for i, g in enumerate(scenario.groups):
        if g.exit_choice is not None:
            for j, name in enumerate(g.exit_choice.among):
                node(("groups", i, "exit_choice", "among", j), name)
    for i, e in enumerate(scenario.events):
        for j, name in enumerate(e.corridor or ()):
            node(("events", i, "corridor", j), name)
        for j, name in enumerate(e.destinations):
            node(("events", i, "destinations", j), name)
        if e.group is not None and e.group not in groups:
            errs.append((("events", i, "group"),
                         f"must be one of the groups {sorted(groups)}; got {e.group!r}"))
    for i, w in enumerate(scenario.waiting_areas):
        node(("waiting_areas", i, "node"), w.node)
    return errs
