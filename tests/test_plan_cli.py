"""The ``crowdwalk plan`` command: JSON fields, plots, bad CSV files, infeasible profiles."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.planning import read_profile_csv

runner = CliRunner()


def write(tmp_path, text, name="profile.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


STAIRS = "s,z\n-2,0\n0.4,0\n0.4,0.17\n0.7,0.17\n0.7,0.34\n1.0,0.34\n1.0,0.51\n6,0.51\n"


def test_json_output_has_the_documented_fields(tmp_path):
    path = write(tmp_path, STAIRS)
    result = runner.invoke(app, ["plan", "--profile", str(path), "--json", "--horizon"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["status"] == "ok"
    for key in ("footholds", "step_lengths", "energy_total", "energy_per_metre",
                "efficiency", "stats"):
        assert key in data
    assert len(data["footholds"]) == len(data["step_lengths"]) + 1 == 5
    assert data["footholds"][0] == {"s": 0.0, "z": 0.0}
    assert [f["z"] for f in data["footholds"]][1:4] == pytest.approx([0.17, 0.34, 0.51])
    assert data["energy_per_metre"] == pytest.approx(
        data["energy_total"] / sum(data["step_lengths"]))
    assert data["stats"]["nodes_expanded"] >= 1


def test_planner_body_height_and_speed_options_and_plot(tmp_path):
    path = write(tmp_path, "s,z\n0,0\n10,0\n")
    out = tmp_path / "plan.png"
    short = runner.invoke(app, ["plan", "--profile", str(path), "--json", "--planner", "fixed",
                                "--body-height", "1.5", "--speed", "1.0", "--plot", str(out)])
    tall = runner.invoke(app, ["plan", "--profile", str(path), "--json", "--body-height", "1.9"])
    assert short.exit_code == 0 and tall.exit_code == 0
    a, b = json.loads(short.output), json.loads(tall.output)
    assert a["planner"] == "fixed" and a["speed"] == 1.0
    assert a["step_lengths"][0] < b["step_lengths"][0]
    assert out.exists() and out.stat().st_size > 5000


def test_human_readable_table(tmp_path):
    result = runner.invoke(app, ["plan", "--profile", str(write(tmp_path, STAIRS))])
    assert result.exit_code == 0
    assert result.output.startswith("status: ok") and "J/(kg m)" in result.output


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("s,z\n0,0\n1,abc\n", ":3: profile s,z must be two numbers [m]; got '1,abc'."),
        ("s,z\n1,0\n0,0\n", ":3: profile s must be non-decreasing (previous row 1) [m]; got 0.0."),
        ("s,z\n0,0\n1,nan\n", ":3: profile s,z must be finite [m]; got '1,nan'."),
        ("s,z\n", ":1: profile rows must be at least two s,z rows; got 0."),
        ("s,z\n0,0\n", ":2: profile rows must be at least two s,z rows; got 1."),
        ("s,z\n-1,0\n0.4,0\n", "walk.profile must be at least one step (0.67 m) long"),
        ("a,b\n0,0\n", ":1: profile header must be columns named s and z; got 'a,b'."),
    ],
)
def test_bad_csv_exits_2_with_one_clear_line(tmp_path, text, message):
    result = runner.invoke(app, ["plan", "--profile", str(write(tmp_path, text))])
    assert result.exit_code == 2
    assert message in result.output
    if message.startswith(":"):
        assert f"profile.csv{message}" in result.output  # file:line names the row
    assert "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1


def test_missing_file_and_bad_options_exit_2(tmp_path):
    missing = runner.invoke(app, ["plan", "--profile", str(tmp_path / "nope.csv")])
    assert missing.exit_code == 2 and "file not found" in missing.output
    path = write(tmp_path, "s,z\n0,0\n10,0\n")
    bad = runner.invoke(app, ["plan", "--profile", str(path), "--planner", "astar"])
    assert bad.exit_code == 2 and "plan.planner must be one of" in bad.output
    slow = runner.invoke(app, ["plan", "--profile", str(path), "--speed", "-1"])
    assert slow.exit_code == 2 and "plan.speed" in slow.output


def test_wall_reports_no_legal_foothold_with_exit_1(tmp_path):
    path = write(tmp_path, "s,z\n-2,0\n1.0,0\n1.0,0.6\n5,0.6\n")
    result = runner.invoke(app, ["plan", "--profile", str(path), "--json", "--horizon"])
    assert result.exit_code == 1
    data = json.loads(result.output)
    assert data["status"] == "no legal foothold"
    assert "rise +0.60 m" in data["message"]


@pytest.mark.parametrize("planner", ["best_first", "best_first_multistart", "fixed"])
def test_walk_stops_in_front_of_a_wall_and_says_where_and_why(tmp_path, planner):
    path = write(tmp_path, "s,z\n-2,0\n3.0,0\n3.0,0.6\n5,0.6\n")
    result = runner.invoke(app, ["plan", "--profile", str(path), "--planner", planner])
    assert result.exit_code == 1
    first = result.output.splitlines()[0]
    assert first.startswith("status: no legal foothold at s = 3.00 m: rise +0.60 m exceeds "
                            "the largest step rise 0.25 m")
    data = json.loads(runner.invoke(app, ["plan", "--profile", str(path), "--planner",
                                          planner, "--json"]).output)
    s = [f["s"] for f in data["footholds"]]
    assert 2.5 < s[-1] < 3.0 and len(s) > 4  # walked up to the wall, not one horizon
    assert data["stats"]["plans"] == len(s)  # the steps taken, and the plan that found none


def test_walk_covers_the_whole_profile(tmp_path):
    result = runner.invoke(app, ["plan", "--profile", str(write(tmp_path, STAIRS)), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    s = np.array([f["s"] for f in data["footholds"]])
    z = np.array([f["z"] for f in data["footholds"]])
    assert data["status"] == "ok" and 6 - 0.9 < s[-1] <= 6
    assert z[-1] == pytest.approx(0.51) and np.all(np.diff(s) > 0)
    # one plan per step taken, and the last one, whose first step would pass the end
    assert data["stats"]["plans"] == len(s)


def test_csv_without_header_and_with_comments(tmp_path):
    profile = read_profile_csv(write(tmp_path, "# flat\n0,0\n\n2,0.1\n"))
    assert profile.s.tolist() == [0.0, 2.0] and profile.z.tolist() == [0.0, 0.1]
