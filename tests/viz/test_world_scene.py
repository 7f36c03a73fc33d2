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
        assert view.figures is None and view.footprints is None
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
        px = np.round(project_to_pixels(plotter, points)).astype(int)
        def route_coloured(c):  # shaded #d9480f: strong red, little green, almost no blue
            return (c[:, 0] > 120) & (c[:, 1] < 0.5 * c[:, 0]) & (c[:, 2] < 0.2 * c[:, 0])

        assert route_coloured(image[px[:, 1], px[:, 0]]).mean() >= 0.75
        # the same test on points shifted 1.5 m off the nodes mostly finds ground, not route
        off = np.round(project_to_pixels(plotter, points + [1.5, 1.5, 0.0])).astype(int)
        assert route_coloured(image[off[:, 1], off[:, 0]]).mean() <= 0.25
