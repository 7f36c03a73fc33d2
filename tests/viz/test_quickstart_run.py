"""The viewer on real runs of the bundled quickstart scenario (4 s, planned and unplanned):
bodies where the run puts them, a committed reference picture, planned and unplanned side
by side.

The reference picture is rendered from a run folder stored with the tests
(``data/quickstart_4s_best_first.zip``: ``crowdwalk run scenarios/quickstart.yaml
--planner best_first --duration 4``), so a change of the simulation does not move it; the
other tests run the simulation of this checkout."""

import os
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.viz.camera import project_to_pixels
from crowdwalk.viz.headless import offscreen_plotter
from crowdwalk.viz.scene import Scene, load_scenes, run_folders

REFERENCE = Path(__file__).parent / "reference" / "quickstart_4s_follow3.png"
STORED_RUN = Path(__file__).parent / "data" / "quickstart_4s_best_first.zip"


@pytest.fixture(scope="module")
def planned(compare_folder):
    return Scene.from_run(compare_folder / "best_first")


def test_every_body_is_drawn_where_the_run_puts_it(offscreen, planned, compare_folder):
    from crowdwalk.record import open_run

    t = 3.0
    with offscreen_plotter((800, 500)) as plotter:
        view = planned.attach(plotter)
        view.set_time(t)
        plotter.render()
        image = plotter.screenshot(return_img=True).astype(int)
        poses = open_run(compare_folder / "best_first").poses()
        record = poses.frame(poses.frames[np.searchsorted(poses.times, t + 1e-9) - 1])
        np.testing.assert_array_equal(view.agent_ids, record.ids)
        *_, centres, _, _ = view.bodies.parts(record.positions)
        chests = centres[:, 1]
        px = np.round(project_to_pixels(plotter, chests, view.renderer)).astype(int)
        x0, y0, x1, y1 = np.array(view.renderer.GetViewport()) * [800, 500, 800, 500]
        inside = (px[:, 0] >= x0) & (px[:, 0] < x1) & (px[:, 1] >= 500 - y1) & (
            px[:, 1] < 500 - y0)
        assert inside.sum() >= 0.9 * len(record.ids) > 5
        colours = image[px[inside, 1], px[inside, 0]]
        assert np.mean(np.ptp(colours, axis=1) > 60) >= 0.85  # coloured bodies, grey ground
        # a metre beside each chest, at ground level, is ground (low chroma)
        beside = np.round(project_to_pixels(plotter, chests - [0.0, 1.0, 1.3], view.renderer)
                          ).astype(int)
        colours = image[beside[inside, 1], beside[inside, 0]]
        assert np.mean(np.ptp(colours, axis=1) > 60) < 0.5


def test_image_matches_the_committed_reference(offscreen, tmp_path):
    import zipfile

    import imageio.v3 as iio

    with zipfile.ZipFile(STORED_RUN) as stored:
        stored.extractall(tmp_path / "run")
    scene = Scene.from_run(tmp_path / "run", follow=3)
    out = scene.render_png(tmp_path / "now.png", time=3.5, size=(480, 300))
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
    # the comparison is sensitive: half a second later differs clearly
    later = iio.imread(scene.render_png(tmp_path / "later.png", time=3.0, size=(480, 300)))
    assert np.mean(np.abs(later[..., :3] - reference).max(axis=2) > 60) > 0.01


def test_compare_folder_opens_side_by_side_linked(offscreen, compare_folder):
    assert [p.name for p in run_folders(compare_folder)] == ["best_first", "fixed"]
    scenes = load_scenes([compare_folder], follow=3)
    assert [s.title for s in scenes] == ["quickstart (best_first)", "quickstart (fixed)"]
    with offscreen_plotter((960, 400), columns=2) as plotter:
        lead = scenes[0].attach(plotter, scenes[1:])
        lead.set_time(3.0)  # walker 3 walks from 2.7 s (its spawn waits for room)
        other = lead.linked[0]
        assert other.renderer.GetActiveCamera() is lead.renderer.GetActiveCamera()
        assert other.playback.time == lead.playback.time or other._shown_time == 3.0
        # the same walker in both, each highlighted, both with its own info panel
        for view in (lead, other):
            assert view.actors["highlight"].visibility
            assert view.overlay.actor("info").GetInput().startswith("walker 3")
        assert "planner: best_first" in lead.overlay.actor("info").GetInput()
        assert "planner: fixed" in other.overlay.actor("info").GetInput()
        keys = lead.key_bindings()
        keys["Right"]()  # one key moves both
        assert lead._shown_time == other._shown_time == pytest.approx(3.1)
        keys["c"]()
        assert lead.color == other.color == "group"
        lx0, _, lx1, _ = lead.renderer.GetViewport()
        rx0, _, rx1, _ = other.renderer.GetViewport()
        assert lx1 <= 0.5 <= rx0  # side by side, each in its half


def test_render_two_runs_side_by_side_from_the_cli(offscreen, compare_folder, tmp_path):
    import imageio.v3 as iio

    out = tmp_path / "both.png"
    result = CliRunner().invoke(app, ["render", str(compare_folder / "best_first"),
                                      str(compare_folder / "fixed"), "--out", str(out),
                                      "--time", "3", "--size", "800x300", "--follow", "3"])
    assert result.exit_code == 0, result.output
    image = iio.imread(out)[..., :3].astype(int)
    left, right = image[:, :400], image[:, 400:]
    for half in (left, right):  # each half shows a scene with coloured bodies
        assert np.mean(np.ptp(half, axis=2) > 60) > 0.005
    gif = tmp_path / "both.gif"
    result = CliRunner().invoke(app, ["render", str(compare_folder), "--out", str(gif),
                                      "--start", "1", "--end", "1.4", "--fps", "5",
                                      "--size", "320x120"])
    assert result.exit_code == 0, result.output
    assert iio.imread(gif, index=None).shape[:3] == (3, 120, 320)
