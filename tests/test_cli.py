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
