"""Who the walkers are (group, planner, style) and the followed walker's status."""

import shutil

import numpy as np
import pytest

from crowdwalk.record import open_run
from crowdwalk.viz.footprints import Footsteps
from crowdwalk.viz.walkers import Walkers, walker_status


def test_styles_come_from_the_run_and_fall_back_to_the_groups_preset(compare_folder, tmp_path):
    run_dir = tmp_path / "styled"
    shutil.copytree(compare_folder / "best_first", run_dir)
    scenario = run_dir / "scenario.yaml"
    text = scenario.read_text()
    assert "  - name: visitors\n" in text
    scenario.write_text(text.replace("  - name: visitors\n",
                                     "  - name: visitors\n    style: {preset: proud}\n"))
    run = open_run(run_dir)
    walkers = Walkers.from_run(run, Footsteps.from_table(run.footsteps()))
    assert walkers.labels("style") == ["normal", "proud"]
    visitors = walkers.group == "visitors"
    assert visitors.any() and np.all(walkers.style[visitors] == "proud")
    assert np.all(walkers.style[~visitors] == "normal")
    assert set(walkers.planner) == {"best_first"}
    codes = walkers.codes("style", walkers.id)
    np.testing.assert_array_equal(codes, visitors.astype(int))
    assert walkers.codes("group", np.array([10**6]))[0] == -1  # an unknown id
    # a style recorded per walker wins over the group's preset
    rows = [{"id": 0, "group": "g", "planner": "fixed", "style": {"preset": "tired"}}]
    assert Walkers.from_rows(rows).style.tolist() == ["tired"]


def test_status_measures_speed_step_length_and_energy_up_to_a_time():
    n = 6  # one walker at 1.4 m/s: a step of 0.7 m every 0.5 s
    t = 0.5 * np.arange(n)
    xy = np.column_stack([0.7 * np.arange(n), np.where(np.arange(n) % 2, -0.09, 0.09)])
    steps = Footsteps(np.zeros(n, int), t, np.column_stack([xy, np.zeros(n)]),
                      np.full(n, 4.0), np.full(n, "best_first"),
                      step_length=np.full(n, 0.7))
    status = walker_status(steps, 0, 1.6)
    assert status.steps == 4 and status.energy == pytest.approx(16.0)
    assert status.speed == pytest.approx(1.4) and status.step_length == pytest.approx(0.7)
    assert walker_status(steps, 0, 10.0).speed == 0.0  # stopped long ago
    assert walker_status(steps, 1, 1.6).steps == 0  # another walker
