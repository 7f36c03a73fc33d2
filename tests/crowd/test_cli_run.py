"""crowdwalk run: writes the run folder; bad input exits 2 with one line."""

from pathlib import Path

from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.record import open_run

SCENARIO = Path(__file__).parents[2] / "scenarios" / "rimea1_corridor.yaml"
runner = CliRunner()


def test_run_writes_the_run_folder(tmp_path):
    result = runner.invoke(app, ["run", str(SCENARIO), "--out", str(tmp_path), "--quiet",
                                 "--duration", "3"])
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()  # --quiet: no progress bar, one line: where and next
    assert len(lines) == 1 and str(tmp_path) in lines[0] and "next:" in lines[0], lines
    for name in ("scenario.yaml", "trajectories.sqlite", "footsteps.csv", "summary.json"):
        assert (tmp_path / name).exists()
    assert (tmp_path / "scenario.yaml").read_text() == SCENARIO.read_text()
    assert open_run(tmp_path).summary["simulated_time_s"] == 3.0


def test_run_without_quiet_reports_progress_and_summary(tmp_path):
    result = runner.invoke(app, ["run", str(SCENARIO), "--out", str(tmp_path),
                                 "--duration", "2"])
    assert result.exit_code == 0, result.output
    assert "agents remaining" in result.output and "real time" in result.output


def test_bad_input_exits_2_without_traceback(tmp_path):
    for args, text in (
        (["run", str(tmp_path / "missing.yaml"), "--out", str(tmp_path)], "file not found"),
        (["run", str(SCENARIO), "--out", str(tmp_path), "--duration", "-1"],
         "RunOverrides.duration must be > 0 [s]; got -1.0."),
        (["run", str(SCENARIO), "--out", str(tmp_path), "--planner", "teleport"],
         "RunOverrides.planner must be one of"),
    ):
        result = runner.invoke(app, args)
        assert result.exit_code == 2, (args, result.output)
        assert text in result.output
        assert "Traceback" not in result.output


def test_crowd_model_option_runs_the_named_model(tmp_path, monkeypatch):
    import crowdwalk.crowd.run as crowd_run
    from crowdwalk.crowd.params import crowd_model

    seen = []
    real = crowd_run.run_scenario

    def spy(*args, params=None, **kwargs):
        seen.append(params)
        return real(*args, params=params, **kwargs)

    monkeypatch.setattr(crowd_run, "run_scenario", spy)
    result = runner.invoke(app, ["run", str(SCENARIO), "--out", str(tmp_path), "--quiet",
                                 "--duration", "1", "--crowd-model", "headway_s175"])
    assert result.exit_code == 0, result.output
    assert seen == [crowd_model("headway_s175")]
    result = runner.invoke(app, ["run", str(SCENARIO), "--out", str(tmp_path / "b"),
                                 "--crowd-model", "fast"])
    assert result.exit_code == 2 and "crowd.model must be one of" in result.output
    assert "Traceback" not in result.output
