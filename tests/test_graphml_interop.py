"""GraphML from other tools: an OSMnx-style street graph (every attribute a string, as
``ox.save_graphml`` writes it; two-way streets as opposite edge pairs; no ``width``)."""

from __future__ import annotations

import networkx as nx
import pytest

from crowdwalk.errors import InputError
from crowdwalk.routes import GRAPHML_WIDTH, RouteGraph
from crowdwalk.terrain import Terrain


def _osmnx_style(path, **edge_extra) -> None:
    g = nx.MultiDiGraph(crs="EPSG:32633", simplified="True")
    for osmid, (x, y) in {101: (2.0, 2.0), 102: (30.0, 2.0), 103: (30.0, 20.0)}.items():
        g.add_node(str(osmid), osmid=str(osmid), x=str(x), y=str(y), street_count="2")
    two_way = dict(oneway="False", highway="footway", length="28.0", osmid="7")
    g.add_edge("101", "102", reversed="False", **two_way, **edge_extra)
    g.add_edge("102", "101", reversed="True", **two_way, **edge_extra)
    g.add_edge("102", "103", oneway="True", highway="path", length="18.0", osmid="8",
               reversed="False", geometry="LINESTRING (30 2, 31 11, 30 20)")
    nx.write_graphml(g, path)


def test_osmnx_style_graph_reads_and_round_trips(tmp_path):
    _osmnx_style(tmp_path / "osm.graphml")
    terrain = Terrain.flat((0, 0, 40, 25))
    routes = RouteGraph.from_graphml(tmp_path / "osm.graphml", terrain)
    assert len(routes.corridors) == 2  # the opposite pair is one two-way corridor
    assert routes.route("101", "103") == ["101", "102", "103"]
    assert routes.route("102", "101") == ["102", "101"]  # "False" is not one-way
    with pytest.raises(Exception, match="no route"):
        routes.route("103", "102")  # "True" is
    assert {c.width for c in routes.corridors} == {GRAPHML_WIDTH}
    via = next(c.via for c in routes.corridors if c.b == "103")
    assert via == ((31.0, 11.0),)

    routes.to_graphml(tmp_path / "back.graphml")
    back = RouteGraph.from_graphml(tmp_path / "back.graphml", terrain)
    assert set(back.graph.edges) == set(routes.graph.edges)
    for u, v, d in routes.graph.edges(data=True):
        assert back.graph.edges[u, v]["cost"] == pytest.approx(d["cost"])
    assert back.walkable_area.symmetric_difference(routes.walkable_area).area < 1e-6


@pytest.mark.parametrize("extra,match", [
    ({"width": "['3', '4.5']"}, None),  # a merged way: the narrower width
    ({"width": "wide"}, "width must be a number"),
    ({"width": "nan"}, "width must be a finite number"),
    ({"oneway": "maybe"}, "oneway must be true or false"),
])
def test_osmnx_attribute_strings(tmp_path, extra, match):
    _osmnx_style(tmp_path / "g.graphml", **({} if "oneway" in extra else extra))
    if "oneway" in extra:
        g = nx.read_graphml(tmp_path / "g.graphml")
        for _, _, d in g.edges(data=True):
            d.update(extra)
        nx.write_graphml(g, tmp_path / "g.graphml")
    if match is None:
        routes = RouteGraph.from_graphml(tmp_path / "g.graphml", Terrain.flat((0, 0, 40, 25)))
        assert next(c.width for c in routes.corridors if "101" in (c.a, c.b)) == 3.0
    else:
        with pytest.raises(InputError, match=match):
            RouteGraph.from_graphml(tmp_path / "g.graphml", Terrain.flat((0, 0, 40, 25)))
