"""Re-routing: walkers held up in a jammed corridor take a free detour."""

import numpy as np

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.record import open_run

SCENARIO = """
name: detour
terrain: {extent: [0, -8, 24, 6]}
routes:
  nodes:
    - {name: hall, xy: [2.5, 1.0], area: [[0.5, -1.5], [4.5, -1.5], [4.5, 3.5], [0.5, 3.5]]}
    - {name: exit, xy: [21.5, 1.0], area: [[19.5, -1.5], [23.5, -1.5], [23.5, 3.5], [19.5, 3.5]]}
    - {name: south_west, xy: [6.0, -5.5]}
    - {name: south_east, xy: [18.0, -5.5]}
  edges:
    - {from: hall, to: exit, width: 0.9}
    - {from: hall, to: south_west, width: 3.0}
    - {from: south_west, to: south_east, width: 3.0}
    - {from: south_east, to: exit, width: 3.0}
groups:
  - {name: crowd, count: 40, spawn: hall, destinations: [exit], planner: fixed}
simulation: {duration: 60.0, seed: 3, dt: 0.05, fps: 10}
outputs: {poses: false}
"""


def test_blocked_walkers_reroute_through_the_free_corridor(tmp_path):
    path = tmp_path / "detour.yaml"
    path.write_text(SCENARIO)
    summary = run_scenario(path, tmp_path / "run", overrides=RunOverrides(duration=45.0))
    assert summary["planning"]["reroutes"] >= 3
    traj = open_run(tmp_path / "run").trajectories()
    detour = np.unique(traj.id[traj.y < -3.0])  # walked the southern corridor
    direct = np.unique(traj.id[(traj.y > 0.0) & (traj.x > 9.0) & (traj.x < 15.0)])
    assert detour.size >= 3 and direct.size >= 5
    rerouted = {a["id"] for a in summary["agents"] if a["reroutes"] > 0}
    assert set(detour.tolist()) <= rerouted  # only re-routed walkers took the detour
    assert summary["agents_arrived"] >= 30
