"""The ko_badler gait engine: footholds, continuity and leg geometry of its poses."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from crowdwalk.body import JOINT, Body
from crowdwalk.gait.ko_badler.engine import KoBadlerEngine

WIDTH = 0.09


def straight_steps(n_steps, length, speed, n_agents=1, heading=0.0):
    """Steps of n agents walking along +x side by side (1 m apart), batched per step;
    ``length`` [m] one for all steps or one per step."""
    lengths = np.broadcast_to(np.asarray(length, dtype=float), (n_steps,))
    dur = float(np.mean(lengths)) / speed
    c, s = np.cos(heading), np.sin(heading)
    fwd, left = np.array([c, s, 0.0]), np.array([-s, c, 0.0])
    lanes = np.arange(n_agents)[:, None] * left[None] * 1.0
    out = []
    for i in range(n_steps):
        foot = i % 2  # 0: the left foot swings, the right one stands
        side = -1.0 if foot == 0 else 1.0
        length = lengths[i]
        centre = lanes + lengths[:i].sum() * fwd
        start = centre + side * 0.5 * WIDTH * left
        target = centre + length * fwd - side * 0.5 * WIDTH * left
        out.append(SimpleNamespace(
            agent=np.arange(n_agents), start_time=np.full(n_agents, i * dur),
            duration=np.full(n_agents, dur), foot=np.full(n_agents, foot), start=start,
            target=target, stance_centre=centre[:, :2], heading=np.full(n_agents, heading),
            length=np.full(n_agents, length),
            swing_bezier=np.full((n_agents, 4, 3), np.nan)))  # fmt: skip
    return out, dur


def walk(engine, steps, dur, per_step=20):
    """Poses of every agent at per_step phases of each step, and the step's start/end."""
    frames = []
    agents = steps[0].agent
    for st in steps:
        engine.command(st)
        t0 = float(st.start_time[0])
        frames.append([engine.pose(t0 + dur * s, agents) for s in np.linspace(0, 1, per_step)])
    return frames


@pytest.fixture(scope="module")
def walked():
    body = Body.from_heights(np.array([1.55, 1.75, 1.95]))
    engine = KoBadlerEngine(body)
    steps, dur = straight_steps(6, 0.7, 1.33, n_agents=3, heading=0.4)
    return engine, steps, walk(engine, steps, dur), body


def test_swing_foot_lands_on_the_target_foothold(walked):
    """Lemma 2 in the product: after the heel rolls to flat the foot's N is the target."""
    engine, steps, frames, body = walked
    for st, step in zip(steps, frames, strict=True):
        end = step[-1]
        swing = np.where(st.foot == 0, JOINT["l_talocrural"], JOINT["r_talocrural"])
        ankle = end.positions[np.arange(3), swing]
        # the foot's own direction (its toe-out from the heading, MetaGait §6.1)
        ball = end.positions[np.arange(3), swing + 2]
        fwd = (ball - ankle)[:, :2] / np.linalg.norm((ball - ankle)[:, :2], axis=1)[:, None]
        # the heel is on the floor at the moment of heel strike ...
        pitch = np.arctan2(ball[:, 2] - ankle[:, 2], np.linalg.norm((ball - ankle)[:, :2], axis=1))
        pitch = pitch + np.arctan2(body.ankle_height, body.ball_offset)  # sole angle, toe up
        heel = ankle[:, :2] - np.hypot(body.heel_offset, body.ankle_height)[:, None] * (
            np.cos(np.arctan2(body.ankle_height, body.heel_offset) + pitch)[:, None] * fwd)
        heel_z = ankle[:, 2] - np.hypot(body.heel_offset, body.ankle_height) * np.sin(
            np.arctan2(body.ankle_height, body.heel_offset) + pitch)  # fmt: skip
        np.testing.assert_allclose(heel_z, st.target[:, 2], atol=1e-6)
        # ... and N is hN ahead of it, at the commanded foothold
        n_point = heel + body.heel_offset[:, None] * fwd
        np.testing.assert_allclose(n_point, st.target[:, :2], atol=1e-6)


def test_stance_foot_stays_on_its_foothold(walked):
    """While the stance foot is flat its ball does not move and touches the floor."""
    engine, steps, frames, body = walked
    own = engine.own
    phases = np.linspace(0, 1, 20)
    flat = (phases > own.fgm + 0.02) & (phases < min(own.mom, 1.0) - 0.02)
    for st, step in zip(steps, frames, strict=True):
        stance_ball = np.where(st.foot == 0, JOINT["r_metatarsal"], JOINT["l_metatarsal"])
        balls = np.array([f.positions[np.arange(3), stance_ball] for f, fl in zip(step, flat,
                                                                                strict=True)
                          if fl])  # fmt: skip
        assert np.ptp(balls, axis=0).max() < 1e-9
        np.testing.assert_allclose(balls[..., 2], 0.0, atol=1e-9)


def test_poses_are_continuous_with_changing_steps():
    """Steps of changing length: the end of one step is the start of the next, and the
    swing foot leaves its push-off without a jump (every joint)."""
    steps, dur = straight_steps(6, [0.7, 0.5, 0.85, 0.6, 0.75, 0.55], 1.33)
    engine = KoBadlerEngine(Body.from_heights(np.array([1.75])))
    tom = engine.own.tom
    ends, starts, around_tom = [], [], []
    for st in steps:
        engine.command(st)
        t0, d = float(st.start_time[0]), float(st.duration[0])
        starts.append(engine.pose(t0, st.agent).positions)
        around_tom.append([engine.pose(t0 + d * (tom + e), st.agent).positions
                           for e in (-1e-7, 1e-7)])  # fmt: skip
        ends.append(engine.pose(t0 + d, st.agent).positions)
    for end, start in zip(ends[:-1], starts[1:], strict=True):
        np.testing.assert_allclose(end, start, atol=1e-6)
    for before, after in around_tom:
        np.testing.assert_allclose(before, after, atol=1e-4)


def test_legs_reach_their_feet_and_knees_bend_forward(walked):
    """FK from the pelvis puts the ankles where the foot model has them (the IK reaches);
    knees flex (never hyperextend) and peak in swing at 50-75 deg (Winter: ~65)."""
    engine, steps, frames, body = walked
    flex = []
    for step in frames[1:]:
        for f in step:
            for side in ("l", "r"):
                h, k, a = (f.positions[:, JOINT[f"{side}_{j}"]] for j in ("hip", "knee",
                                                                           "talocrural"))
                u, v = h - k, a - k
                cos = np.sum(u * v, 1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
                angle = np.pi - np.arccos(np.clip(cos, -1, 1))
                fwd = np.array([np.cos(0.4), np.sin(0.4), 0.0])
                assert np.all((k - 0.5 * (h + a)) @ fwd > -1e-6)  # the knee points forward
                flex.append(np.degrees(angle))
    flex = np.concatenate(flex)
    assert flex.min() >= 0 and 50 < flex.max() < 75
    assert engine.stats["poses"] > 0 and np.isfinite(frames[-1][-1].joints).all()


def test_swing_ankle_rises_to_the_planner_curve_over_a_step_up():
    """On a step up the swing ankle is never below the planner's Bezier (and lands)."""
    steps, dur = straight_steps(3, 0.6, 1.0)
    rise = 0.15
    last = steps[-1]
    last.target = last.target + [0.0, 0.0, rise]
    trail = steps[-2].start[0]
    ctrl = np.array([trail + [0, 0, 0.08], trail + [0.3, 0, 0.45],
                     last.target[0] + [-0.3, 0, 0.45], last.target[0] + [0, 0, 0.08]])
    last.swing_bezier = ctrl[None]
    engine = KoBadlerEngine(Body.from_heights(np.array([1.75])))
    frames = walk(engine, steps, dur, per_step=40)
    swing = JOINT["l_talocrural"] if last.foot[0] == 0 else JOINT["r_talocrural"]
    z = np.array([f.positions[0, swing, 2] for f in frames[-1]])
    assert engine.stats["bezier_lifted"] > 0
    assert z.max() > 0.3  # the curve's peak, far above the unplanned swing (about 0.15 m)
    assert z[-1] - rise < 0.12  # it lands on the raised foothold, not on the curve


def test_swing_toes_clear_the_floor_in_mid_swing(walked):
    """The swing sole (ball, straight toes) clears level ground by Winter's 1.29 cm least
    toe clearance in mid swing (without the lift the rigid foot dips 1.2-1.5 cm below)."""
    engine, steps, frames, body = walked
    phases = np.linspace(0, 1, 20)
    tom = engine.own.tom
    mid = (phases > tom + 0.4 * (1 - tom)) & (phases < tom + 0.7 * (1 - tom))  # toes straight
    toes = body.toe_offset - body.ball_offset
    for st, step in zip(steps[1:], frames[1:], strict=True):
        ankle_j = np.where(st.foot == 0, JOINT["l_talocrural"], JOINT["r_talocrural"])
        for f in (f for f, m in zip(step, mid, strict=True) if m):
            ankle, ball = f.positions[np.arange(3), ankle_j], f.positions[np.arange(3), ankle_j + 2]
            d = ball - ankle
            # the foot's own direction (it toes out from the heading by its toe-out)
            pitch = np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1])) + np.arctan2(body.ankle_height,
                                                                    body.ball_offset)
            toe_z = ball[:, 2] + toes * np.sin(pitch)
            assert np.all(np.minimum(ball[:, 2], toe_z) > 0.0129 - 1e-6)


def test_crowd_run_with_gait_ko_badler(tmp_path):
    """``gait: ko_badler`` in a scenario: crowdwalk run poses the walker with this engine."""
    from crowdwalk.crowd.run import run_scenario
    from crowdwalk.record import open_run

    scenario = tmp_path / "lone.yaml"
    scenario.write_text(LONE_WALKER, encoding="utf-8")
    summary = run_scenario(scenario, tmp_path / "run")
    assert summary["poses"] == "written"
    run = open_run(tmp_path / "run")
    frames = list(run.poses())
    assert len(frames) >= 50
    last = frames[-1]
    assert np.isfinite(last.positions).all() and last.positions[0, 0, 0] > 2.0


LONE_WALKER = """\
name: lone
terrain: {extent: [-1, -2, 21, 2], base: 0.0}
routes:
  nodes:
    - {name: start, xy: [1.0, 0.0], area: [[0.5, -0.5], [1.5, -0.5], [1.5, 0.5], [0.5, 0.5]]}
    - {name: end, xy: [18.0, 0.0]}
  edges: [{from: start, to: end, width: 3.0}]
groups:
  - {name: walker, count: 1, spawn: start, destinations: [end], planner: fixed,
     body_height: {mean: 1.75, sd: 0.0}, free_speed: {mean: 1.33, sd: 0.0}, gait: ko_badler}
simulation: {duration: 3.0, seed: 1, dt: 0.04, fps: 20}
outputs: {poses: true}
"""
