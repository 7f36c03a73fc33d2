"""crowdwalk compare: the same agents with each planner, report.md with plots."""

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.compare import compare_planners
from crowdwalk.record import open_run

SCENARIO = Path(__file__).parents[1] / "scenarios" / "obstacle_stride.yaml"
#: The planner that strides over the Fig. 11 obstacle (Chen & Li's best_first as written
#: steps onto it, see the README).
PLANNED = "best_first_multistart"


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("compare")
    return compare_planners(SCENARIO, [PLANNED, "fixed"], out)


def test_report_has_tables_and_plots(report):
    text = report.read_text()
    assert f"| {PLANNED} |" in text and "| fixed |" in text
    assert "## By terrain type" in text
    for png in ("per_agent.png", "energy_by_terrain.png", "footholds_on_obstacles.png"):
        assert f"]({png})" in text
        assert (report.parent / png).stat().st_size > 5000


def test_runs_are_posed_as_the_scenario_asks_so_they_can_be_viewed_side_by_side(report):
    for planner in (PLANNED, "fixed"):
        run = open_run(report.parent / planner)
        assert run.summary["poses"] == "written"
        assert (report.parent / planner / "poses.sqlite").stat().st_size > 10_000


def test_runs_use_the_same_agents_and_differ_only_in_planner(report):
    a, b = (open_run(report.parent / p) for p in (PLANNED, "fixed"))
    sa, sb = a.summary, b.summary
    assert sa["seed"] == sb["seed"]
    for x, y in zip(sa["agents"], sb["agents"], strict=True):
        assert (x["body_height_m"], x["free_speed_m_s"], x["group"]) == \
            (y["body_height_m"], y["free_speed_m_s"], y["group"])
        assert x["planner"] == PLANNED and y["planner"] == "fixed"


def test_fixed_walkers_step_on_the_obstacle_planned_do_not(report):
    steps = {p: open_run(report.parent / p).footsteps() for p in (PLANNED, "fixed")}
    assert steps[PLANNED].on_obstacle.sum() == 0
    # at least one fixed walker lands on it (whether both do depends on where their
    # neutral steps fall: with the normal-mode steps one of the two strides it by chance)
    assert steps["fixed"].on_obstacle.sum() >= 1
    text = report.read_text()
    fixed_row = next(line for line in text.splitlines() if line.startswith("| fixed | 2/2"))
    assert fixed_row.split("|")[6].strip() == str(steps["fixed"].on_obstacle.sum())


def test_cli_rejects_unknown_planner_with_exit_2(tmp_path):
    result = CliRunner().invoke(app, ["compare", str(SCENARIO), "--planners",
                                      "best_first,teleport", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert "compare.planners must be names from" in result.output
    assert "Traceback" not in result.output
    assert "agents remaining" not in result.output  # checked before the progress bar


def test_report_compares_the_same_trips_and_splits_by_step_direction(report):
    text = report.read_text()
    assert "## Same agents, same trips" in text
    assert "## By terrain type and step direction" in text
    trips = next(line for line in text.splitlines() if line.startswith(f"| {PLANNED} | 2 |"))
    assert "less energy than `fixed` (2 agents" in trips  # Fig. 11: striding saves


def test_paired_trips_only_pairs_agents_that_arrived_in_both_runs():
    from crowdwalk.compare import paired_trips

    def summary(energies, arrived):
        return {"agents": [{"id": i, "arrived": a, "energy_J_per_kg": e, "distance_m": 10.0}
                           for i, (e, a) in enumerate(zip(energies, arrived, strict=True))]}

    rng = np.random.default_rng(1)
    base = 100 + rng.normal(0, 5, 40)
    noisy = {"fixed": summary(base, [True] * 40),
             PLANNED: summary(base + rng.normal(0, 3, 40), [True] * 39 + [False])}
    r = paired_trips(noisy, "fixed")[PLANNED]
    assert r["agents"] == 39
    assert r["ci"][0] < r["difference"] < r["ci"][1]
    assert r["significant"] == (r["ci"][0] > 0 or r["ci"][1] < 0)
    saving = {"fixed": summary(base, [True] * 40), PLANNED: summary(base - 2, [True] * 40)}
    r = paired_trips(saving, "fixed")[PLANNED]
    assert r["significant"] and r["difference"] == pytest.approx(-2)
    assert r["relative"] == pytest.approx(-2 / base.mean())


def test_terrain_rows_split_by_direction_keep_the_totals():
    from crowdwalk.compare import terrain_table
    from crowdwalk.steps import FOOTSTEP_COLUMNS, FootstepTable

    cols = {c: np.zeros(6) for c in FOOTSTEP_COLUMNS}
    cols.update(kind=np.array([0, 0, 2, 2, 2, 0]), agent=np.array([0, 0, 0, 1, 1, 1]),
                step_length=np.array([0.6, 0.6, 0.3, 0.3, 0.3, 0.6]),
                step_height=np.array([0.0, 0.0, 0.17, 0.17, -0.17, -0.17]),
                energy=np.array([4.0, 4.0, 9.5, 9.5, 4.5, 6.0]),
                on_obstacle=np.zeros(6, dtype=int))
    steps = FootstepTable(**cols)
    split = terrain_table(steps, by_direction=True)
    assert list(split) == ["flat", "flat down", "stairs up", "stairs down"]
    assert split["stairs up"]["energy_per_metre"] == pytest.approx(19 / 0.6)
    assert split["stairs up"]["agents"] == 2
    whole = terrain_table(steps)
    assert whole["stairs"]["footholds"] == 3
    assert np.isnan(whole["stairs"]["ci"][0])  # too few agents for an interval
