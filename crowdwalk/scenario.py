"""Scenario files: YAML loaded safely, validated by frozen pydantic models.

Sections: ``terrain`` (extent, base height, features), ``routes`` (nodes and edges, or a
GraphML file relative to the scenario), ``groups`` (who walks where, when and how),
``simulation`` (duration [s], seed, dt [s], fps) and ``outputs``. Unknown keys are
errors. Angles are **degrees in the file** (stair and slope headings, inclines) and are
converted to radians when the world is built; everything else is SI.

A bad file raises :class:`~crowdwalk.errors.InputError` with one line naming the file,
the YAML line and the field path, e.g.
``quickstart.yaml:31: groups[0].count must be ≥ 1; got 0.``
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from crowdwalk import behaviours
from crowdwalk.behaviours import (
    EventSpec,
    ExitChoice,
    MeasurementSpec,
    ObstacleSpec,
    WaitingAreaSpec,
)
from crowdwalk.checks import MAX_ROUTE_NODES
from crowdwalk.errors import InputError, existing_file
from crowdwalk.style import GaitName, LockSpec, StyleSpec
from planners import PLANNERS

__all__ = [
    "Scenario",
    "TerrainSpec",
    "RoutesSpec",
    "Group",
    "Normal",
    "SpawnTimes",
    "Simulation",
    "Outputs",
    "load_scenario",
    "parse_scenario",
    "scenario_json_schema",
    "PLANNER_NAMES",
]

PLANNER_NAMES: tuple[str, ...] = tuple(sorted(PLANNERS))
PlannerName = Literal[PLANNER_NAMES]  # the planners' names (planners.PLANNERS)

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]
Polygon2 = Annotated[list[Vec2], Field(min_length=3, description="polygon vertices [m]")]
Positive = Annotated[float, Field(gt=0)]
NonNeg = Annotated[float, Field(ge=0)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True,
                              allow_inf_nan=False)


def _resolve(value: str | None, info: ValidationInfo) -> str | None:
    """A path relative to the scenario file (``context['base_dir']``), made absolute."""
    if value is None:
        return None
    base = (info.context or {}).get("base_dir")
    p = Path(value).expanduser()
    if not p.is_absolute() and base is not None:
        p = Path(base) / p
    return str(p)


# --- terrain ------------------------------------------------------------------------


class BlockSpec(_Model):
    """A block, curb or obstacle: a ``footprint`` polygon, or a ``center`` + ``size``
    rectangle turned by ``heading`` [deg]; flat top at world height ``top`` [m]."""

    type: Literal["block"]
    top: float = Field(description="height of the top face, world z [m]")
    footprint: Polygon2 | None = None
    center: Vec2 | None = None
    size: tuple[Positive, Positive] | None = Field(None, description="(length, width) [m]")
    heading: float = Field(0.0, description="direction of the length axis [deg]")

    @model_validator(mode="after")
    def _one_shape(self):
        if (self.footprint is None) == (self.center is None or self.size is None):
            raise ValueError("give either footprint, or center and size")
        return self

    def build(self):
        from crowdwalk.terrain import Block

        if self.footprint is not None:
            return Block(self.footprint, self.top)
        return Block.box(self.center, self.size, self.top, math.radians(self.heading))


class StairsSpec(_Model):
    """A straight stair flight (see :class:`crowdwalk.terrain.StairFlight`)."""

    type: Literal["stairs"]
    start: Vec2 = Field(description="middle of the first riser's base line [m]")
    heading: float = Field(description="walking direction of the flight [deg from +x]")
    width: Positive = Field(description="[m]")
    going: Positive = Field(description="tread depth [m]")
    rise: Positive = Field(description="riser height [m]")
    steps: int = Field(ge=1, description="number of treads")
    base: float = Field(0.0, description="ground height before the first riser [m]")
    direction: Literal["up", "down"] = "up"

    def build(self):
        from crowdwalk.terrain import StairFlight

        return StairFlight(self.start, math.radians(self.heading), self.width, self.going,
                           self.rise, self.steps, self.base, self.direction == "up")


class RampSpec(_Model):
    """A rectangular ramp from the middle of its lower edge ``start``."""

    type: Literal["ramp"]
    start: Vec2 = Field(description="[m]")
    heading: float = Field(description="direction from start to end [deg from +x]")
    length: Positive = Field(description="horizontal length [m]")
    width: Positive = Field(description="[m]")
    z_start: float = Field(0.0, description="height at start [m]")
    z_end: float = Field(description="height at the far end [m]")

    def build(self):
        from crowdwalk.terrain import Slope

        return Slope.ramp(self.start, math.radians(self.heading), self.length, self.width,
                          self.z_start, self.z_end)


class SlopeSpec(_Model):
    """A planar slope over a polygon: height ``z0`` at ``origin``, rising at ``incline``
    [deg] towards ``heading`` [deg]."""

    type: Literal["slope"]
    footprint: Polygon2
    origin: Vec2 = Field(description="[m]")
    z0: float = Field(0.0, description="height at origin [m]")
    heading: float = Field(description="direction of steepest ascent [deg from +x]")
    incline: float = Field(gt=-60, lt=60, description="slope angle [deg]")

    def build(self):
        from crowdwalk.terrain import Slope

        return Slope(self.footprint, self.origin, self.z0, math.radians(self.heading),
                     math.tan(math.radians(self.incline)))


class RoughSpec(_Model):
    """Rough ground: seeded noise (``amplitude``, ``correlation``, ``seed``) or a height
    array (inline ``heights`` or a ``.npy`` / ``.csv`` ``heights_file``)."""

    type: Literal["rough"]
    origin: Vec2 = Field(description="position of the first grid node [m]")
    cell: Positive = Field(description="grid spacing [m]")
    size: tuple[Positive, Positive] | None = Field(None, description="(lx, ly) for noise [m]")
    amplitude: NonNeg | None = Field(None, description="noise standard deviation [m]")
    correlation: Positive = Field(1.0, description="noise correlation length [m]")
    seed: int = 0
    base: float = Field(0.0, description="mean height [m]")
    taper: NonNeg = Field(0.0, description="fade to base at the border over [m]")
    heights: list[list[float]] | None = Field(None, description="rows along y, [m]")
    heights_file: str | None = None

    _resolve_file = field_validator("heights_file")(_resolve)

    @model_validator(mode="after")
    def _one_source(self):
        noise = self.amplitude is not None
        given = (self.heights is not None) + (self.heights_file is not None) + noise
        if given != 1:
            raise ValueError("give exactly one of amplitude (noise), heights, heights_file")
        if noise and self.size is None:
            raise ValueError("noise needs size (lx, ly) [m]")
        return self

    def build(self):
        from crowdwalk.terrain import Heightfield

        if self.amplitude is not None:
            return Heightfield.noise(self.origin, self.size, self.cell, self.amplitude,
                                     self.correlation, self.seed, self.base, self.taper)
        if self.heights is not None:
            h = np.asarray(self.heights, dtype=float)
        else:
            path = existing_file(self.heights_file)
            h = np.load(path) if path.suffix == ".npy" else np.loadtxt(path, delimiter=",")
        return Heightfield(self.origin, self.cell, self.base + h)


class MeshSpec(_Model):
    """Any mesh trimesh reads (OBJ/STL/PLY/GLB), turned to z up if ``up: y``, scaled,
    turned by ``rotate`` [deg] about z, then moved by ``translate`` [m]."""

    type: Literal["mesh"]
    path: str = Field(description="relative to the scenario file")
    translate: Vec3 = (0.0, 0.0, 0.0)
    scale: Positive = 1.0
    rotate: float = Field(0.0, description="[deg] about z")
    up: Literal["z", "y"] = Field("z", description="the file's up axis (glTF: y)")

    _resolve_path = field_validator("path")(_resolve)

    def build(self):
        from crowdwalk.terrain import MeshFeature

        return MeshFeature.load(self.path, self.translate, self.scale, math.radians(self.rotate),
                                self.up)


FeatureSpec = Annotated[
    BlockSpec | StairsSpec | RampSpec | SlopeSpec | RoughSpec | MeshSpec,
    Field(discriminator="type"),
]


class TerrainSpec(_Model):
    """The ground: a flat base over ``extent`` plus features; where footprints overlap the
    feature listed last decides the height."""

    extent: tuple[float, float, float, float] = Field(description="xmin, ymin, xmax, ymax [m]")
    base: float = Field(0.0, description="height of the flat base [m]")
    features: list[FeatureSpec] = []

    def build(self):
        """The :class:`crowdwalk.terrain.Terrain` this section describes."""
        from crowdwalk.checks import at
        from crowdwalk.terrain import Terrain

        features = tuple(at(("terrain", "features", i), f.build)
                         for i, f in enumerate(self.features))
        return at(("terrain",), Terrain, self.extent, self.base, features)


# --- routes -------------------------------------------------------------------------


class NodeSpec(_Model):
    """A place: ``xy`` [m] and an optional ``area`` polygon [m] where agents stand."""

    name: str = Field(min_length=1)
    xy: Vec2
    area: Polygon2 | None = None


class EdgeSpec(_Model):
    """A corridor between two nodes."""

    from_: str = Field(alias="from")
    to: str
    width: Positive = Field(description="clear width [m]")
    via: list[Vec2] = Field([], description="intermediate centre-line points [m]")
    oneway: bool = False


class RoutesSpec(_Model):
    """The route graph: inline ``nodes`` and ``edges``, or a ``graphml`` file."""

    graphml: str | None = None
    nodes: list[NodeSpec] = Field([], max_length=MAX_ROUTE_NODES)
    edges: list[EdgeSpec] = Field([], max_length=MAX_ROUTE_NODES)

    _resolve_graphml = field_validator("graphml")(_resolve)

    @model_validator(mode="after")
    def _one_source(self):
        if self.graphml is not None and (self.nodes or self.edges):
            raise ValueError("give either graphml or nodes/edges, not both")
        if self.graphml is None and not self.nodes:
            raise ValueError("give nodes (and edges) or a graphml file")
        return self

    def node_names(self) -> list[str]:
        """Names of the route nodes (reads the GraphML file if there is one)."""
        if self.graphml is None:
            return [n.name for n in self.nodes]
        import networkx as nx

        return [str(n) for n in nx.read_graphml(existing_file(self.graphml)).nodes]

    def build(self, terrain=None, obstacles=()):
        """The :class:`crowdwalk.routes.RouteGraph` this section describes (``obstacles``:
        shapely polygons cut out of the walkable area)."""
        from crowdwalk.routes import Corridor, Place, RouteGraph

        if self.graphml is not None:
            return RouteGraph.from_graphml(self.graphml, terrain, obstacles=obstacles)
        places = [Place(n.name, n.xy[0], n.xy[1], n.area) for n in self.nodes]
        corridors = [Corridor(e.from_, e.to, e.width, tuple(e.via), e.oneway)
                     for e in self.edges]
        return RouteGraph(places, corridors, terrain, obstacles=obstacles)


# --- groups -------------------------------------------------------------------------


class Normal(_Model):
    """A normal distribution truncated to [min, max] (default mean ± 3 sd)."""

    mean: float
    sd: NonNeg = 0.0
    min: float | None = None
    max: float | None = None

    @model_validator(mode="after")
    def _range(self):
        lo, hi = self.bounds
        if not lo <= self.mean <= hi:
            raise ValueError(f"mean {self.mean} must lie in [min, max] = [{lo}, {hi}]")
        return self

    @property
    def bounds(self) -> tuple[float, float]:
        lo = self.mean - 3 * self.sd if self.min is None else self.min
        hi = self.mean + 3 * self.sd if self.max is None else self.max
        return lo, hi

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` draws (n,) by resampling outside [min, max]."""
        lo, hi = self.bounds
        x = rng.normal(self.mean, self.sd, n)
        for _ in range(100):
            bad = (x < lo) | (x > hi)
            if not bad.any():
                break
            x[bad] = rng.normal(self.mean, self.sd, int(bad.sum()))
        return np.clip(x, lo, hi)


# Adult body height, mixed sexes: mean 1.71 m, sd 0.09 m — approximately the pooled
# distribution of European adult men (≈1.78 m) and women (≈1.65 m), NCD Risk Factor
# Collaboration, "A century of trends in adult human height", eLife 5:e13410 (2016).
DEFAULT_BODY_HEIGHT = Normal(mean=1.71, sd=0.09, min=1.45, max=2.05)
MIN_FREE_SPEED = 0.1  # [m/s]; slower is standing still (planned as speed class 0)
# Free walking speed: Weidmann (1993), Transporttechnik der Fussgänger, ETH Zürich,
# mean 1.34 m/s, sd 0.26 m/s.
DEFAULT_FREE_SPEED = Normal(mean=1.34, sd=0.26, min=0.6, max=2.1)


class SpawnTimes(_Model):
    """When a group's agents enter: from ``start`` [s], one every ``interval`` [s] or at
    ``rate`` [1/s] (exactly one of the two; all at once if neither); ``process: poisson``
    draws exponential gaps of mean ``interval`` (a Poisson arrival process)."""

    start: NonNeg = 0.0
    interval: NonNeg | None = None
    rate: Positive | None = None
    process: Literal["regular", "poisson"] = "regular"

    @model_validator(mode="after")
    def _one(self):
        if self.interval is not None and self.rate is not None:
            raise ValueError("give interval or rate, not both")
        if self.process == "poisson" and not (self.rate or self.interval):
            raise ValueError("poisson arrivals need a rate or an interval > 0")
        return self

    def times(self, n: int, rng: np.random.Generator | None = None) -> np.ndarray:
        """Spawn times (n,) [s] (``rng`` draws the gaps of Poisson arrivals)."""
        step = 1.0 / self.rate if self.rate is not None else (self.interval or 0.0)
        if self.process == "poisson":
            if rng is None:
                raise ValueError("poisson arrivals need a random generator")
            gaps = rng.exponential(step, max(n - 1, 0))
            return self.start + np.concatenate([[0.0], np.cumsum(gaps)])[:n]
        return self.start + step * np.arange(n)


class Group(_Model):
    """Agents that share a spawn place, destinations and distributions."""

    name: str = Field(min_length=1)
    count: int = Field(ge=1)
    spawn: str | Polygon2 = Field(description="route node name, or a polygon [m]")
    spawn_times: SpawnTimes = SpawnTimes()
    destinations: list[str] = Field([], description="route nodes, visited in order")
    exit_choice: ExitChoice | None = Field(None, description="then one exit among several")
    density: Positive | None = Field(None, le=6.0, description="start density [1/m²]")
    body_height: Normal = Field(DEFAULT_BODY_HEIGHT, description="[m]")
    free_speed: Normal = Field(DEFAULT_FREE_SPEED, description="[m/s]")
    planner: PlannerName = "best_first_multistart"
    gait: GaitName = Field("elevation_angles", description="gait engine of the group")
    style: StyleSpec | None = Field(None, description="KLAW style (crowdwalk.style)")
    lock: LockSpec | None = Field(None, description="locked locomotion parameter(s)")

    @model_validator(mode="after")
    def _somewhere(self):
        if not self.destinations and self.exit_choice is None:
            raise ValueError("give destinations or exit_choice")
        return self

    @field_validator("body_height")
    @classmethod
    def _height_range(cls, v: Normal) -> Normal:
        lo, hi = v.bounds
        if lo < 0.5 or hi > 2.6:
            raise ValueError(f"body heights must lie in [0.5, 2.6] m; got [{lo}, {hi}]")
        return v

    @field_validator("free_speed")
    @classmethod
    def _speed_range(cls, v: Normal) -> Normal:
        lo, hi = v.bounds
        if lo < MIN_FREE_SPEED or hi > 3.0:  # the planner's speed classes are 5 cm/s wide
            raise ValueError(f"free speeds must lie in [{MIN_FREE_SPEED}, 3] m/s; "
                             f"got [{lo:g}, {hi:g}]")
        return v


class Simulation(_Model):
    """Run settings."""

    duration: Positive = Field(description="simulated time [s]")
    seed: int = Field(0, ge=0)
    dt: Positive = Field(0.05, le=1.0, description="time step [s]")
    fps: Positive = Field(25.0, le=240, description="output frame rate [1/s]")


class Outputs(_Model):
    """What a run writes."""

    poses: bool = Field(True, description="write full-body poses (poses.sqlite)")


class Scenario(_Model):
    """A whole scenario file."""

    name: str = ""
    description: str = ""
    terrain: TerrainSpec
    routes: RoutesSpec
    groups: list[Group] = Field(min_length=1)
    simulation: Simulation
    outputs: Outputs = Outputs()
    obstacles: list[ObstacleSpec] = []
    events: list[EventSpec] = Field([], max_length=1000)
    waiting_areas: list[WaitingAreaSpec] = Field([], max_length=MAX_ROUTE_NODES)
    measurement: MeasurementSpec = MeasurementSpec()
    _source: str = PrivateAttr("<scenario>")
    _root: object = PrivateAttr(None)  # the YAML node graph it was read from

    def where(self, loc: tuple) -> str:
        """``"file:line"`` of a field path such as ``("groups", 0, "spawn")``."""
        line = _line(self._root, loc)
        return f"{self._source}:{line}" if line else self._source

    def cross_errors(self) -> list[tuple[tuple, str]]:
        """Problems between sections as (field path, message); empty when consistent."""
        names = self.routes.node_names()
        known = set(names)
        errs: list[tuple[tuple, str]] = []
        if len(known) != len(names):
            errs.append((("routes", "nodes"), "node names must be unique"))
        for i, e in enumerate(self.routes.edges):
            for key, val in (("from", e.from_), ("to", e.to)):
                if val not in known:
                    errs.append((("routes", "edges", i, key),
                                 f"must be one of the route nodes {sorted(known)}; got {val!r}"))
        seen = set()
        for i, g in enumerate(self.groups):
            if g.name in seen:
                errs.append((("groups", i, "name"), f"must be unique; got {g.name!r} twice"))
            seen.add(g.name)
            if isinstance(g.spawn, str) and g.spawn not in known:
                errs.append((("groups", i, "spawn"),
                             f"must be one of the route nodes {sorted(known)}; got {g.spawn!r}"))
            for j, d in enumerate(g.destinations):
                if d not in known:
                    errs.append((("groups", i, "destinations", j),
                                 f"must be one of the route nodes {sorted(known)}; got {d!r}"))
        return errs + behaviours.cross_errors(self, known)


# --- loading ------------------------------------------------------------------------


def _loc_text(loc: tuple) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "scenario"


def _node_at(root, loc: tuple):
    """The YAML node at a pydantic location (skipping union tags); the deepest found."""
    node = root
    for part in loc:
        if isinstance(node, yaml.MappingNode):
            nxt = next((v for k, v in node.value if k.value == str(part)), None)
            if nxt is None:
                key = next((k for k, v in node.value if k.value == str(part)), None)
                if key is not None:
                    return key
                continue  # a union tag such as 'stairs' in the location
            node = nxt
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int):
            if part >= len(node.value):
                return node
            node = node.value[part]
        else:
            break
    return node


def _clean_loc(root, loc: tuple) -> tuple:
    """The location without union tags (parts that are no key of the YAML mapping)."""
    node, out = root, []
    for part in loc:
        if isinstance(node, yaml.MappingNode):
            nxt = next((v for k, v in node.value if k.value == str(part)), None)
            if nxt is None and isinstance(part, str) and any(
                    k.value == "type" and v.value == part for k, v in node.value):
                continue  # the discriminator tag pydantic inserts
            node = nxt
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int):
            node = node.value[part] if part < len(node.value) else None
        else:
            node = None
        out.append(part)
    return tuple(out)


def _key_node(root, loc: tuple):
    """The key node of the last location part if it is a mapping key (for unknown keys)."""
    parent = _node_at(root, loc[:-1]) if loc else root
    if isinstance(parent, yaml.MappingNode):
        for k, _ in parent.value:
            if k.value == str(loc[-1]):
                return k
    return _node_at(root, loc)


def _line(root, loc: tuple, key: bool = False) -> int | None:
    if root is None:
        return None
    node = _key_node(root, loc) if key else _node_at(root, loc)
    return node.start_mark.line + 1 if node is not None else None


def _duplicate_keys(node, path=()):
    """(location, line) of the first repeated mapping key, or None."""
    if isinstance(node, yaml.MappingNode):
        seen = set()
        for k, v in node.value:
            if k.value in seen:
                return path + (k.value,), k.start_mark.line + 1
            seen.add(k.value)
            found = _duplicate_keys(v, path + (k.value,))
            if found:
                return found
    elif isinstance(node, yaml.SequenceNode):
        for i, v in enumerate(node.value):
            found = _duplicate_keys(v, path + (i,))
            if found:
                return found
    return None


_CONSTRAINTS = {
    "greater_than": "> {gt}",
    "greater_than_equal": "≥ {ge}",
    "less_than": "< {lt}",
    "less_than_equal": "≤ {le}",
    "literal_error": "one of {expected}",
    "int_parsing": "an integer",
    "int_from_float": "an integer",
    "int_type": "an integer",
    "float_parsing": "a number",
    "finite_number": "a finite number",
    "float_type": "a number",
    "bool_parsing": "true or false",
    "bool_type": "true or false",
    "string_type": "a string",
    "too_short": "at least {min_length} item(s) long",
    "too_long": "at most {max_length} item(s) long",
    "list_type": "a list",
    "tuple_type": "a list",
    "dict_type": "a mapping",
    "model_type": "a mapping",
    "model_attributes_type": "a mapping",
    "union_tag_invalid": "a known type, one of {expected_tags}",
    "union_tag_not_found": "a mapping with a 'type' key",
}

# Units of scenario fields by key (for error messages); mean/sd/min/max take their
# distribution's unit.
_UNITS = {
    "duration": "s", "dt": "s", "start": "s", "interval": "s", "rate": "1/s", "fps": "1/s",
    "width": "m", "going": "m", "rise": "m", "length": "m", "top": "m", "base": "m",
    "z0": "m", "z_start": "m", "z_end": "m", "cell": "m", "amplitude": "m",
    "correlation": "m", "taper": "m", "size": "m", "heading": "deg", "incline": "deg",
    "rotate": "deg", "body_height": "m", "free_speed": "m/s",
    "density": "1/m²", "release_time": "s", "release_rate": "1/s", "thickness": "m",
}


def _constraint(error: dict) -> str | None:
    """The pydantic error as a "must be ..." constraint, or None if it has no such form."""
    template = _CONSTRAINTS.get(error["type"])
    if template is None:
        return None
    try:
        return template.format(**(error.get("ctx") or {}))
    except (KeyError, IndexError):
        return None


def _unit(loc: tuple) -> str:
    keys = [p for p in loc if isinstance(p, str)]
    for key in reversed(keys):
        if key in _UNITS and (key == keys[-1] or key in ("body_height", "free_speed")):
            return f" [{_UNITS[key]}]"
    return ""


def _fail(source: str, line: int | None, text: str) -> InputError:
    where = f"{source}:{line}" if line else source
    return InputError(f"{where}: {text}")


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def parse_scenario(text: str, source: str = "<scenario>", base_dir=None) -> Scenario:
    """Validate scenario YAML ``text``; ``base_dir`` resolves relative file paths."""
    from crowdwalk.safe_yaml import compose_bounded, construct

    try:
        root = compose_bounded(text, source)
        data = construct(root)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = mark.line + 1 if mark else text.count("\n", 0, getattr(exc, "position", 0)) + 1
        problem = getattr(exc, "problem", None) or getattr(exc, "reason", None) or \
            str(exc).splitlines()[0]
        raise _fail(source, line, f"not valid YAML: {problem}.") from None
    if not isinstance(data, dict):
        raise _fail(source, 1, f"scenario must be a mapping of sections; got "
                    f"{type(data).__name__}.")
    dup = _duplicate_keys(root)
    if dup:
        raise _fail(source, dup[1], f"{_loc_text(dup[0])} is given twice.")
    try:
        sc = Scenario.model_validate(data, context={"base_dir": base_dir})
    except ValidationError as exc:
        errs = exc.errors()
        e = errs[0]
        loc = _clean_loc(root, tuple(e["loc"]))
        msg = e["msg"].removeprefix("Value error, ")
        more = f" ({len(errs) - 1} more problem(s))" if len(errs) > 1 else ""
        if e["type"] == "extra_forbidden":
            text = f"{_loc_text(loc)} is not a known key{more}."
            raise _fail(source, _line(root, loc, key=True), text) from None
        if e["type"] == "missing":
            text = f"{_loc_text(loc)} is required{more}."
            raise _fail(source, _line(root, loc[:-1]), text) from None
        constraint = _constraint(e)
        got = _short(e.get("input"))
        if e["type"] == "union_tag_invalid":
            got = repr(e["ctx"]["tag"])
        if constraint is not None:
            text = f"{_loc_text(loc)} must be {constraint}{_unit(loc)}; got {got}{more}."
        else:
            text = f"{_loc_text(loc)}: {msg}; got {got}{more}."
        raise _fail(source, _line(root, loc), text) from None
    errs = sc.cross_errors()
    if errs:
        loc, msg = errs[0]
        raise _fail(source, _line(root, loc), f"{_loc_text(loc)} {msg}.")
    sc._source, sc._root = source, root
    return sc


def load_scenario(path) -> Scenario:
    """Read and validate a scenario YAML file (paths inside are relative to it)."""
    path = existing_file(path)
    data = path.read_bytes()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise _fail(str(path), data.count(b"\n", 0, exc.start) + 1,
                    f"a scenario file must be UTF-8 text; got byte {data[exc.start]:#04x}.") \
            from None
    return parse_scenario(text, str(path), path.parent)


def scenario_json_schema() -> dict:
    """JSON Schema (draft 2020-12) of a scenario file."""
    return Scenario.model_json_schema(by_alias=True)
