"""Route graphs: places joined by walkable corridors, shortest routes by travel cost.

A :class:`RouteGraph` wraps a ``networkx.DiGraph``. Nodes are places (``x``, ``y`` [m],
optional ``area`` polygon); every corridor becomes one directed edge per walkable
direction with attributes ``width`` [m], ``length`` [m], ``cost`` [m of flat-walking
equivalent], ``geometry`` (shapely LineString) and ``oneway``.

Cost model (documented deviation-free defaults, :class:`RouteCosts`): the cost of an edge
is the time to walk it at free speed, expressed in metres of level walking, computed once
from the terrain profile along its centre line:

- on slopes, Tobler's hiking function (Tobler 1993) relative to level ground,
  ``f(g) = exp(3.5 (|g + 0.05| − 0.05))``, floored at 1 so that no edge costs less than
  its length (Tobler's mild-downhill bonus is dropped);
- each vertical height change (stair riser, curb) adds ``climb·Δz`` going up and
  ``descent·|Δz|`` going down. The factors follow Weidmann (1993): horizontal speed on
  stairs 0.610 m/s up and 0.694 m/s down against 1.34 m/s on the level, i.e. 2.20× and
  1.93× the level travel time, spread over the 1.76 m of run per metre of rise of a
  standard 0.17/0.30 m stair: (2.20 − 1) · 1.76 = 2.1 and (1.93 − 1) · 1.76 = 1.6;
- a single vertical change higher than ``max_step`` (0.5 m) is not walkable: building a
  corridor over it is an error.

One Dijkstra distance field per destination (:meth:`RouteGraph.distances_to`, cached)
serves every agent going there.
"""

from __future__ import annotations

import copy
import functools
import math
import re
from dataclasses import dataclass

import networkx as nx
import numpy as np
import shapely
from shapely.geometry import LineString, Point, Polygon

from crowdwalk.checks import MAX_ROUTE_NODES
from crowdwalk.errors import InfeasibleError, existing_file, invalid

__all__ = ["Place", "Corridor", "RouteCosts", "RouteGraph", "spawn_points",
           "lattice_points"]


@dataclass(frozen=True, eq=False)
class Place:
    """A route node: a named place at (x, y) [m] with an optional area polygon [m]."""

    name: str
    x: float
    y: float
    area: Polygon | None = None

    def __post_init__(self):
        if not (np.isfinite(self.x) and np.isfinite(self.y)):
            raise invalid("Place", "xy", "finite [m]", (self.x, self.y))
        if self.area is not None:
            area = self.area if isinstance(self.area, Polygon) else Polygon(self.area)
            if not area.is_valid or area.area <= 0:
                raise invalid(f"Place[{self.name!r}]", "area",
                              "a valid polygon with positive area [m²]", area.wkt)
            if not area.buffer(1e-9).covers(Point(self.x, self.y)):
                raise invalid(f"Place[{self.name!r}]", "area", f"a polygon around its node "
                              f"({self.x}, {self.y}) [m]", area.wkt)
            object.__setattr__(self, "area", area)


@dataclass(frozen=True, eq=False)
class Corridor:
    """A walkable corridor between places ``a`` and ``b``.

    Parameters
    ----------
    a, b : node names
    width : clear width [m], > 0
    via : (k, 2) intermediate centre-line points [m] (may be empty)
    oneway : walkable only from ``a`` to ``b``
    """

    a: str
    b: str
    width: float
    via: tuple[tuple[float, float], ...] = ()
    oneway: bool = False

    def __post_init__(self):
        name = f"Corridor[{self.a!r}->{self.b!r}]"
        if not (np.isfinite(self.width) and self.width > 0):
            raise invalid(name, "width", "> 0 [m]", self.width)
        if self.a == self.b:
            raise invalid(name, "b", "a different node than a", self.b)
        object.__setattr__(self, "via", tuple(tuple(float(c) for c in p) for p in self.via))


@dataclass(frozen=True)
class RouteCosts:
    """Travel-cost factors (see the module docstring for sources).

    Attributes
    ----------
    tobler : Tobler's exponent [1/(m/m)]
    climb : extra cost per metre of vertical rise [m/m]
    descent : extra cost per metre of vertical drop [m/m]
    max_step : highest walkable single vertical change [m]
    min_length : shortest accepted corridor [m]
    """

    tobler: float = 3.5
    climb: float = 2.1
    descent: float = 1.6
    max_step: float = 0.5
    min_length: float = 0.05


def _segments_near(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray,
                   eps: float) -> np.ndarray:
    """(p,) bool: segments a–b that cross or come within ``eps`` [m] of segments c–d (all
    (p, 2) [m], or (2,) for one c–d)."""
    def cross(u, v):
        return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

    def to_segment(p, q0, q1):  # distance of points p from segments q0-q1
        e = q1 - q0
        t = np.clip(np.sum((p - q0) * e, axis=-1) / np.maximum(np.sum(e * e, axis=-1),
                                                              1e-300), 0.0, 1.0)
        return np.linalg.norm(p - (q0 + t[..., None] * e), axis=-1)

    crossing = (cross(b - a, c - a) * cross(b - a, d - a) < 0) & \
        (cross(d - c, a - c) * cross(d - c, b - c) < 0)
    near = np.minimum(np.minimum(to_segment(a, c, d), to_segment(b, c, d)),
                      np.minimum(to_segment(c, a, b), to_segment(d, a, b)))
    return crossing | (near < eps)


def _ring_edges(rings) -> frozenset:
    """The edges of polygon rings as a set of ((x0, y0), (x1, y1)) [m], each with its
    ends in sorted order (coordinates rounded to 1 nm)."""
    out = set()
    for ring in rings:
        xy = np.round(shapely.get_coordinates(ring), 9)
        for p, q in zip(map(tuple, xy[:-1]), map(tuple, xy[1:]), strict=True):
            if p != q:
                out.add((p, q) if p < q else (q, p))
    return frozenset(out)


def _slope_factor(grade: np.ndarray, tobler: float) -> np.ndarray:
    """Tobler (1993) travel-time factor relative to level ground, floored at 1."""
    return np.maximum(1.0, np.exp(tobler * (np.abs(grade + 0.05) - 0.05)))


def spawn_points(area, n: int, rng: np.random.Generator, min_spacing: float = 0.5,
                 attempts: int = 30) -> np.ndarray:
    """Up to ``n`` seeded random points inside ``area`` at least ``min_spacing`` apart.

    Parameters
    ----------
    area : shapely geometry with positive area [m]
    n : number of points
    rng : numpy Generator (the only source of randomness)
    min_spacing : minimal distance between points [m]
    attempts : candidates drawn per requested point

    Returns
    -------
    (n, 2) points [m]. Raises :class:`~crowdwalk.errors.InputError` if ``n`` points do not
    fit.
    """
    if n < 0 or int(n) != n:
        raise invalid("spawn_points", "n", "an integer ≥ 0", n)
    if n == 0:
        return np.zeros((0, 2))
    if area is None or area.area <= 0:
        raise invalid("spawn_points", "area", "a polygon with positive area [m²]", area)
    if not min_spacing >= 0:
        raise invalid("spawn_points", "min_spacing", "≥ 0 [m]", min_spacing)
    shapely.prepare(area)
    x0, y0, x1, y1 = area.bounds
    m = attempts * n
    cand = rng.uniform((x0, y0), (x1, y1), size=(int(m / max(area.area / ((x1 - x0) * (y1 - y0)),
                                                             1e-3)) + 1, 2))
    cand = cand[shapely.contains_xy(area, cand[:, 0], cand[:, 1])][:m]
    d2 = min_spacing**2
    densest = int(0.9069 * area.area / (math.pi * d2 / 4)) if d2 else n  # hexagonal packing
    if d2 == 0 or n > densest:  # no spacing to keep, or more discs than can ever fit
        k = len(cand) if d2 == 0 else densest
        if k >= n:
            return cand[:n].copy()
    else:
        chosen = _dart_throw(cand, n, min_spacing)
        if len(chosen) == n:
            return chosen
        k = len(chosen)
    fit = max(k, 1)
    raise invalid("spawn_points", "n", f"at most about {fit} for an area of {area.area:.1f} m² "
                  f"at min_spacing {min_spacing} m", n)


def _dart_throw(cand: np.ndarray, n: int, spacing: float) -> np.ndarray:
    """The first ``n`` candidates (m, 2) [m], in order, each at least ``spacing`` [m] from
    the ones taken before it (a grid of spacing/√2 cells holds at most one point each, so
    a candidate is compared with the points of the 5 × 5 cells around it only)."""
    h = spacing / math.sqrt(2)
    d2 = spacing**2
    cells = np.floor((cand - cand.min(axis=0, initial=0.0)) / h).astype(np.int64)
    taken: dict[tuple[int, int], tuple[float, float]] = {}
    out: list[tuple[float, float]] = []
    for first in range(0, len(cand), 4096):  # in chunks: the first n usually suffice
        chunk = zip(cand[first:first + 4096].tolist(), cells[first:first + 4096].tolist(),
                    strict=True)
        for (x, y), (i, j) in chunk:
            if all((p := taken.get((i + di, j + dj))) is None
                   or (p[0] - x) ** 2 + (p[1] - y) ** 2 >= d2
                   for di in (-2, -1, 0, 1, 2) for dj in (-2, -1, 0, 1, 2)):
                taken[(i, j)] = (x, y)
                out.append((x, y))
                if len(out) == n:
                    return np.array(out, dtype=float)
    return np.array(out, dtype=float).reshape(-1, 2)


GRAPHML_WIDTH = 2.0  # [m] corridor width of a GraphML edge without ``width`` (a footway)


def _graphml_float(value, owner: str, name: str) -> float:
    """A GraphML number; OSMnx writes several values of a merged way as "['3', '4']"
    (the smallest is taken)."""
    if isinstance(value, str):
        numbers = re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|nan|inf", value)
        if len(numbers) != 1 and not value.strip().startswith("["):
            raise invalid(owner, name, "a number [m]", value)
        value = min(map(float, numbers), default=math.nan)
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise invalid(owner, name, "a number [m]", value) from None
    if not math.isfinite(value):
        raise invalid(owner, name, "a finite number [m]", value)
    return value


def _graphml_bool(value, owner: str, name: str) -> bool:
    """A GraphML boolean, also the strings "True"/"false"/"yes"/"0" OSMnx and others write."""
    if isinstance(value, bool | int | float):
        return bool(value)
    text = str(value).strip().lower()
    if text in ("true", "yes", "1"):
        return True
    if text in ("false", "no", "0", ""):
        return False
    raise invalid(owner, name, "true or false", value)


def lattice_points(area, n: int, density: float, rng: np.random.Generator, *,
                   front=None) -> np.ndarray:
    """``n`` points of a hexagonal lattice at ``density`` [1/m²] inside ``area``.

    The lattice (spacing ``sqrt(2 / (sqrt(3) density))`` [m]) gets a random phase and
    orientation from ``rng`` (up to 8 draws until ``n`` points fit); of the points inside
    ``area`` the ``n`` nearest to ``front`` (2,) [m] (default: the area's centroid) are
    kept, so a crowd starts as one block at the given density next to where it goes.

    Returns
    -------
    (n, 2) points [m]. Raises :class:`~crowdwalk.errors.InputError` if fewer fit.
    """
    if not (np.isfinite(density) and density > 0):
        raise invalid("lattice_points", "density", "> 0 [1/m²]", density)
    a = float(np.sqrt(2.0 / (np.sqrt(3.0) * density)))
    x0, y0, x1, y1 = area.bounds
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    reach = 0.5 * np.hypot(x1 - x0, y1 - y0) + a
    k = int(np.ceil(reach / a)) + 1
    i, j = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1))
    uv = np.column_stack([(i + 0.5 * (j % 2)).ravel() * a, j.ravel() * a * np.sqrt(3) / 2])
    shapely.prepare(area)
    for _ in range(8):  # a few phases: in a small area the lattice's fit depends on them
        turn = rng.uniform(0, 2 * np.pi)
        rot = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
        pts = centre + (uv + rng.uniform(0, a, 2)) @ rot.T
        pts = pts[shapely.contains_xy(area, pts[:, 0], pts[:, 1])]
        if len(pts) >= n:
            break
    if len(pts) < n:
        raise invalid("Group", "density", f"at least {n / max(area.area, 1e-9):.2f} /m² for "
                      f"{n} agents in {area.area:.1f} m² (the lattice holds {len(pts)})",
                      density)
    ref = np.asarray(area.centroid.coords[0]) if front is None else np.asarray(front, float)
    order = np.argsort(np.linalg.norm(pts - ref, axis=1), kind="stable")
    return pts[np.sort(order[:n])]


_WALL_HALF_THICKNESS = 5e-4  # [m] walls cut the walkable area as 1 mm wide strips


class RouteGraph:
    """Places and corridors as a networkx DiGraph with travel costs from the terrain.

    Parameters
    ----------
    places : iterable of :class:`Place`
    corridors : iterable of :class:`Corridor`
    terrain : :class:`crowdwalk.terrain.Terrain` or None (level ground everywhere)
    costs : :class:`RouteCosts`
    obstacles : shapely polygons [m] cut out of the walkable area (walls, obstacles);
        paths go around them

    Attributes
    ----------
    graph : networkx.DiGraph
        The corridors that can be walked (routing).
    layout : networkx.DiGraph
        Every corridor, closed ones too (:meth:`with_closed`): the walkable area's shape.
    """

    def __init__(self, places, corridors, terrain=None, costs: RouteCosts = RouteCosts(),
                 obstacles=()):
        self.terrain = terrain
        self.costs = costs
        self.obstacles = shapely.union_all(list(obstacles)) if len(obstacles) else None
        self._base_obstacles = self.obstacles  # without the walls of closed corridors
        self.places = {}
        for p in places:
            if p.name in self.places:
                raise invalid("RouteGraph", "nodes", "unique names", p.name)
            self.places[p.name] = p
        self.corridors = tuple(corridors)
        g = nx.DiGraph()
        for p in self.places.values():
            g.add_node(p.name, x=p.x, y=p.y, area=p.area)
            if terrain is not None and not terrain.area.covers(Point(p.x, p.y)):
                raise invalid(f"RouteGraph.nodes[{p.name!r}]", "xy",
                              f"inside the terrain extent {terrain.bounds} [m]", (p.x, p.y))
            if terrain is not None and p.area is not None and not terrain.area.buffer(
                    1e-9).covers(p.area):
                raise invalid(f"RouteGraph.nodes[{p.name!r}]", "area",
                              f"inside the terrain extent {terrain.bounds} [m]", p.area.bounds)
        seen = set()
        lines = [self._corridor_line(c, seen) for c in self.corridors]
        # one batched terrain pass for the profiles of every corridor, both directions
        fwd, back = self._edge_costs(lines)
        for c, line, cf, cb in zip(self.corridors, lines, fwd, back, strict=True):
            g.add_edge(c.a, c.b, width=c.width, length=line.length, cost=cf, geometry=line,
                       oneway=c.oneway)
            if not c.oneway:
                g.add_edge(c.b, c.a, width=c.width, length=line.length, cost=cb,
                           geometry=LineString(np.asarray(line.coords)[::-1]), oneway=False)
        self.graph = g
        self.layout = g  # every corridor, open or closed (the walkable area)
        self._fields: dict[str, tuple[dict, dict]] = {}
        self._paths: dict[tuple, np.ndarray] = {}

    # -- construction --

    def _corridor_line(self, c: Corridor, seen: set) -> LineString:
        """Checked centre line of corridor ``c`` [m]."""
        name = f"RouteGraph.edges[{c.a!r}->{c.b!r}]"
        for end in (c.a, c.b):
            if end not in self.places:
                raise invalid(name, "node", f"one of {sorted(self.places)}", end)
        key = frozenset((c.a, c.b))
        if key in seen:
            raise invalid(name, "nodes", "joined by one corridor only", f"{c.a!r}, {c.b!r}")
        seen.add(key)
        pa, pb = self.places[c.a], self.places[c.b]
        line = LineString(np.array([(pa.x, pa.y), *c.via, (pb.x, pb.y)], dtype=float))
        if line.length < self.costs.min_length:
            raise invalid(name, "length", f"≥ {self.costs.min_length} m (merge the two places)",
                          round(line.length, 6))
        if self.terrain is not None:
            # the extent is a rectangle: the buffered band is inside iff its bounds are
            x0, y0, x1, y1 = np.asarray(line.bounds) + np.array([-1, -1, 1, 1]) * c.width / 2
            ex0, ey0, ex1, ey1 = self.terrain.bounds
            if x0 < ex0 - 1e-9 or y0 < ey0 - 1e-9 or x1 > ex1 + 1e-9 or y1 > ey1 + 1e-9:
                raise invalid(name, "corridor", f"inside the terrain extent {self.terrain.bounds}"
                              " [m]", f"bounds {tuple(round(v, 2) for v in (x0, y0, x1, y1))}")
        return line

    def _edge_costs(self, lines: list[LineString]) -> tuple[list[float], list[float]]:
        """Travel costs [m of level walking] of every centre line, forwards and backwards."""
        lengths = [line.length for line in lines]
        if self.terrain is None or not lines:
            return lengths, lengths
        pts = [np.asarray(line.coords) for line in lines]
        profiles = self.terrain.profiles(pts + [p[::-1] for p in pts])
        costs = []
        for k, (s, z) in enumerate(profiles):
            c = self.corridors[k % len(lines)]
            a, b = (c.a, c.b) if k < len(lines) else (c.b, c.a)
            costs.append(self._profile_cost(s, z, lengths[k % len(lines)],
                                            f"RouteGraph.edges[{a!r}->{b!r}]"))
        return costs[:len(lines)], costs[len(lines):]

    def _profile_cost(self, s: np.ndarray, z: np.ndarray, length: float, name: str) -> float:
        """Travel cost [m] of one ground profile (s, z) [m] of horizontal ``length`` [m]."""
        ds, dz = np.diff(s), np.diff(z)
        jump = ds <= 1e-12
        if jump.any() and np.abs(dz[jump]).max() > self.costs.max_step:
            k = np.flatnonzero(jump & (np.abs(dz) > self.costs.max_step))[0]
            raise invalid(name, "corridor", f"free of vertical steps above "
                          f"{self.costs.max_step} m", f"{dz[k]:+.3f} m at s = {s[k]:.3f} m")
        run = ~jump
        grade = dz[run] / ds[run]
        cost = np.sum(ds[run] * _slope_factor(grade, self.costs.tobler))
        up = np.clip(dz[jump], 0, None).sum()
        down = np.clip(-dz[jump], 0, None).sum()
        return float(max(cost, length) + self.costs.climb * up + self.costs.descent * down)

    @classmethod
    def from_graphml(cls, path, terrain=None, costs: RouteCosts = RouteCosts(),
                     obstacles=()) -> RouteGraph:
        """Read places and corridors from GraphML written by :meth:`to_graphml`, OSMnx
        (``ox.save_graphml`` of a projected graph) or any tool: node attributes ``x``, ``y``
        [m]; optional edge attributes ``width`` [m] (default :data:`GRAPHML_WIDTH`),
        ``geometry`` and node ``area`` as WKT, ``oneway`` (true/false, also as the strings
        OSMnx writes). A pair of opposite edges (a two-way street) is one corridor; of
        parallel edges the first is kept."""
        path = existing_file(path)
        try:
            g = nx.read_graphml(path)
        except Exception as exc:  # noqa: BLE001 - parser errors of several kinds
            raise invalid("GraphML", "file", "valid GraphML", f"{path}: {exc}") from exc
        if g.number_of_nodes() > MAX_ROUTE_NODES:
            raise invalid("GraphML", "nodes", f"at most {MAX_ROUTE_NODES:,}", g.number_of_nodes())
        places, corridors, seen = [], [], set()
        for n, d in g.nodes(data=True):
            if "x" not in d or "y" not in d:
                raise invalid(f"GraphML.nodes[{n!r}]", "x/y", "present [m]", sorted(d))
            area = shapely.from_wkt(d["area"]) if d.get("area") else None
            places.append(Place(str(n), _graphml_float(d["x"], f"GraphML.nodes[{n!r}]", "x"),
                                _graphml_float(d["y"], f"GraphML.nodes[{n!r}]", "y"), area))
        for a, b, d in g.edges(data=True):
            owner = f"GraphML.edges[{a!r}->{b!r}]"
            if frozenset((a, b)) in seen:
                continue
            seen.add(frozenset((a, b)))
            via = ()
            if d.get("geometry"):
                via = tuple(map(tuple, shapely.get_coordinates(shapely.from_wkt(d["geometry"]))
                                [1:-1]))
            width = _graphml_float(d.get("width", GRAPHML_WIDTH), owner, "width")
            oneway = _graphml_bool(d.get("oneway", False), owner, "oneway") and \
                not g.has_edge(b, a)
            corridors.append(Corridor(str(a), str(b), width, via, oneway))
        return cls(places, corridors, terrain, costs, obstacles)

    def to_graphml(self, path) -> None:
        """Write places and corridors (one edge per corridor) as GraphML."""
        g = nx.DiGraph()
        for p in self.places.values():
            g.add_node(p.name, x=p.x, y=p.y, area=p.area.wkt if p.area is not None else "")
        for c in self.corridors:
            line = self.graph.edges[c.a, c.b]["geometry"]
            g.add_edge(c.a, c.b, width=c.width, oneway=c.oneway, geometry=line.wkt)
        nx.write_graphml(g, path)

    def with_closed(self, walls: dict) -> RouteGraph:
        """This graph with the corridors in ``walls`` closed: each key, a frozenset of the
        corridor's two nodes, maps to the wall (shapely polygon [m]) that blocks it. Their
        edges leave the routing graph (both directions) and the walls are cut out of the
        walkable area; the corridors' costs and geometry are shared, not recomputed. No
        walls: this graph (``self``, with every corridor open)."""
        if not walls:
            return self
        family = self.__dict__.setdefault("_family", [self])  # the graphs of one layout
        new = copy.copy(self)
        for cached in ("walkable_area", "_walkable_tolerant", "_inner", "_corner_legs",
                       "_corner_ok"):
            new.__dict__.pop(cached, None)
        family.append(new)  # its visibility legs are re-checked only near the change
        new._fields, new._paths = {}, {}
        new.graph = self.layout.copy(as_view=False)
        new.graph.remove_edges_from([(u, v) for u, v in self.layout.edges
                                     if frozenset((u, v)) in walls])
        base = [] if self._base_obstacles is None else [self._base_obstacles]
        new.obstacles = shapely.union_all(base + list(walls.values())) if base or walls \
            else None
        return new

    # -- geometry --

    def node_xy(self, name: str) -> np.ndarray:
        """Position (2,) [m] of node ``name``."""
        self._check_node(name, "node")
        p = self.places[name]
        return np.array([p.x, p.y])

    def node_area(self, name: str) -> Polygon:
        """Where agents may stand at node ``name``: its area polygon, or else a disc of the
        widest incident corridor's half width (at least 0.5 m) [m]."""
        self._check_node(name, "node")
        p = self.places[name]
        if p.area is not None:
            return p.area
        widths = [d["width"] for *_, d in self.layout.in_edges(name, data=True)]
        widths += [d["width"] for *_, d in self.layout.out_edges(name, data=True)]
        return Point(p.x, p.y).buffer(max([0.5] + [w / 2 for w in widths]))

    @functools.cached_property
    def walkable_area(self):
        """Union of the corridors (centre lines buffered by half their width) and the node
        areas, as one shapely geometry [m]; on a terrain, minus the ground beyond every
        vertical change higher than ``costs.max_step`` (walls, tall obstacles): the
        corridors are cut along such edges and only the pieces that carry a corridor centre
        line or a node are kept."""
        parts = [d["geometry"].buffer(d["width"] / 2) for *_, d in self.layout.edges(data=True)]
        parts += [self.node_area(n) for n in self.layout.nodes]
        geom = shapely.union_all(parts)
        if self.terrain is not None:
            walls = self.terrain.steps(self.costs.max_step)
            if len(walls):
                cut = shapely.union_all(shapely.linestrings(walls)).buffer(
                    _WALL_HALF_THICKNESS, cap_style="flat")
                pieces = shapely.get_parts(geom.difference(cut))
                carriers = shapely.union_all(
                    [d["geometry"] for *_, d in self.layout.edges(data=True)]
                    + [Point(p.x, p.y) for p in self.places.values()])
                geom = shapely.union_all(pieces[shapely.intersects(pieces, carriers)])
        if self.obstacles is not None:
            geom = geom.difference(self.obstacles)
        shapely.prepare(geom)
        return geom

    @functools.cached_property
    def _walkable_tolerant(self):
        """:attr:`walkable_area` grown by 1 nm, prepared (covers a path along its edge)."""
        geom = self.walkable_area.buffer(1e-9)
        shapely.prepare(geom)
        return geom

    def sees(self, a, b) -> bool:
        """True when the straight segment from ``a`` to ``b`` (2,) [m] lies inside the
        walkable area."""
        return bool(self._walkable_tolerant.covers(LineString([tuple(a), tuple(b)])))

    def sees_all(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(n,) bool: :meth:`sees` for each segment from ``a`` (n, 2) to ``b`` (n, 2) [m],
        in one vectorised shapely call."""
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if not len(a):
            return np.zeros(0, dtype=bool)
        return shapely.covers(self._walkable_tolerant, shapely.linestrings(np.stack([a, b], 1)))

    @functools.cached_property
    def _inner(self):
        """The walkable area shrunk by 0.25 m (simplified to 2 cm, grown by 1 µm,
        prepared) and its corners (k, 2) [m]: where shortest walks keep a body off the
        walls, and their turning points."""
        inner = self.walkable_area.buffer(-0.25, quad_segs=2).simplify(0.02)
        rings = shapely.get_rings(shapely.get_parts(inner))
        corners = np.unique(np.round(shapely.get_coordinates(rings), 9), axis=0)
        self._inner_edges = _ring_edges(rings)
        inner = inner.buffer(1e-6)
        shapely.prepare(inner)
        return inner, corners

    @functools.cached_property
    def _corner_ok(self) -> np.ndarray:
        """For every pair i < j of the corners of :attr:`_inner` (``np.triu_indices`` order):
        True when the segment between them stays inside it (computed once). When another
        graph of the same layout (this one and those :meth:`with_closed` made from it:
        other doors shut) has them, only the pairs that involve a corner it lacks or whose
        segment comes near an edge where the two shrunk areas differ are checked; every
        other pair keeps its answer, which is then the same (a segment inside the one area
        that misses their difference is inside the other, and one that leaves it there
        leaves the other too)."""
        inner, corners = self._inner
        i, j = np.triu_indices(len(corners), 1)
        base = next((g for g in getattr(self, "_family", ())
                     if g is not self and "_corner_ok" in g.__dict__), None)
        if base is None:
            return shapely.covers(inner, shapely.linestrings(
                np.stack([corners[i], corners[j]], axis=1)))
        _, old_corners = base._inner
        old_ok, n_old = base._corner_ok, len(old_corners)
        index = {tuple(c): k for k, c in enumerate(old_corners)}
        at = np.array([index.get(tuple(c), -1) for c in corners])  # setup: one per corner
        oi, oj = np.minimum(at[i], at[j]), np.maximum(at[i], at[j])
        kept = (oi >= 0) & (oj >= 0)
        pair = oi * n_old - oi * (oi + 1) // 2 + (oj - oi - 1)
        ok = np.zeros(len(i), bool)
        ok[kept] = old_ok[pair[kept]]
        # where the areas differ is bounded by the ring edges only one of them has (a
        # segment between kept corners can reach it only across such an edge)
        check = ~kept
        a, b = corners[i], corners[j]
        edges = np.array(sorted(base._inner_edges ^ self._inner_edges)).reshape(-1, 2, 2)
        if len(edges):  # bounding boxes of (pair, changed edge) first, then exact
            lo, hi = np.minimum(a, b), np.maximum(a, b)
            e_lo, e_hi = edges.min(axis=1) - 1e-5, edges.max(axis=1) + 1e-5
            p, e = np.nonzero(np.all((lo[:, None] <= e_hi[None]) & (hi[:, None] >= e_lo[None]),
                                     axis=2) & kept[:, None])
            near = _segments_near(a[p], b[p], edges[e, 0], edges[e, 1], 1e-5)
            check[p[near]] = True
        seg = shapely.linestrings(np.stack([a[check], b[check]], axis=1))
        ok[check] = shapely.covers(inner, seg)
        return ok

    @functools.cached_property
    def _corner_legs(self) -> list[tuple[int, int, float]]:
        """Visibility legs (i, j, length [m]) between the corners of :attr:`_inner` that stay
        inside it, indexed from 2 as in :meth:`shortest_walk` (:attr:`_corner_ok`)."""
        inner, corners = self._inner
        i, j = np.triu_indices(len(corners), 1)
        ok = self._corner_ok
        length = np.linalg.norm(corners[i] - corners[j], axis=1)
        return list(zip((i[ok] + 2).tolist(), (j[ok] + 2).tolist(), length[ok].tolist(),
                        strict=True))

    def shortest_walk(self, a, b) -> np.ndarray:
        """Shortest polyline (k, 2) [m] from ``a`` to ``b`` (2,) [m] inside the walkable
        area: the straight segment if it lies inside, else Dijkstra on the visibility
        graph of the two points and the corners of the area shrunk by 0.25 m, its legs
        0.25 m off the walls (Lozano-Pérez & Wesley 1979); the straight segment if no
        such path exists."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        if self.sees(a, b):
            return np.stack([a, b])
        inner, corners = self._inner
        pts = np.vstack([a, b, corners])
        # legs from a or b (which may stand nearer a wall) may run in the walkable area;
        # the legs between corners (in the shrunk area) are the same for every walk
        i = np.repeat([0, 1], [len(pts) - 1, len(pts) - 2])
        j = np.concatenate([np.arange(1, len(pts)), np.arange(2, len(pts))])
        seg = shapely.linestrings(np.stack([pts[i], pts[j]], axis=1))
        ok = shapely.covers(inner, seg) | shapely.covers(self._walkable_tolerant, seg)
        g = nx.Graph()
        length = np.linalg.norm(pts[i] - pts[j], axis=1)
        g.add_weighted_edges_from(zip(i[ok], j[ok], length[ok], strict=True))
        g.add_weighted_edges_from(self._corner_legs)
        try:
            return pts[nx.shortest_path(g, 0, 1, weight="weight")]
        except (nx.NetworkXNoPath, nx.NodeNotFound):
            return np.stack([a, b])

    # -- routing --

    def _check_node(self, name, field_name: str) -> None:
        if name not in self.places:
            raise invalid("RouteGraph", field_name, f"one of {sorted(self.places)}", name)

    def distances_to(self, dest: str) -> dict[str, float]:
        """Travel cost [m] from every node that can reach ``dest`` (cached per destination)."""
        return self._field(dest)[0]

    def _field(self, dest: str):
        self._check_node(dest, "destination")
        if dest not in self._fields:
            dist, paths = nx.single_source_dijkstra(self.graph.reverse(copy=False), dest,
                                                    weight="cost")
            self._fields[dest] = (dist, paths)
        return self._fields[dest]

    def route(self, a: str, b: str) -> list[str]:
        """Cheapest node sequence from ``a`` to ``b``; raises
        :class:`~crowdwalk.errors.InfeasibleError` if ``b`` cannot be reached."""
        self._check_node(a, "origin")
        dist, paths = self._field(b)
        if a not in dist:
            raise InfeasibleError(f"RouteGraph: no route from {a!r} to {b!r} "
                                  "(check one-way corridors and disconnected parts).")
        return list(reversed(paths[a]))

    def route_cost(self, a: str, b: str) -> float:
        """Travel cost [m] of the cheapest route from ``a`` to ``b``."""
        self.route(a, b)
        return float(self.distances_to(b)[a])

    def raw_path(self, nodes: list[str]) -> np.ndarray:
        """Centre-line polyline (k, 2) [m] through a node sequence."""
        if len(nodes) == 1:
            return self.node_xy(nodes[0])[None, :]
        pts = [np.asarray(self.graph.edges[u, v]["geometry"].coords) for u, v in
               zip(nodes[:-1], nodes[1:], strict=True)]
        return np.concatenate([pts[0]] + [p[1:] for p in pts[1:]])

    def path(self, a: str, b: str, start=None, radius: float | None = None) -> np.ndarray:
        """Smooth polyline (k, 2) [m] from ``a`` (or from ``start`` (2,) [m]) to ``b`` along
        the cheapest route, inside the walkable area.

        Corners are rounded by quadratic Bézier arcs cut back by at most ``radius`` [m]
        (default: half the narrower adjacent corridor width) and half of each adjacent leg;
        an arc that would leave the walkable area is shrunk until it stays inside.
        """
        nodes = self.route(a, b)
        key = (a, b, None if start is None else tuple(np.round(start, 9)), radius)
        if key not in self._paths:
            raw = self.raw_path(nodes)
            if start is not None:
                raw = np.vstack([np.asarray(start, float)[None, :], raw[1:] if len(raw) > 1
                                 else raw])
            raw = self._around_obstacles(raw)
            widths = [self.graph.edges[u, v]["width"] for u, v in
                      zip(nodes[:-1], nodes[1:], strict=True)]
            self._paths[key] = self._round_corners(raw, radius, min(widths, default=1.0))
        return self._paths[key].copy()

    def _around_obstacles(self, raw: np.ndarray, clear: float = 0.35) -> np.ndarray:
        """``raw`` (k, 2) [m] with every leg that passes within ``clear`` [m] of an obstacle
        replaced by the shortest path around it: Dijkstra on the visibility graph of the
        leg's ends and the corners of the obstacles grown by ``clear`` (Lozano-Pérez &
        Wesley 1979), legs kept inside the walkable area."""
        if self.obstacles is None:
            return raw
        blocked = self.obstacles.buffer(clear - 1e-3)
        shapely.prepare(blocked)
        legs = shapely.linestrings(np.stack([raw[:-1], raw[1:]], axis=1))
        hit = shapely.intersects(blocked, legs)
        if not hit.any():
            return raw
        corners = shapely.get_coordinates(shapely.get_exterior_ring(shapely.get_parts(
            self.obstacles.buffer(clear, quad_segs=2, join_style="mitre"))))
        area = self._walkable_tolerant
        out = [raw[0]]
        for k in range(len(raw) - 1):
            if not hit[k]:
                out.append(raw[k + 1])
                continue
            pts = np.vstack([raw[k], raw[k + 1], corners])
            pts = pts[np.r_[True, True, shapely.covers(area, shapely.points(pts[2:]))]]
            i, j = np.triu_indices(len(pts), 1)
            seg = shapely.linestrings(np.stack([pts[i], pts[j]], axis=1))
            ok = ~shapely.intersects(blocked, seg) & shapely.covers(area, seg)
            g = nx.Graph()
            length = np.linalg.norm(pts[i] - pts[j], axis=1)
            g.add_weighted_edges_from(zip(i[ok], j[ok], length[ok], strict=True))
            try:
                via = nx.shortest_path(g, 0, 1, weight="weight")
            except (nx.NetworkXNoPath, nx.NodeNotFound):
                via = [0, 1]  # no way round inside the walkable area: keep the leg
            out.extend(pts[via[1:]])
        return np.asarray(out)

    def _round_corners(self, raw: np.ndarray, radius, width: float) -> np.ndarray:
        keep = np.concatenate([[True], np.linalg.norm(np.diff(raw, axis=0), axis=1) > 1e-9])
        raw = raw[keep]
        if len(raw) < 3:
            return raw
        r_max = width / 2 if radius is None else float(radius)
        area = self._walkable_tolerant
        out = [raw[0]]
        t = np.linspace(0.0, 1.0, 9)[:, None]
        for i in range(1, len(raw) - 1):
            p0, v, p1 = raw[i - 1], raw[i], raw[i + 1]
            d_in, d_out = v - p0, p1 - v
            l_in, l_out = np.linalg.norm(d_in), np.linalg.norm(d_out)
            cosang = float(np.dot(d_in, d_out) / (l_in * l_out))
            if cosang > 1 - 1e-9:
                out.append(v)
                continue
            r = min(r_max, 0.5 * l_in, 0.5 * l_out)
            arc = None
            for _ in range(6):
                a_pt, b_pt = v - d_in / l_in * r, v + d_out / l_out * r
                cand = (1 - t) ** 2 * a_pt + 2 * (1 - t) * t * v + t**2 * b_pt
                if area.covers(LineString(np.vstack([out[-1], cand]))):
                    arc = cand
                    break
                r /= 2
            out.extend(arc if arc is not None else [v])
        out.append(raw[-1])
        return np.asarray(out)

    def __repr__(self) -> str:
        return (f"RouteGraph({self.graph.number_of_nodes()} nodes, {len(self.corridors)} "
                f"corridors, walkable {self.walkable_area.area:.1f} m²)")

