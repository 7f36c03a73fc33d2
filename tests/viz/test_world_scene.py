"""The world of the bundled quickstart scenario, before any run."""

from pathlib import Path

import numpy as np
import pytest

from crowdwalk.viz.camera import project_to_pixels
from crowdwalk.viz.headless import offscreen_plotter
from crowdwalk.viz.scene import Scene
from crowdwalk.viz.world_meshes import node_positions

QUICKSTART = Path(__file__).parents[2] / "scenarios" / "quickstart.yaml"


@pytest.fixture(scope="module")
def world_scene():
    if not QUICKSTART.exists():
        pytest.skip("scenarios/quickstart.yaml is not in this checkout")
    return Scene.from_scenario(QUICKSTART)


def test_world_scene_has_terrain_walkable_area_and_routes(offscreen, world_scene):
    with offscreen_plotter((480, 300)) as plotter:
        view = world_scene.attach(plotter)
        assert {"terrain", "terrain edges", "walkable area", "route edges", "route nodes"} <= set(
            plotter.actors
        )
        assert view.bodies is None and view.footprints is None
        terrain = plotter.actors["terrain"].mapper.dataset
        points = np.asarray(terrain.points)
        np.testing.assert_allclose(terrain.point_data["height"], points[:, 2])
        # every walkable (upward) face lies on the ground surface the terrain reports
        faces = terrain.compute_normals(cell_normals=True, point_normals=False)
        up = faces.cell_data["Normals"][:, 2] > 0.5
        centres = np.asarray(faces.cell_centers().points)[up]
        np.testing.assert_allclose(centres[:, 2], world_scene.terrain.height(centres[:, :2]),
                                   atol=1e-6)


def test_route_nodes_are_drawn_where_the_graph_puts_them(offscreen, world_scene):
    with offscreen_plotter((640, 400)) as plotter:
        view = world_scene.attach(plotter)
        view.set_time(0.0)
        plotter.render()
        image = plotter.screenshot(return_img=True).astype(int)
        pos = node_positions(world_scene.routes.graph)
        xy = np.array(list(pos.values()))
        points = np.column_stack([xy, world_scene.terrain.height(xy) + 0.05])
        px = np.round(project_to_pixels(plotter, points, view.renderer)).astype(int)
        def route_coloured(c):  # shaded #6a3d9a: purple, little green
            return (c[:, 2] > c[:, 1] + 40) & (c[:, 0] > c[:, 1] + 15)

        assert route_coloured(image[px[:, 1], px[:, 0]]).mean() >= 0.75
        # the same test on points shifted 1.5 m off the nodes mostly finds ground, not route
        off = np.round(project_to_pixels(plotter, points + [1.5, 1.5, 0.0], view.renderer)
                       ).astype(int)
        assert route_coloured(image[off[:, 1], off[:, 0]]).mean() <= 0.25


def test_route_edges_follow_the_corridors_centre_lines_through_their_via_points():
    from crowdwalk.scenario import load_scenario
    from crowdwalk.viz.world_meshes import route_lines
    from crowdwalk.world import build_world

    park = QUICKSTART.parent / "uneven_park.yaml"
    if not park.exists():
        pytest.skip("scenarios/uneven_park.yaml is not in this checkout")
    world = build_world(load_scenario(park))
    lines, _ = route_lines(world.routes.graph, world.terrain)
    drawn = np.asarray(lines.points)[:, :2]
    corridors = world.routes.corridors
    assert lines.n_lines == len(corridors)  # one line per corridor, not one per direction
    vias = np.array([p for c in corridors for p in c.via])
    assert len(vias) >= 3
    gap = np.min(np.linalg.norm(drawn[None] - vias[:, None], axis=2), axis=1)
    np.testing.assert_allclose(gap, 0.0, atol=1e-6)  # every bend is drawn
    # each drawn line is as long as its corridor's centre line, longer than the chord
    pos = {n: np.asarray(d["pos"] if "pos" in d else (d["x"], d["y"]), float)[:2]
           for n, d in world.routes.graph.nodes(data=True)}
    cells = [np.asarray(lines.get_cell(i).points)[:, :2] for i in range(lines.n_cells)]
    for c in (c for c in corridors if c.via):
        own = next(p for p in cells if {tuple(p[0]), tuple(p[-1])}
                   == {tuple(pos[c.a]), tuple(pos[c.b])})
        length = np.sum(np.linalg.norm(np.diff(own, axis=0), axis=1))
        centre_line = world.routes.graph.edges[c.a, c.b]["length"]
        assert length == pytest.approx(centre_line, rel=1e-9)
        assert length > np.linalg.norm(pos[c.a] - pos[c.b]) + 0.05  # not the chord
