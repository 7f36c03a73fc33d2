"""The ko_badler gait engine: footholds, continuity and leg geometry of its poses."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from crowdwalk.body import JOINT, Body
from crowdwalk.gait.ko_badler.engine import KoBadlerEngine

WIDTH = 0.09


def straight_steps(n_steps, length, speed, n_agents=1, heading=0.0):
    """Steps of n agents walking along +x side by side (1 m apart), batched per step."""
    dur = length / speed
    c, s = np.cos(heading), np.sin(heading)
    fwd, left = np.array([c, s, 0.0]), np.array([-s, c, 0.0])
    lanes = np.arange(n_agents)[:, None] * left[None] * 1.0
    out = []
    for i in range(n_steps):
        foot = i % 2  # 0: the left foot swings, the right one stands
        side = -1.0 if foot == 0 else 1.0
        centre = lanes + i * length * fwd
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
        heading = st.heading[0]
        fwd = np.array([np.cos(heading), np.sin(heading)])
        # the heel is on the floor at the moment of heel strike ...
        ball = end.positions[np.arange(3), swing + 2]
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


def test_poses_are_continuous_across_steps(walked):
    """The end of one step is the start of the next (root, every joint)."""
    _, _, frames, _ = walked
    for a, b in zip(frames[:-1], frames[1:], strict=True):
        np.testing.assert_allclose(a[-1].root_position, b[0].root_position, atol=1e-9)
        jump = np.abs(a[-1].positions - b[0].positions).max()
        assert jump < 0.02  # the toes relax differently per step; everything else matches


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
