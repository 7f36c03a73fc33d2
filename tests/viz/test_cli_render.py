"""``crowdwalk render`` / ``view`` and the run-folder path of the scene builder."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.record import open_run
from crowdwalk.viz.scene import Scene

runner = CliRunner()


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, crowd, write_run):
    return write_run(tmp_path_factory.mktemp("run") / "synthetic", *crowd)


def test_scene_from_run_reads_the_stored_poses_and_footsteps(run_dir, crowd):
    poses, steps = crowd
    scene = Scene.from_run(run_dir)
    assert scene.title == "synthetic"
    assert list(scene.poses.parents) == list(poses.parents)
    np.testing.assert_allclose(scene.poses.times, poses.times)
    ids, positions = scene.poses.at(7)
    np.testing.assert_array_equal(ids, poses.at(7)[0])
    np.testing.assert_allclose(positions, poses.at(7)[1], atol=1e-5)  # float32 blobs
    assert len(scene.footsteps) == len(steps)
    np.testing.assert_allclose(scene.footsteps.heading, steps.heading, atol=1e-5)
    assert scene.walkable_area.area == pytest.approx(14 * 11)
    assert scene.time_range == pytest.approx((0.0, 2.9))


def test_run_without_poses_shows_trajectory_poles(run_dir, tmp_path):
    import shutil

    bare = tmp_path / "bare"
    shutil.copytree(run_dir, bare)
    (bare / "poses.sqlite").unlink()
    scene = Scene.from_run(bare)
    ids, poles = scene.poses.at(3)
    assert poles.shape == (12, 4, 3)
    np.testing.assert_allclose(poles[:, 1, 2] - poles[:, 0, 2], 1.5)
    # the shoulder bar lies across the torso's facing (the trajectories' orientation)
    traj = open_run(bare).trajectories()
    rows = traj.frame == np.unique(traj.frame)[3]
    bar = poles[:, 2, :2] - poles[:, 3, :2]
    facing = np.column_stack([traj.ori_x[rows], traj.ori_y[rows]])
    np.testing.assert_allclose(np.einsum("ij,ij->i", bar, facing), 0.0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(bar, axis=1), 0.2)


def test_render_png_and_gif(offscreen, run_dir, tmp_path):
    import imageio.v3 as iio

    png = tmp_path / "frame.png"
    result = runner.invoke(app, ["render", str(run_dir), "--out", str(png), "--time", "1.0",
                                 "--size", "320x200", "--color", "planner"])
    assert result.exit_code == 0, result.output
    assert iio.imread(png).shape[:2] == (200, 320)
    gif = tmp_path / "walk.gif"
    result = runner.invoke(app, ["render", str(run_dir), "--out", str(gif), "--start", "0",
                                 "--end", "0.5", "--fps", "4", "--size", "160x100"])
    assert result.exit_code == 0, result.output
    assert iio.imread(gif, index=None).shape[0] == 3


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--out", "x.txt"], "render.out must be a .png, .gif or .mp4 file"),
        (["--out", "x.png", "--size", "big"], "render.size must be WIDTHxHEIGHT"),
        (["--out", "x.png", "--color", "mood"], "Scene.color must be one of energy"),
        (["--out", "x.gif", "--start", "2", "--end", "1"], "render.end must be >= start"),
        (["--out", "x.gif", "--time", "1"], "render.time must be unset for a movie"),
        (["--out", "x.png", "--start", "1"], "render.start must be unset for a .png"),
    ],
)
def test_bad_options_exit_2_with_one_line(offscreen, run_dir, tmp_path, args, message):
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    result = runner.invoke(app, ["render", str(run_dir), *args])
    assert result.exit_code == 2
    assert message in result.output
    assert "Traceback" not in result.output


def test_missing_run_exits_2(tmp_path):
    result = runner.invoke(app, ["render", str(tmp_path / "nope"), "--out", "x.png"])
    assert result.exit_code == 2 and "not found" in result.output


def test_view_without_display_explains_itself(monkeypatch, run_dir):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    result = runner.invoke(app, ["view", str(run_dir)])
    assert result.exit_code == 2 and "crowdwalk render" in result.output


def test_help_lists_view_and_render_with_units():
    result = runner.invoke(app, ["render", "--help"])
    assert result.exit_code == 0
    assert "simulated time [s]" in result.output and "WIDTHxHEIGHT [px]" in result.output
    assert "view" in runner.invoke(app, ["--help"]).output


def test_render_without_gl_stack_explains_what_to_install(monkeypatch, run_dir, tmp_path):
    import crowdwalk.viz.headless as headless

    monkeypatch.setattr(headless, "gl_available", lambda: False)
    result = runner.invoke(app, ["render", str(run_dir), "--out", str(tmp_path / "x.png")])
    assert result.exit_code == 2
    assert "libegl1 libegl-mesa0 libgl1-mesa-dri" in result.output
    assert not (tmp_path / "x.png").exists()


def test_gl_probe_fails_cleanly_when_the_child_cannot_render(monkeypatch):
    import crowdwalk.viz.headless as headless

    monkeypatch.setattr(headless, "_PROBE", "import sys; sys.exit(139)")  # as a segfault
    assert headless.gl_available.__wrapped__(timeout=30) is False


def test_follow_needs_an_agent_of_the_run(run_dir, tmp_path):
    result = runner.invoke(app, ["render", str(run_dir), "--out", str(tmp_path / "x.png"),
                                 "--follow", "99"])
    assert result.exit_code == 2
    assert "Scene.follow must be an agent id of the run (0..11); got 99." in result.output
