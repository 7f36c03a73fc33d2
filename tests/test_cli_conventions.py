"""CLI conventions: --version, --out refuses a non-empty folder, view without a window,
render --time outside the run, what was written and what to run next, incomplete runs."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from crowdwalk import __version__
from crowdwalk.cli import app

SCENARIO = Path(__file__).parents[1] / "scenarios" / "lone_walker.yaml"  # poses on
runner = CliRunner()


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("conventions") / "run"
    result = runner.invoke(app, ["run", str(SCENARIO), "--out", str(out), "--duration", "2"])
    assert result.exit_code == 0, result.output
    assert f"wrote the run folder {out}" in result.output and "next: `crowdwalk view" in \
        result.output
    return out


def test_version():
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0 and result.output.strip() == f"crowdwalk {__version__}"


def test_out_into_a_non_empty_folder_needs_overwrite(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    args = ["run", str(SCENARIO), "--out", str(tmp_path), "--duration", "1", "--quiet"]
    result = runner.invoke(app, args)
    assert result.exit_code == 2 and "--overwrite" in result.output
    assert not (tmp_path / "trajectories.sqlite").exists()
    result = runner.invoke(app, [*args, "--overwrite"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "summary.json").exists() and (tmp_path / "notes.txt").exists()


def test_view_without_a_window_exits_2(run_dir, monkeypatch):
    for display in ("", ":97"):  # unset, and an X server that is not there
        monkeypatch.setenv("DISPLAY", display)
        result = runner.invoke(app, ["view", str(run_dir)])
        assert result.exit_code == 2, result.output
        assert "crowdwalk render" in result.output


@pytest.mark.parametrize("option,value", [("--time", "500"), ("--time", "-5")])
def test_render_time_outside_the_run_is_an_error(run_dir, tmp_path, option, value):
    result = runner.invoke(app, ["render", str(run_dir), "--out", str(tmp_path / "f.png"),
                                 option, value])
    assert result.exit_code == 2, result.output
    assert "time range [0, 2]" in result.output and value in result.output
    assert not (tmp_path / "f.png").exists()


def test_view_time_outside_the_run_names_view(run_dir):
    result = runner.invoke(app, ["view", str(run_dir), "--web", "--time", "500"])
    assert result.exit_code == 2, result.output
    assert "view.time" in result.output and "time range [0, 2]" in result.output


def test_incomplete_run_is_named_and_stays_readable(run_dir, tmp_path):
    killed = tmp_path / "killed"
    shutil.copytree(run_dir, killed)
    (killed / "summary.json").unlink()  # what SIGKILL leaves (tests/test_record.py)
    result = runner.invoke(app, ["export-bvh", str(killed), "--agent", "0",
                                 "--out", str(tmp_path / "a.bvh")])
    assert result.exit_code == 0, result.output
    assert "incomplete run" in result.output and "2.0 s of simulation" in result.output
    assert (tmp_path / "a.bvh").stat().st_size > 1000 and "next:" in result.output
