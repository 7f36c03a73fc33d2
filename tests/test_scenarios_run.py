"""Every scenario in scenarios/ runs a few simulated seconds (agents capped to stay fast)."""

from pathlib import Path

import numpy as np
import pytest

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.record import open_run

SCENARIOS = sorted((Path(__file__).parents[1] / "scenarios").glob("*.yaml"))


def test_the_issue_scenarios_exist():
    names = {p.stem for p in SCENARIOS}
    assert {"quickstart", "stairs_up_down", "obstacle_stride", "uneven_park", "corner",
            "bottleneck", "counterflow", "stadium_egress"} <= names


@pytest.mark.parametrize("path", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_scenario_runs_a_few_seconds(path, tmp_path):
    poses = path.stem == "quickstart"  # one scenario with full poses
    summary = run_scenario(path, tmp_path, overrides=RunOverrides(
        max_agents=12, duration=3.0, poses=poses))
    assert summary["simulated_time_s"] == pytest.approx(3.0)
    assert summary["complete"] and not summary["interrupted"]
    assert summary["agents_total"] <= 12
    run = open_run(tmp_path)
    traj = run.trajectories()
    assert traj.frame.size > 0 and np.isfinite(traj.x).all() and np.isfinite(traj.z).all()
    steps = run.footsteps()
    assert steps.agent.size > 0 and np.isfinite(steps.energy).all()
    assert summary["max_overlap_m"] <= 0.01
    if poses:
        stored = run.poses()
        assert stored is not None and stored.frames.size > 10
        rec = stored.frame(int(stored.frames[-1]))
        assert np.isfinite(rec.positions).all()
        assert summary["poses"] == "written"
