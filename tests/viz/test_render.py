"""Off-screen rendering: pictures show agents and footprints where the run says."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from crowdwalk.viz.camera import project_to_pixels
from crowdwalk.viz.headless import offscreen_plotter
from crowdwalk.viz.scene import Scene

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


def _orange(colours):
    """The palette's first colour (planner "best_first", 230/159/0) under any shading."""
    return (colours[:, 0] > colours[:, 2] + 60) & (colours[:, 1] > colours[:, 2] + 30)


def _blue(colours):
    """The palette's second colour (planner "fixed", 0/114/178) under any shading."""
    return (colours[:, 2] > colours[:, 0] + 25) & (colours[:, 2] > colours[:, 1] + 10)


@pytest.fixture
def planner_view(offscreen, crowd):
    poses, steps = crowd
    scene = Scene(poses=poses, footsteps=steps, walkable_area=AREA, color="planner")
    image, view, ctx = _render(scene, 1.2, size=(800, 500))
    yield image, view
    ctx.__exit__(None, None, None)


def test_projection_matches_vtk_world_to_display(planner_view):
    _, view = planner_view
    renderer = view.plotter.renderer
    points = np.array([[0.0, 0.0, 0.0], [5.0, 3.0, 1.0], [9.0, -1.0, 0.2]])
    got = project_to_pixels(view.plotter, points, view.renderer)
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
    *_, centres, _, _ = view.bodies.parts(positions)  # pelvis, chest, head
    hits = []
    for volume in range(3):
        colours, inside = _pixels(image, project_to_pixels(view.plotter, centres[:, volume],
                                                           view.renderer))
        assert inside.sum() >= 10
        # coloured by planner like their footprints: even ids plan (orange), odd do not (blue)
        best = (ids[inside] % 2 == 0)
        assert best.sum() >= 4 and (~best).sum() >= 4
        hits += [*_orange(colours[best]), *_blue(colours[~best])]
    assert np.mean(hits) >= 0.85  # a walker in front may hide a volume now and then
    # ground far from every agent and footprint stays light: the test can fail
    rng = np.random.default_rng(3)
    probe = np.column_stack([rng.uniform(-1.5, 11.5, 400), rng.uniform(-1.5, 8.5, 400)])
    joints_xy = positions[:, :, :2].reshape(-1, 2)
    far = (np.min(np.linalg.norm(probe[:, None] - joints_xy[None], axis=2), axis=1) > 1.5) & (
        np.min(np.linalg.norm(probe[:, None] - steps.position[None, :, :2], axis=2), axis=1) > 0.5
    )
    ground = np.column_stack([probe[far], np.zeros(far.sum())])
    colours, inside = _pixels(image, project_to_pixels(view.plotter, ground, view.renderer))
    assert inside.sum() >= 20
    assert np.mean((np.ptp(colours, axis=1) < 40) & (colours.mean(axis=1) > 150)) >= 0.9  # ground


def test_footprints_appear_in_planner_colours_until_now(planner_view, crowd):
    _, view = planner_view
    poses, steps = crowd
    view.actors["agents"].visibility = False  # nothing may hide a footprint
    view.plotter.render()
    image = view.plotter.screenshot(return_img=True)
    view.actors["agents"].visibility = True
    centre = steps.position[:, :2] + 0.07 * np.column_stack(
        [np.cos(steps.heading), np.sin(steps.heading)]
    )
    points = np.column_stack([centre, steps.position[:, 2] + 0.01])
    colours = np.full((len(steps), 3), -1)
    got, inside = _pixels(image, project_to_pixels(view.plotter, points, view.renderer))
    colours[inside] = got
    orange, blue = _orange(colours), _blue(colours)
    placed = inside & (steps.time <= 1.2)
    best, fixed = placed & (steps.planner == "best_first"), placed & (steps.planner == "fixed")
    assert best.sum() >= 10 and fixed.sum() >= 10
    # (a few pixels each from afar, and a later footprint may cover an earlier one)
    assert np.mean(orange[best]) >= 0.85
    assert np.mean(blue[fixed]) >= 0.85
    future = inside & (steps.time > 1.25)
    assert future.sum() >= 10
    assert np.mean(orange[future] | blue[future]) <= 0.1  # not placed yet, so not drawn


def test_key_bindings_drive_playback_colour_and_follow(planner_view, crowd):
    _, view = planner_view
    keys = view.key_bindings()
    legend = {name: view.overlay.actor(name) for name in view.overlay.names()
              if name.startswith("legend ")}
    labels = {name.split(" ", 2)[2]: actor for name, actor in legend.items()
              if name != "legend heading"}
    assert {"best_first", "fixed"} <= set(labels)
    orange = labels["best_first"].GetTextProperty().GetColor()
    assert orange[0] > 0.8 and orange[2] < 0.1  # the colour of best_first bodies and footprints
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
    before = np.array(view.bodies.mesh.point_data["rgb"])
    keys["c"]()
    assert view.color == "style"  # the synthetic run has no styles: one grey for all
    rgb = np.array(view.bodies.mesh.point_data["rgb"])
    assert not np.array_equal(rgb, before) and len(np.unique(rgb, axis=0)) == 1
    keys["c"]()
    assert view.color == "agent"
    assert len(np.unique(view.bodies.mesh.point_data["rgb"], axis=0)) >= 8
    assert not any(n.startswith("legend heading") for n in view.overlay.names())
    keys["c"]()
    assert view.color == "energy"
    assert "bar energy" in view.overlay.names()
    keys["f"]()
    assert view.follow == view.agent_ids[0]
    root = view.agent_root(view.follow)
    np.testing.assert_allclose(view.renderer.camera.focal_point, root, atol=1e-6)
    assert view.actors["highlight"].visibility
    assert "walker " in view.overlay.actor("info").GetInput()
    keys["Right"]()  # the camera moves with the agent
    np.testing.assert_allclose(view.renderer.camera.focal_point, view.agent_root(view.follow),
                               atol=1e-6)
    keys["f"]()
    assert view.follow is None and not view.actors["highlight"].visibility


def _intersects(a, b, margin=0.0):
    return a[0] < b[2] - margin and b[0] < a[2] - margin and a[1] < b[3] - margin \
        and b[1] < a[3] - margin


def test_overlays_cover_neither_the_scene_nor_each_other(offscreen, crowd):
    poses, steps = crowd
    for size in ((640, 480), (1280, 800), (1000, 400)):
        scene = Scene(poses=poses, footsteps=steps, walkable_area=AREA, follow=3,
                      title="a title long enough to need room", color="energy")
        image, view, ctx = _render(scene, 1.5, size=size)
        try:
            w, h = size
            x0, y0, x1, y1 = view.renderer.GetViewport()
            scene_px = np.array([x0 * w, y0 * h, x1 * w, y1 * h])
            boxes = view.overlay.boxes_px()
            assert {"title", "time", "info", "bar energy"} <= set(boxes)
            names = list(boxes)
            for i, name in enumerate(names):
                box = boxes[name]
                assert box[2] > box[0] and box[3] > box[1]
                assert 0 <= box[0] and box[2] <= w + 1 and 0 <= box[1] and box[3] <= h + 1, name
                assert not _intersects(box, scene_px), name
                for other in names[i + 1:]:
                    assert not _intersects(box, boxes[other], margin=1.0), (name, other)
        finally:
            ctx.__exit__(None, None, None)


def test_interactive_controls_install_on_a_plotter(planner_view):
    _, view = planner_view
    view.install_controls()
    view._slider.GetRepresentation().SetValue(1.0)
    view._slider.InvokeEvent("InteractionEvent")
    assert view.playback.time == pytest.approx(1.0)
    x0, y0, x1, y1 = view.renderer.GetViewport()
    point = view._slider.GetRepresentation().GetPoint1Coordinate().GetValue()
    assert point[1] > y1  # the slider sits in the header band, above the scene


def test_followed_agent_is_centred(offscreen, crowd):
    poses, steps = crowd
    scene = Scene(poses=poses, footsteps=steps, walkable_area=AREA, follow=5)
    image, view, ctx = _render(scene, 1.0, size=(320, 240))
    try:
        col, row = project_to_pixels(view.plotter, view.agent_root(5)[None], view.renderer)[0]
        x0, y0, x1, y1 = view.renderer.GetViewport()
        assert col == pytest.approx(320 * (x0 + x1) / 2, abs=2)
        assert row == pytest.approx(240 * (1 - (y0 + y1) / 2), abs=2)
    finally:
        ctx.__exit__(None, None, None)


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
