"""scripts/bottleneck_binds.py: the labels of made-up decisions, the pairing of entrants,
and one short run (the recorder leaves the run as it is; inside the headway model's free
zone no step is capped by it)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from crowdwalk.crowd import CrowdParams
from crowdwalk.record import Trajectories
from crowdwalk.verify import _bottleneck, _run

_SPEC = importlib.util.spec_from_file_location(
    "bottleneck_binds", Path(__file__).parents[2] / "scripts" / "bottleneck_binds.py")
binds = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(binds)


def _decision(**kw) -> dict:
    """A follower's decision that stands with nothing freeing it, then ``kw``."""
    d = {"t": 1.0, "agent": 1, "x": 7.7, "y": 0.0, "move": False, "free": 0.0,
         "reach": np.inf, "nominal": 0.7, "nolim": (False, 0.0), "nosoft": (False, 0.0),
         "alone": (False, 0.0), "single": {}, "plan_move": False, "plan_len": 0.0,
         "wake": np.inf, "stepped": False, "t1": 1.25}
    return {**d, **kw}


def test_labels_name_what_frees_the_step():
    lab = binds.label
    assert lab(_decision(), leader=0) == "stand:walls"
    assert lab(_decision(nosoft=(True, 0.6)), leader=0) == "stand:soft"
    assert lab(_decision(nolim=(True, 0.6)), leader=0) == "stand:priority"
    assert lab(_decision(single={0: (True, 0.6)}), leader=0) == "stand:hard_leader"
    assert lab(_decision(single={0: (False, 0.0), 2: (True, 0.6)}), 0) == "stand:hard_other"
    assert lab(_decision(alone=(True, 0.9)), leader=0) == "stand:hard_several"
    step = {"move": True, "free": 0.3, "plan_move": True, "plan_len": 0.3, "stepped": True,
            "t1": 1.5}
    assert lab(_decision(**{**step, "clash": True, "plan_move": False}), 0) == "stand:clash"
    assert lab(_decision(**{**step, "stepped": False}), 0) == "stand:yield"
    assert lab(_decision(**step, reach=0.2), 0) == "step:headway"
    assert lab(_decision(**{**step, "free": 0.9, "plan_len": 0.65}), 0) == "step:full"
    assert lab(_decision(**step, single={0: (True, 0.6)}), 0) == "step:short_hard_leader"
    assert lab(_decision(**step, single={0: (True, 0.35)}), 0) == "step:short_walls_or_plan"
    assert lab(_decision(**step, alone=(True, 0.9)), 0) == "step:short_hard_several"


def _entrants(ys, gap=0.5, fps=10.0) -> Trajectories:
    """Walkers along x from 7 to 9 m at 1 m/s, one every ``gap`` s, walker i at
    y = 5 + ys[i]."""
    rows = []
    for i, y in enumerate(ys):
        t0 = gap * i
        for f in range(int(round(t0 * fps)), int(round((t0 + 2.0) * fps)) + 1):
            rows.append((f, i, 7.0 + (f / fps - t0), 5.0 + y))
    a = np.array(sorted(rows))
    n = len(a)
    return Trajectories(frame=a[:, 0].astype(int), id=a[:, 1].astype(int), x=a[:, 2],
                        y=a[:, 3], z=np.zeros(n), ori_x=np.ones(n), ori_y=np.zeros(n),
                        fps=fps)


def test_pairs_binned_by_lateral_distance_and_time_summed():
    ys = [0.2 * (-1) ** i for i in range(20)]  # 0.4 m apart: every pair in the last bin
    traj = _entrants(ys)
    # follower 7 stands 0.25 s (woken at 0.15 s) and steps 0.35 s between 6's entry and its own
    t7 = binds.entries(traj)[7][0]
    decisions = [_decision(agent=7, t=t7 - 0.4, t1=t7 - 0.25, wake=t7 - 0.25),
                 _decision(agent=7, t=t7 - 0.7, t1=t7 - 0.6),
                 _decision(agent=7, t=t7 - 0.35, move=True, free=0.9, plan_move=True,
                           plan_len=0.7, stepped=True, t1=t7)]
    acc = {}
    binds.attribute(decisions, traj, acc)
    assert set(acc) == {">=0.3"}
    (row,) = binds.report(acc)
    assert row["pairs"] == 9 and abs(row["entry_gap_median_s"] - 0.5) < 0.051
    # the decision before 6's entry (t7 - 0.7 < t6 = t7 - 0.5) is not counted
    assert abs(row["s_per_pair"]["step:full"] * 9 - 0.35) < 0.01
    assert abs(row["s_per_pair"]["stand:walls"] * 9 - 0.15) < 0.01
    assert row["stands_per_pair"] == round(1 / 9, 2) and row["stands_woken_share"] == 1.0


def test_recorder_leaves_the_run_and_headway_is_off_at_the_mouth(tmp_path):
    data, params = _bottleneck(0.8, 5, 24), CrowdParams()
    plain = _run(data, tmp_path / "plain", params).traj
    with binds.Recorder() as rec:
        seen = _run(data, tmp_path / "seen", params).traj
    for name in ("frame", "id", "x", "y"):
        assert np.array_equal(getattr(plain, name), getattr(seen, name))
    assert len(rec.decisions) > 100
    # within 1 m of the opening (headway_free_margin) the headway model caps no step
    near = [d for d in rec.decisions if d["x"] > 7.05 and abs(d["y"]) < 0.4]
    assert near and all(d["reach"] == np.inf for d in near)
    # and the wrappers are gone afterwards
    import crowdwalk.crowd.simulation as simulation
    from crowdwalk.crowd.steering import choose_steps
    assert simulation.choose_steps is choose_steps


def test_without_columns_drops_bodies_and_reservations():
    """The hard test with reservations (``with_reservations``: K + K columns, no
    ``agent``) loses both the neighbour's body and its reservation."""
    from crowdwalk.crowd.mouth_priority import with_reservations
    from crowdwalk.crowd.steering import Neighbours

    def nbs(valid):
        z = np.zeros((1, 2, 2))
        return Neighbours(valid=np.array([valid]), now=z, end=z, velocity=z,
                          radius=np.full((1, 2), 0.18), heading=np.zeros((1, 2)),
                          remaining=np.zeros((1, 2)), agent=np.array([[3, 4]]))

    lim = with_reservations(nbs([True, True]), nbs([False, True]))
    assert lim.valid.shape == (1, 4) and lim.agent is None  # why agents cannot be used
    out = binds.without_columns(lim, 2, [1])
    assert out.valid.tolist() == [[True, False, False, False]]
    plain = nbs([True, True])  # without reservations the K columns only
    assert binds.without_columns(plain, 2, [0]).valid.tolist() == [[False, True]]


def test_jams_find_mutual_blockers_in_long_gaps():
    import sys
    sys.path.insert(0, str(Path(__file__).parents[2] / "scripts"))
    spec = importlib.util.spec_from_file_location(
        "bottleneck_jams", Path(__file__).parents[2] / "scripts" / "bottleneck_jams.py")
    jams = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(jams)
    traj = _entrants([0.0] * 20)
    ent = binds.entries(traj)
    t = ent[10][0]  # a long gap: shift the later entrants by 3 s
    late = traj.frame / traj.fps > t + 0.05
    traj = Trajectories(frame=traj.frame + np.where(late, int(3 * traj.fps), 0), id=traj.id,
                        x=traj.x, y=traj.y, z=traj.z, ori_x=traj.ori_x, ori_y=traj.ori_y,
                        fps=traj.fps)
    stand = {"x": 7.8, "y": 0.4, "stuck": 1.0, "fine": False, "nolim": False, "alone": True}
    decisions = [{**stand, "t": t + 1.0, "agent": 31, "blockers": [[35]]},
                 {**stand, "t": t + 1.5, "agent": 35, "blockers": [[31], [8]]},
                 {**stand, "t": t + 2.0, "agent": 8, "blockers": [[7, 9]]},
                 {**stand, "t": t - 5.0, "agent": 8, "blockers": [[35]]}]  # not in the gap
    (j,) = jams.jams(decisions, traj, seed=0)
    assert j["gap_s"] > 1.5 and j["stands"] == 3
    assert j["mutual_pairs"] == [[31, 35]]
    assert j["by_one"] == 2 and j["by_two_or_three"] == 1 and j["walls_only"] == 0


def test_pairs_binned_by_entry_gap_and_side_steps_labelled():
    ys = [0.2 * (-1) ** i for i in range(20)]  # 0.4 m apart, but one every 1.2 s
    traj = _entrants(ys, gap=1.2)
    t7 = binds.entries(traj)[7][0]
    # follower 7 steps sideways (90° off +x) for 0.3 s, then a full step into the door
    decisions = [_decision(agent=7, t=t7 - 0.45, move=True, free=0.9, plan_move=True,
                           plan_len=0.7, stepped=True, t1=t7 - 0.15, heading=90.0),
                 _decision(agent=7, t=t7 - 0.15, move=True, free=0.9, plan_move=True,
                           plan_len=0.7, stepped=True, t1=t7, heading=-10.0)]
    acc = {}
    binds.attribute(decisions, traj, acc, by="gap")
    assert set(acc) == {"1.1-1.5"}
    (row,) = binds.report(acc)
    assert row["dy"] == "1.1-1.5" and row["pairs"] == 9
    assert abs(row["gap_s_sum"] - 9 * 1.2) < 0.1
    assert abs(row["s_per_pair"]["step:full:side"] * 9 - 0.3) < 0.01
    assert abs(row["s_per_pair"]["step:full"] * 9 - 0.15) < 0.01
    acc = {}
    binds.attribute(decisions, _entrants(ys, gap=1.0), acc, by="gap")  # 1.0 s: first bin
    assert set(acc) == {"<=1.0"}
    acc = {}
    binds.attribute(decisions, traj, acc)  # by lateral distance, as before
    assert set(acc) == {">=0.3"}
