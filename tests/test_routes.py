"""Route graphs: costs, distance fields, smooth paths inside the walkable area, errors."""

import math

import networkx as nx
import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist
from shapely.geometry import LineString, Point

from crowdwalk.errors import InfeasibleError, InputError
from crowdwalk.routes import Corridor, Place, RouteGraph, spawn_points
from crowdwalk.terrain import Block, Slope, StairFlight, Terrain

FAST = settings(max_examples=30, deadline=None)
EXTENT = (-50.0, -50.0, 50.0, 50.0)


HILLY = Terrain(EXTENT, 0.0, (
    Slope.ramp((-10, -10), 0.5, 30, 12, 0.0, 0.45),
    StairFlight((5, 5), 1.0, 8, 0.3, 0.12, 3),
    Block.box((20, 10), (6, 6), 0.3),
    Slope([(0, 20), (30, 20), (30, 26), (0, 26)], (0, 20), 0.0, math.pi / 2,
          math.tan(math.radians(-4))),
))


@st.composite
def graphs(draw, terrain=None):
    """A random connected graph of places on a jittered grid with random widths."""
    n = draw(st.integers(3, 8))
    rng = np.random.default_rng(draw(st.integers(0, 10_000)))
    grid = rng.permutation(25)[:n]
    xy = np.stack([grid % 5, grid // 5], 1) * 8.0 + rng.uniform(-2, 2, (n, 2))
    places = [Place(f"n{i}", *xy[i]) for i in range(n)]
    # a random spanning tree plus a few chords
    edges = {(int(rng.integers(0, i)), i) for i in range(1, n)}
    for _ in range(draw(st.integers(0, 4))):
        a, b = rng.choice(n, 2, replace=False)
        if (a, b) not in edges and (b, a) not in edges:
            edges.add((int(a), int(b)))
    corridors = []
    for a, b in sorted(edges):
        via = ()
        if rng.random() < 0.4:
            mid = (xy[a] + xy[b]) / 2 + rng.uniform(-3, 3, 2)
            via = (tuple(mid),)
        corridors.append(Corridor(f"n{a}", f"n{b}", float(rng.uniform(0.6, 4.0)), via))
    return RouteGraph(places, corridors, terrain or Terrain.flat(EXTENT)), n


@FAST
@given(g=st.one_of(graphs(), graphs(HILLY)), data=st.data())
def test_paths_stay_inside_walkable_area_and_cost_at_least_distance(g, data):
    routes, n = g
    a = f"n{data.draw(st.integers(0, n - 1))}"
    b = f"n{data.draw(st.integers(0, n - 1))}"
    path = routes.path(a, b)
    np.testing.assert_allclose(path[0], routes.node_xy(a))
    np.testing.assert_allclose(path[-1], routes.node_xy(b))
    if len(path) > 1:
        assert routes.walkable_area.buffer(1e-6).covers(LineString(path))
    straight = float(np.linalg.norm(routes.node_xy(a) - routes.node_xy(b)))
    assert routes.route_cost(a, b) >= straight - 1e-9
    nodes = routes.route(a, b)
    assert routes.route_cost(a, b) == pytest.approx(
        sum(routes.graph.edges[u, v]["cost"] for u, v in zip(nodes[:-1], nodes[1:],
                                                                strict=True)))


@FAST
@given(g=graphs())
def test_distance_field_matches_dijkstra_and_is_cached(g):
    routes, n = g
    field = routes.distances_to("n0")
    assert routes.distances_to("n0") is field
    expect = nx.single_source_dijkstra_path_length(routes.graph.reverse(), "n0", weight="cost")
    assert field.keys() == expect.keys()
    for k, v in expect.items():
        assert field[k] == pytest.approx(v)


def stair_world(oneway=False):
    ter = Terrain(EXTENT, 0.0, (
        StairFlight((0.0, 0.0), 0.0, 3.0, 0.3, 0.17, 6),
        Block([(1.8, -5), (10, -5), (10, 5), (1.8, 5)], 1.02),
        Slope.ramp((0.0, 10.0), 0.0, 10.0, 2.0, 0.0, 1.0),
    ))
    places = [Place("low", -5, 0), Place("high", 6, 0), Place("ramp_low", -5, 10),
              Place("ramp_high", 10, 10)]
    corridors = [Corridor("low", "high", 2.5, oneway=oneway),
                 Corridor("ramp_low", "ramp_high", 1.5, via=((0, 10),)),
                 Corridor("low", "ramp_low", 2.0)]
    return RouteGraph(places, corridors, ter)


def test_stairs_and_slopes_cost_more_than_level():
    routes = stair_world()
    e = routes.graph.edges
    up, down = e["low", "high"], e["high", "low"]
    assert up["cost"] == pytest.approx(11 + 2.1 * 1.02)
    assert down["cost"] == pytest.approx(11 + 1.6 * 1.02)
    ramp_up, ramp_down = e["ramp_low", "ramp_high"], e["ramp_high", "ramp_low"]
    assert ramp_up["cost"] == pytest.approx(5 + 10 * math.exp(3.5 * 0.1))
    assert ramp_down["cost"] == pytest.approx(15.0)  # a gentle descent costs its length
    assert e["low", "ramp_low"]["cost"] == pytest.approx(10.0)


def test_oneway_and_unreachable():
    routes = stair_world(oneway=True)
    assert routes.route("low", "high") == ["low", "high"]
    with pytest.raises(InfeasibleError, match="no route from 'high' to 'low'"):
        routes.route("high", "low")


def test_graphml_round_trip(tmp_path):
    routes = stair_world(oneway=True)
    path = tmp_path / "g.graphml"
    routes.to_graphml(path)
    back = RouteGraph.from_graphml(path, routes.terrain)
    assert set(back.graph.edges) == set(routes.graph.edges)
    for u, v, d in routes.graph.edges(data=True):
        assert back.graph.edges[u, v]["cost"] == pytest.approx(d["cost"])
        assert back.graph.edges[u, v]["width"] == d["width"]
    assert back.walkable_area.symmetric_difference(routes.walkable_area).area < 1e-6


def test_walkable_area_is_corridors_and_node_areas():
    area = [(-8, -2), (-4, -2), (-4, 2), (-8, 2)]
    routes = RouteGraph([Place("a", -6, 0, area), Place("b", 6, 0)],
                        [Corridor("a", "b", 2.0)], Terrain.flat(EXTENT))
    w = routes.walkable_area
    assert w.covers(shapely.Polygon(area))
    assert w.covers(Point(0, 0.99)) and not w.covers(Point(0, 1.01))
    assert routes.node_area("b").area == pytest.approx(math.pi, rel=0.02)


def test_corners_are_rounded_inside_narrow_corridors():
    places = [Place("a", 0, 0), Place("b", 10, 0), Place("c", 10, 10)]
    routes = RouteGraph(places, [Corridor("a", "b", 1.0), Corridor("b", "c", 1.0)])
    path = routes.path("a", "c")
    assert len(path) > 3  # the corner became an arc
    assert not np.any(np.all(np.isclose(path, [10, 0]), axis=1))
    assert routes.walkable_area.buffer(1e-9).covers(LineString(path))
    start = routes.path("a", "c", start=(0.2, 0.3))
    np.testing.assert_allclose(start[0], [0.2, 0.3])


@FAST
@given(n=st.integers(1, 40), spacing=st.floats(0.2, 0.8), seed=st.integers(0, 1000))
def test_spawn_points_inside_and_apart(n, spacing, seed):
    area = shapely.box(0, 0, 6, 4)
    try:
        pts = spawn_points(area, n, np.random.default_rng(seed), spacing)
    except InputError:
        assert n * spacing**2 > 0.5 * area.area  # only refuses when the area is crowded
        return
    assert pts.shape == (n, 2)
    assert shapely.contains_xy(area, pts[:, 0], pts[:, 1]).all()
    if n > 1:
        assert pdist(pts).min() >= spacing
    again = spawn_points(area, n, np.random.default_rng(seed), spacing)
    np.testing.assert_array_equal(pts, again)


def test_spawn_points_refuses_overfull_area():
    with pytest.raises(InputError, match=r"spawn_points\.n must be at most about \d+"):
        spawn_points(shapely.box(0, 0, 1, 1), 50, np.random.default_rng(0), 0.5)


def test_error_messages():
    ter = Terrain.flat((0, 0, 20, 20))
    a, b = Place("a", 2, 2), Place("b", 8, 2)
    with pytest.raises(InputError, match=r"Corridor\['a'->'b'\]\.width must be > 0 \[m\]; got 0"):
        Corridor("a", "b", 0.0)
    with pytest.raises(InputError, match=r"width must be > 0 \[m\]; got -1"):
        Corridor("a", "b", -1.0)
    with pytest.raises(InputError, match=r"node must be one of \['a', 'b'\]; got 'c'"):
        RouteGraph([a, b], [Corridor("a", "c", 1.0)], ter)
    routes = RouteGraph([a, b], [Corridor("a", "b", 1.0)], ter)
    with pytest.raises(InputError, match=r"RouteGraph\.destination must be one of"):
        routes.route("a", "nowhere")
    with pytest.raises(InputError, match=r"RouteGraph\.origin must be one of"):
        routes.route("nowhere", "a")
    with pytest.raises(InputError, match=r"corridor must be inside the terrain extent"):
        RouteGraph([a, Place("far", 19.5, 2)], [Corridor("a", "far", 2.0)], ter)
    with pytest.raises(InputError, match=r"length must be ≥ 0.05 m \(merge the two places\)"):
        RouteGraph([a, Place("near", 2.01, 2)], [Corridor("a", "near", 1.0)], ter)
    with pytest.raises(InputError, match=r"nodes must be joined by one corridor only"):
        RouteGraph([a, b], [Corridor("a", "b", 1.0), Corridor("b", "a", 1.0)], ter)
    wall = Terrain((0, 0, 20, 20), 0.0, (Block.box((5, 2), (1, 4), 1.0),))
    with pytest.raises(InputError, match=r"free of vertical steps above 0.5 m; got '\+1.000 m"):
        RouteGraph([a, b], [Corridor("a", "b", 1.0)], wall)
    with pytest.raises(InputError, match=r"RouteGraph\.nodes\['out'\]\.xy must be inside"):
        RouteGraph([a, Place("out", 30, 2)], [], ter)
    with pytest.raises(InputError, match=r"Place\['p'\]\.area must be a polygon around its node"):
        Place("p", 0, 0, [(1, 1), (2, 1), (2, 2)])
    with pytest.raises(InputError, match=r"RouteGraph\.nodes\['e'\]\.area must be inside"):
        RouteGraph([Place("e", 1, 1, [(-1, 0), (2, 0), (2, 2)])], [], ter)


def test_walkable_area_excludes_tall_obstacles_but_not_curbs():
    ter = Terrain(EXTENT, 0.0, (Block.box((5, 1.5), (1, 1), 1.0),
                                Block.box((8, 1.5), (1, 1), 0.15)))
    routes = RouteGraph([Place("a", 0, 0), Place("b", 12, 0)], [Corridor("a", "b", 4.0)], ter)
    w = routes.walkable_area
    assert not w.intersects(Point(5, 1.5)) and not w.intersects(Point(5, 1.95))
    assert w.covers(Point(5, -1.5)) and w.covers(Point(8, 1.5)) and w.covers(Point(5.6, 1.5))
    assert w.area == pytest.approx(routes.graph.edges["a", "b"]["geometry"].buffer(2).area - 1.0,
                                   abs=0.02)


@pytest.mark.parametrize("shut", [[("east_door", "east")],
                                  [("east_door", "east"), ("north_door", "office")],
                                  [("west_door", "west")]])
def test_graphs_with_doors_shut_recheck_only_the_legs_near_the_doors(shut):
    """The corner-to-corner visibility legs of a graph with doors shut (``with_closed``)
    and of the open one, each derived from the other's near the doors only: the same
    legs as computed from scratch."""
    from pathlib import Path

    from crowdwalk.crowd.events import door_wall
    from crowdwalk.scenario import load_scenario
    from crowdwalk.world import build_world

    scenario = load_scenario(Path(__file__).parents[1] / "scenarios" / "events.yaml")
    reference = build_world(scenario).routes._corner_legs  # open, from scratch
    graph = build_world(scenario).routes
    walls = {frozenset(c): door_wall(graph, c, 0.5) for c in shut}
    closed = graph.with_closed(walls)
    shut_legs = closed._corner_legs  # nothing to derive from yet: from scratch
    assert set(reference) - set(shut_legs)  # the doors cut legs
    assert graph._corner_legs == reference  # open, derived from the closed graph
    assert graph.with_closed(walls)._corner_legs == shut_legs  # closed, from the open one


def test_sees_all_answers_as_sees_one_segment_at_a_time():
    g = stair_world()
    x0, y0, x1, y1 = g.walkable_area.bounds
    rng = np.random.default_rng(3)
    a = rng.uniform((x0 - 1, y0 - 1), (x1 + 1, y1 + 1), (300, 2))
    b = rng.uniform((x0 - 1, y0 - 1), (x1 + 1, y1 + 1), (300, 2))
    want = np.array([g.sees(p, q) for p, q in zip(a, b, strict=True)])
    assert 0 < want.sum() < want.size  # both answers occur
    assert np.array_equal(g.sees_all(a, b), want)
    assert g.sees_all(np.zeros((0, 2)), np.zeros((0, 2))).shape == (0,)
