"""Off-screen rendering: pictures show agents and footprints where the run says."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import shapely

from crowdwalk.viz.camera import project_to_pixels
from crowdwalk.viz.headless import offscreen_plotter
from crowdwalk.viz.scene import Scene

REFERENCE = Path(__file__).parent / "reference" / "synthetic_scene.png"
AREA = shapely.box(-2.0, -2.0, 12.0, 9.0)


def _render(scene, t, size=(640, 400)):
    """Render ``scene`` at time t; returns (image (h,w,3) uint8, view) with the plotter open."""
    ctx = offscreen_plotter(size)
    plotter = ctx.__enter__()
    view = scene.attach(plotter)
    view.set_time(t)
    plotter.render()
    image = plotter.screenshot(return_img=True)
    return image, view, ctx


def _pixels(image, points_px):
    """Colours (n,3) at pixel positions (n,2) [col,row]; None where outside the image."""
    h, w = image.shape[:2]
    c = np.round(points_px).astype(int)
    inside = (c[:, 0] >= 0) & (c[:, 0] < w) & (c[:, 1] >= 0) & (c[:, 1] < h)
    return image[c[inside, 1], c[inside, 0]].astype(int), inside


def _red(colours):
    """Set1's first colour (planner "best_first") under any shading."""
    return (colours[:, 0] > colours[:, 1] + 60) & (colours[:, 0] > colours[:, 2] + 60)


def _grey(colours):
    """Set1's last colour (planner "fixed") under any shading."""
    return np.ptp(colours, axis=1) < 25


@pytest.fixture
def planner_view(offscreen, crowd):
    poses, steps = crowd
    scene = Scene(poses=poses, footsteps=steps, walkable_area=AREA, color="planner")
    image, view, ctx = _render(scene, 1.2)
    yield image, view
    ctx.__exit__(None, None, None)


def test_projection_matches_vtk_world_to_display(planner_view):
    _, view = planner_view
    renderer = view.plotter.renderer
    points = np.array([[0.0, 0.0, 0.0], [5.0, 3.0, 1.0], [9.0, -1.0, 0.2]])
    got = project_to_pixels(view.plotter, points)
    h = view.plotter.window_size[1]
    for p, (col, row) in zip(points, got, strict=True):
        renderer.SetWorldPoint(*p, 1.0)
        renderer.WorldToDisplay()
        x, y, _ = renderer.GetDisplayPoint()
        assert col == pytest.approx(x, abs=0.5) and row == pytest.approx(h - y, abs=0.5)


def test_picture_is_not_blank(planner_view):
    image, _ = planner_view
    assert image.std() > 20
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 200


def test_agents_appear_where_the_run_puts_them(planner_view, crowd):
    image, view = planner_view
    poses, steps = crowd
    ids, positions = poses.at(12)  # t = 1.2 s at 10 fps
    assert np.array_equal(view.agent_ids, ids)
    heads = positions[:, 13] + [0.0, 0.0, view.figures.head_radius]
    colours, inside = _pixels(image, project_to_pixels(view.plotter, heads))
    assert inside.sum() >= 10
    # coloured by planner like their footprints: even ids plan (red), odd ids do not (grey)
    best = (ids[inside] % 2 == 0)
    assert best.sum() >= 4 and (~best).sum() >= 4
    assert np.mean(_red(colours[best])) >= 0.9
    assert np.mean(_grey(colours[~best]) & (colours[~best].mean(axis=1) < 170)) >= 0.9
    # ground far from every agent and footprint stays light: the test can fail
    rng = np.random.default_rng(3)
    probe = np.column_stack([rng.uniform(-1.5, 11.5, 400), rng.uniform(-1.5, 8.5, 400)])
    joints_xy = positions[:, :, :2].reshape(-1, 2)
    far = (np.min(np.linalg.norm(probe[:, None] - joints_xy[None], axis=2), axis=1) > 1.5) & (
        np.min(np.linalg.norm(probe[:, None] - steps.position[None, :, :2], axis=2), axis=1) > 0.5
    )
    ground = np.column_stack([probe[far], np.zeros(far.sum())])
    colours, inside = _pixels(image, project_to_pixels(view.plotter, ground))
    assert inside.sum() >= 20
    assert np.mean(colours.mean(axis=1) > 170) >= 0.9


def test_footprints_appear_in_planner_colours_until_now(planner_view, crowd):
    _, view = planner_view
    poses, steps = crowd
    view.plotter.actors["agents"].visibility = False  # nothing may hide a footprint
    view.plotter.render()
    image = view.plotter.screenshot(return_img=True)
    view.plotter.actors["agents"].visibility = True
    centre = steps.position[:, :2] + 0.07 * np.column_stack(
        [np.cos(steps.heading), np.sin(steps.heading)]
    )
    points = np.column_stack([centre, steps.position[:, 2] + 0.006])
    colours = np.full((len(steps), 3), -1)
    got, inside = _pixels(image, project_to_pixels(view.plotter, points))
    colours[inside] = got
    red = _red(colours)
    grey = _grey(colours) & (colours.mean(axis=1) < 200)
    placed = inside & (steps.time <= 1.2)
    best, fixed = placed & (steps.planner == "best_first"), placed & (steps.planner == "fixed")
    assert best.sum() >= 10 and fixed.sum() >= 10
    assert np.mean(red[best]) >= 0.9
    assert np.mean(grey[fixed]) >= 0.9
    future = inside & (steps.time > 1.25)
    assert future.sum() >= 10
    assert np.mean(red[future] | grey[future]) <= 0.1  # not placed yet, so not drawn


def test_key_bindings_drive_playback_colour_and_follow(planner_view, crowd):
    _, view = planner_view
    keys = view.key_bindings()
    legend = {name: view.plotter.actors[name] for name in view._legend_names}
    assert {"legend planner best_first", "legend planner fixed"} <= set(legend)
    red = legend["legend planner best_first"].GetTextProperty().GetColor()
    assert red[0] > 0.8 and red[1] < 0.3  # the colour of best_first figures and footprints
    t0 = view.playback.time
    keys["space"]()
    assert view.playback.playing
    view.tick(0.5)
    assert view.playback.time == pytest.approx(t0 + 0.5)
    keys["Right"]()
    assert not view.playback.playing
    assert view.playback.time == pytest.approx(t0 + 0.6)
    assert view.frame == 18
    keys["Up"]()
    assert view.playback.speed == 2.0
    keys["c"]()
    assert view.color == "agent"
    assert not any("planner" in name for name in view._legend_names)
    assert not any("planner" in name for name in view.plotter.actors if "legend" in name)
    assert view.plotter.actors["footprints"].mapper.array_name == "agent"
    assert view.plotter.actors["agents"].mapper.array_name == "value"
    keys["c"]()
    assert view.plotter.actors["footprints"].mapper.array_name == "energy"
    keys["f"]()
    assert view.follow == view.agent_ids[0]
    root = view.agent_root(view.follow)
    np.testing.assert_allclose(view.plotter.camera.focal_point, root, atol=1e-6)
    keys["Right"]()  # the camera moves with the agent
    np.testing.assert_allclose(view.plotter.camera.focal_point, view.agent_root(view.follow),
                               atol=1e-6)
    keys["f"]()
    assert view.follow is None


def test_interactive_controls_install_on_a_plotter(planner_view):
    _, view = planner_view
    view.install_controls()
    view._slider.GetRepresentation().SetValue(1.0)
    view._slider.InvokeEvent("InteractionEvent")
    assert view.playback.time == pytest.approx(1.0)


def test_followed_agent_is_centred(offscreen, crowd):
    poses, steps = crowd
    scene = Scene(poses=poses, footsteps=steps, walkable_area=AREA, follow=5)
    image, view, ctx = _render(scene, 1.0, size=(320, 240))
    try:
        col, row = project_to_pixels(view.plotter, view.agent_root(5)[None])[0]
        assert col == pytest.approx(160, abs=2) and row == pytest.approx(120, abs=2)
    finally:
        ctx.__exit__(None, None, None)


def test_image_matches_the_committed_reference(offscreen, crowd, tmp_path):
    poses, steps = crowd
    scene = Scene(poses=poses, footsteps=steps, walkable_area=AREA, title="reference")
    out = scene.render_png(tmp_path / "now.png", time=1.5, size=(320, 200))
    import imageio.v3 as iio

    image = iio.imread(out)[..., :3].astype(float)
    if os.environ.get("CROWDWALK_UPDATE_REFERENCE"):
        REFERENCE.parent.mkdir(exist_ok=True)
        REFERENCE.write_bytes(out.read_bytes())
        pytest.skip("reference image rewritten")
    reference = iio.imread(REFERENCE)[..., :3].astype(float)
    assert image.shape == reference.shape
    diff = np.abs(image - reference).max(axis=2)
    assert diff.mean() < 2.0
    assert np.mean(diff > 60) < 0.01
    # the comparison is sensitive: a later instant differs clearly
    later = iio.imread(scene.render_png(tmp_path / "later.png", time=2.5, size=(320, 200)))
    assert np.mean(np.abs(later[..., :3] - reference).max(axis=2) > 60) > 0.01


def test_movies_have_one_frame_per_tick_and_show_motion(offscreen, crowd, tmp_path):
    import imageio.v3 as iio

    poses, steps = crowd
    scene = Scene(poses=poses, footsteps=steps, walkable_area=AREA)
    calls = []
    gif = scene.render_movie(tmp_path / "walk.gif", start=0.0, end=1.0, fps=5, size=(160, 100),
                             progress=lambda done, total: calls.append((done, total)))
    frames = iio.imread(gif, index=None)
    assert frames.shape[0] == 6 and frames.shape[1:3] == (100, 160)
    assert calls[-1] == (6, 6)
    assert np.abs(frames[0].astype(int) - frames[-1]).mean() > 1.0
    mp4 = scene.render_movie(tmp_path / "walk.mp4", start=0.0, end=1.0, fps=10,
                             size=(160, 96))
    import imageio.v2 as iio2

    with iio2.get_reader(mp4, format="FFMPEG") as reader:
        assert reader.count_frames() == 11
        first = reader.get_data(0)
    assert first.shape[:2] == (96, 160)


def test_show_wires_slider_keys_and_timer_into_the_window(offscreen, crowd, monkeypatch):
    import pyvista as pv

    import crowdwalk.viz.scene as scene_module

    shown = {}

    class Window(pv.Plotter):  # the interactive window, off-screen, never blocking
        def __init__(self, **kwargs):
            assert kwargs.pop("off_screen") is False  # a window even after off-screen renders
            super().__init__(off_screen=True, **kwargs)

        def show(self, *args, **kwargs):
            shown["plotter"] = self
            shown["keys"] = set(self.iren._key_press_event_callbacks)

    monkeypatch.setattr(scene_module.pv, "Plotter", Window)
    poses, steps = crowd
    Scene(poses=poses, footsteps=steps, walkable_area=AREA).show(time=0.5, size=(320, 200))
    assert {"space", "Right", "Left", "Up", "Down", "c", "f"} <= shown["keys"]
    assert shown["plotter"].widgets.slider_widgets
    shown["plotter"].close()
