"""crowdwalk compare: the same agents with each planner, report.md with plots."""

from pathlib import Path

import pytest
from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.compare import compare_planners
from crowdwalk.record import open_run

SCENARIO = Path(__file__).parents[1] / "scenarios" / "obstacle_stride.yaml"


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("compare")
    return compare_planners(SCENARIO, ["best_first", "fixed"], out)


def test_report_has_tables_and_plots(report):
    text = report.read_text()
    assert "| best_first |" in text and "| fixed |" in text
    assert "## By terrain type" in text
    for png in ("per_agent.png", "energy_by_terrain.png", "footholds_on_obstacles.png"):
        assert f"]({png})" in text
        assert (report.parent / png).stat().st_size > 5000


def test_runs_use_the_same_agents_and_differ_only_in_planner(report):
    a, b = (open_run(report.parent / p) for p in ("best_first", "fixed"))
    sa, sb = a.summary, b.summary
    assert sa["seed"] == sb["seed"]
    for x, y in zip(sa["agents"], sb["agents"], strict=True):
        assert (x["body_height_m"], x["free_speed_m_s"], x["group"]) == \
            (y["body_height_m"], y["free_speed_m_s"], y["group"])
        assert x["planner"] == "best_first" and y["planner"] == "fixed"


def test_fixed_walkers_step_on_the_obstacle_planned_do_not(report):
    steps = {p: open_run(report.parent / p).footsteps() for p in ("best_first", "fixed")}
    assert steps["best_first"]["on_obstacle"].sum() == 0
    assert steps["fixed"]["on_obstacle"].sum() >= 2  # both walkers, both lanes
    text = report.read_text()
    fixed_row = next(line for line in text.splitlines() if line.startswith("| fixed | 2/2"))
    assert fixed_row.split("|")[6].strip() == str(steps["fixed"]["on_obstacle"].sum())


def test_cli_rejects_unknown_planner_with_exit_2(tmp_path):
    result = CliRunner().invoke(app, ["compare", str(SCENARIO), "--planners",
                                      "best_first,teleport", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert "compare.planners must be names from" in result.output
    assert "Traceback" not in result.output
