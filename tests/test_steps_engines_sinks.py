"""The typed path from a decided step to poses and outputs: StepBatch, the gait-engine
registry and MixedEngine, run sinks, one body, Terrain.footing."""

from pathlib import Path

import numpy as np
import pytest

from crowdwalk.body import Body
from crowdwalk.crowd.run import RunOverrides, prepare, run_scenario
from crowdwalk.errors import InputError
from crowdwalk.gait.engine import GAIT_ENGINES, GaitEngine, MixedEngine, make_engine
from crowdwalk.record import open_run
from crowdwalk.sinks import RunSink
from crowdwalk.steps import FOOTSTEP_COLUMNS, StepBatch
from planners import Leg

ROOT = Path(__file__).resolve().parents[1]
QUICKSTART = ROOT / "scenarios" / "quickstart.yaml"


class Recorder:
    """A sink that keeps what it is given."""

    def __init__(self) -> None:
        self.calls: list[str] = []
        self.batches: list[StepBatch] = []
        self.frames: list[int] = []
        self.posed = 0

    def begin(self, info) -> None:
        self.calls.append("begin")
        self.n = len(info)

    def steps(self, batch) -> None:
        self.batches.append(batch)

    def frame(self, time, snapshot, poses) -> None:
        assert snapshot.frame == len(self.frames)
        self.frames.append(snapshot.frame)
        if poses is not None:
            assert np.isin(poses.agents, snapshot.agents).all()
            self.posed += 1

    def end(self, summary) -> None:
        self.calls.append("end")
        self.summary = summary


def test_a_sink_sees_every_footstep_the_run_folder_holds(tmp_path):
    rec = Recorder()
    assert isinstance(rec, RunSink)
    summary = run_scenario(QUICKSTART, tmp_path, sinks=[rec],
                           overrides=RunOverrides(duration=4.0, max_agents=6, poses=True))
    assert rec.calls == ["begin", "end"] and rec.summary is summary
    steps = StepBatch.concat(rec.batches)
    table = open_run(tmp_path).footsteps().columns()
    assert list(table) == list(FOOTSTEP_COLUMNS)
    cols = steps.footstep_columns().columns()
    assert len(steps) == table["agent"].size > 20
    for name in FOOTSTEP_COLUMNS:
        if cols[name].dtype.kind == "f":
            np.testing.assert_allclose(table[name], cols[name], atol=1e-5)
        else:
            assert (table[name] == cols[name]).all(), name
    # every step starts where the agent's previous one landed
    for a in np.unique(steps.agent):
        mine = steps.take(steps.agent == a)
        np.testing.assert_array_equal(mine.start[1:], mine.target[:-1])
        assert (np.diff(mine.step) == 1).all()
    frames = open_run(tmp_path).trajectories().frame
    assert rec.frames == list(range(frames.max() + 1))
    assert rec.posed == rec.frames[-1]  # every frame but frame 0


def _walk(sim, seconds: float) -> list:
    frames = []
    while sim.time < seconds - 1e-9:
        if sim.step():
            f = sim.poses()
            if f is not None:
                frames.append(f)
    return frames


@pytest.mark.parametrize("split", [False, True])
def test_a_mixed_engine_poses_each_agent_as_its_own_engine_would(split):
    """Two engines behind MixedEngine give every agent the pose the single engine gives
    it: steps are routed by agent and rows come back in the order asked. All agents on
    one engine: identical. Alternating: within 5 cm (each engine's interpolator inserts
    the datasets its own requests solved, so the two histories differ; with the planner's
    speed-dependent steps up to 2.7 cm), far below what a misrouted step or row would
    give (metres)."""
    over = RunOverrides(duration=3.0, max_agents=6, poses=True)
    _, world, one, _, _ = prepare(QUICKSTART, over)
    _, _, two, _, _ = prepare(QUICKSTART, over)
    body = Body.from_heights(two.pop.body_height)
    engines = [make_engine("elevation_angles", body=body, ground=world.terrain.height,
                           attributes=two.pop.style) for _ in range(2)]
    choice = np.arange(two.n) % 2 if split else np.zeros(two.n, int)
    two.gait = MixedEngine(engines, choice)
    assert isinstance(two.gait, GaitEngine)
    a, b = _walk(one, 3.0), _walk(two, 3.0)
    assert len(a) == len(b) > 10
    tol = 0.05 if split else 0.0  # normal-mode steps vary more: up to 2.7 cm seen
    for fa, fb in zip(a, b, strict=True):
        assert (fa.agents == fb.agents).all()
        np.testing.assert_allclose(fb.positions, fa.positions, rtol=0, atol=tol)
        np.testing.assert_allclose(fb.root_quaternion, fa.root_quaternion, rtol=0, atol=tol)
    assert (engines[1].stats["commands"] > 0) == split


def test_gait_engines_are_chosen_by_registered_name():
    assert "elevation_angles" in GAIT_ENGINES
    with pytest.raises(InputError, match=r"^make_engine\.name must be one of"):
        make_engine("no_such_gait", body=Body.from_heights([1.7]), ground=None)
    from crowdwalk.scenario import parse_scenario

    text = QUICKSTART.read_text().replace("planner: best_first", "planner: best_first\n"
                                          "    gait: no_such_gait", 1)
    with pytest.raises(ValueError, match="gait"):
        parse_scenario(text)


def test_the_planned_leg_is_the_animated_leg():
    heights = np.round(np.linspace(1.4, 2.1, 36) / 0.02) * 0.02
    body = Body.from_heights(heights)
    for leg, h, i in zip(body.planning_legs(), heights, range(heights.size), strict=True):
        assert leg == Leg.from_body_height(float(h))
        assert leg.thigh == body.thigh[i] and leg.toe_offset == body.toe_offset[i]


def test_terrain_footing_kind_and_stride_over_obstacles():
    from crowdwalk.scenario import load_scenario
    from crowdwalk.terrain import TerrainKind
    from crowdwalk.world import build_world

    terrain = build_world(load_scenario(ROOT / "scenarios" / "obstacle_stride.yaml")).terrain
    rng = np.random.default_rng(0)
    x0, y0, x1, y1 = terrain.bounds
    xy = rng.uniform([x0, y0], [x1, y1], size=(400, 2))
    d = np.tile([1.0, 0.0], (400, 1))
    kind, over = terrain.footing(xy, d, stride=np.full(400, 1.0))
    np.testing.assert_array_equal(kind, terrain.kind(xy))
    assert not over[kind != TerrainKind.BLOCK].any()
    _, never = terrain.footing(xy, d, stride=np.zeros(400))
    _, always = terrain.footing(xy, d, stride=np.full(400, 10.0))
    assert not never.any()
    assert (always == (kind == TerrainKind.BLOCK)).all()


def test_a_mixed_engine_poses_no_agents_as_an_empty_frame():
    body = Body.from_heights([1.6, 1.8])
    engines = [make_engine(name, body=body, ground=None) for name in ("elevation_angles", "klaw")]
    frame = MixedEngine(engines, np.array([0, 1])).pose(0.0, np.array([], dtype=int))
    assert frame.agents.size == 0 and frame.positions.shape[0] == 0


def test_a_background_sink_waits_for_every_call_and_raises_its_failure():
    """BackgroundSink.wait (the run reads the overlap check's result after it): every
    call made before it is done, in order; a failing call is raised by end, not wait
    (the run writes its summary between the two)."""
    import threading
    import time

    from crowdwalk.sinks import BackgroundSink, Snapshot

    gate = threading.Event()

    class Slow(Recorder):
        def frame(self, time_, snapshot, poses) -> None:
            gate.wait(5)
            time.sleep(0.002)
            super().frame(time_, snapshot, poses)

    sink = Slow()
    bg = BackgroundSink(lambda: sink, name="test-sink")
    assert bg._thread.name == "test-sink"
    for f in range(5):
        bg.frame(f / 10, Snapshot(f, np.arange(2), np.zeros((2, 2)), np.zeros(2),
                                  np.zeros((2, 2))), None)
    assert sink.frames == []  # held at the gate: nothing done yet
    gate.set()
    bg.wait()
    assert sink.frames == [0, 1, 2, 3, 4]
    bg.frame(0.5, Snapshot(9, np.arange(2), np.zeros((2, 2)), np.zeros(2),
                           np.zeros((2, 2))), None)  # out of order: the Recorder asserts
    bg.wait()
    assert sink.frames == [0, 1, 2, 3, 4]
    with pytest.raises(AssertionError):
        bg.end({})
