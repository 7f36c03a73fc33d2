"""Re-routing continues from where the walker stands: no walking back to the room's node."""

import numpy as np
import shapely

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.record import open_run

SCENARIO = """
name: two_doors
terrain: {extent: [-1, -1, 19, 12]}
routes:
  nodes:
    - {name: room, xy: [5.0, 5.0], area: [[0, 0], [10, 0], [10, 10], [0, 10]]}
    - {name: door_a, xy: [10.0, 5.0]}
    - {name: door_b, xy: [10.0, 9.0]}
    - {name: out, xy: [14.0, 6.0], area: [[11, 2], [18, 2], [18, 11], [11, 11]]}
  edges:
    - {from: room, to: door_a, width: 0.45}
    - {from: door_a, to: out, width: 0.45}
    - {from: room, to: door_b, width: 1.2}
    - {from: door_b, to: out, width: 1.2}
groups:
  - {name: crowd, count: 40, spawn: room, destinations: [out], planner: fixed}
simulation: {duration: 60.0, seed: 2, dt: 0.05, fps: 10}
outputs: {poses: false}
"""


def test_rerouted_walkers_go_on_from_where_they_stand(tmp_path):
    path = tmp_path / "two_doors.yaml"
    path.write_text(SCENARIO)
    summary = run_scenario(path, tmp_path / "run", overrides=RunOverrides(duration=45.0))
    rerouted = [a["id"] for a in summary["agents"] if a["reroutes"] > 0]
    assert len(rerouted) >= 3
    t = open_run(tmp_path / "run").trajectories()
    back = []
    for i in rerouted:  # analysis of a finished run: one pass per walker
        x = t.x[t.id == i]
        back.append(float(np.max(np.maximum.accumulate(x) - x)))
    # walking back to the room's node (x = 5) lost 2.9-4.7 m of x (median 4.4) before
    # re-routing went on from where the walker stands; stepping back in the clog to get
    # round others still accounts for up to about 2 m
    assert np.median(back) <= 1.5 and max(back) <= 2.5, back
    through_b = np.unique(t.id[(t.x > 10.0) & (t.y > 8.0)])
    assert through_b.size >= 3


STOP_ON_THE_WAY = """
name: stop_on_the_way
terrain: {extent: [-1, -9, 16, 17]}
routes:
  nodes:
    - {name: room, xy: [2.0, 2.0], area: [[0, 0], [4, 0], [4, 4], [0, 4]]}
    - {name: stop, xy: [12.0, 2.0], area: [[10, 0], [14, 0], [14, 4], [10, 4]]}
    - {name: exit, xy: [12.0, 14.0], area: [[10, 12], [14, 12], [14, 16], [10, 16]]}
    - {name: round, xy: [7.0, -6.0]}
  edges:
    - {from: room, to: stop, width: 1.2}
    - {from: room, to: round, width: 1.2}
    - {from: round, to: stop, width: 1.2}
    - {from: stop, to: exit, width: 1.2}
    - {from: room, to: exit, width: 1.2}
groups:
  - {name: visitors, count: 6, spawn: room, destinations: [stop, exit], planner: fixed}
events:
  - {time: 1.0, action: close, corridor: [room, stop], at: 0.5}
simulation: {duration: 50.0, seed: 1, dt: 0.05, fps: 10}
outputs: {poses: false}
"""


def test_rerouted_walkers_still_visit_the_stop_ahead(tmp_path):
    """A door shuts between the walkers and their intermediate stop; the corridor straight
    to the exit is shorter than the way round to the stop, and must not be taken (the old
    re-routing, aimed at the route's last node, sent all six there)."""
    path = tmp_path / "stop.yaml"
    path.write_text(STOP_ON_THE_WAY)
    summary = run_scenario(path, tmp_path / "run")
    assert summary["events"][0]["walkers_rerouted"] == 6
    assert summary["agents_arrived"] == 6
    t = open_run(tmp_path / "run").trajectories()
    stop, exit_ = shapely.box(10, 0, 14, 4), shapely.box(10, 12, 14, 16)
    for i in range(6):  # analysis of a finished run: one pass per walker
        a = t.agent(i)
        at_stop = np.flatnonzero(shapely.contains_xy(stop, a.x, a.y))
        at_exit = np.flatnonzero(shapely.contains_xy(exit_, a.x, a.y))
        assert at_stop.size and at_exit.size and at_stop[0] < at_exit[0], i
        assert a.y.min() < -3.0, i  # the way round, not back through the room to the exit
