"""The command line: help on every command, bad input exits 2 without a traceback."""

from typer.testing import CliRunner

from crowdwalk.cli import app

runner = CliRunner()


def test_help_lists_commands():
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0
    for command in ("validate", "schema"):
        assert command in result.output


def test_missing_file_exits_2_without_traceback(tmp_path):
    result = runner.invoke(app, ["validate", str(tmp_path / "nope.yaml")])
    assert result.exit_code == 2
    assert "Traceback" not in result.output


def test_bad_scenario_is_reported_before_any_progress_bar(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nterrain: {extent: [0, 0, 10, 10]}\ngroups: []\n")
    for args in (["run", str(bad), "--out", str(tmp_path / "r")],
                 ["compare", str(bad), "--out", str(tmp_path / "c")]):
        result = runner.invoke(app, args)
        assert result.exit_code == 2
        assert "bad.yaml:1: routes is required" in result.output
        assert "agents remaining" not in result.output  # no bar was drawn
        assert not (tmp_path / "r").exists()


