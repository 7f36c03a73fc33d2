"""The KLAW engine (Bruderlin & Calvert 1993) on a straight walk: the step constraints of
§2.2 show in the poses it produces."""

from types import SimpleNamespace

import numpy as np
import pytest

from crowdwalk.body import JOINT, Body
from crowdwalk.gait.klaw import MTC_WINDOW, KlawEngine, double_support_fraction
from crowdwalk.style import Style

STEP, TIME, WIDTH, DT = 0.68, 0.53, 0.1, 0.01


def _walk(style_columns=None, steps=8, change=None):
    """Poses (F, n, J, 3), times (F,), stance side (F, n) and the heel-strike frames of a
    straight walk of n = 1 + len(style_columns) walkers (row 0 the default style)."""
    variants = [{}] + list(style_columns or [])
    n = len(variants)
    body = Body.from_heights(np.full(n, 1.75))
    base = Style.default(body.height, 1.3)
    cols = {k: np.array([v.get(k, getattr(base, k)[0]) for v in variants]) for k in
            {k for v in variants for k in v}}
    engine = KlawEngine(body, attributes=base.with_values(**cols) if cols else base)
    feet = {0: np.array([0.0, WIDTH / 2, 0.0]), 1: np.array([0.0, -WIDTH / 2, 0.0])}
    stance, t, frames, times, sides, strikes = 1, 0.0, [], [], [], []
    for k in range(steps):
        if change is not None and k == change[0]:
            engine.style = engine.style.with_values(**change[1])
        swing = 1 - stance
        target = feet[stance] + np.array([STEP, 0.0, 0.0])
        target[1] = feet[swing][1]
        engine.command(SimpleNamespace(
            agent=np.arange(n), start_time=np.full(n, t), duration=np.full(n, TIME),
            foot=np.full(n, swing), start=np.tile(feet[stance], (n, 1)),
            target=np.tile(target, (n, 1)), heading=np.zeros(n)))
        strikes.append(len(frames))
        for tt in np.arange(t, t + TIME - 1e-9, DT):
            frame = engine.pose(tt, np.arange(n))
            assert not frame.fallback.any()
            frames.append(frame.positions)
            times.append(tt)
            sides.append(frame.stance_left)
        feet[swing], stance, t = target, swing, t + TIME
    return np.array(frames), np.array(times), np.array(sides), strikes


def _knee(p, side):
    h, k, a = (p[..., JOINT[f"{side}_{j}"], :] for j in ("hip", "knee", "talocrural"))
    u, v = k - h, a - k
    cos = (u * v).sum(-1) / np.linalg.norm(u, axis=-1) / np.linalg.norm(v, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def test_walk_is_continuous_and_the_stance_foot_does_not_slide():
    p, t, left, strikes = _walk()
    assert np.isfinite(p).all()
    speed = np.linalg.norm(np.diff(p, axis=0), axis=-1) / DT
    assert speed.max() < 7.0  # m/s: no joint jumps (swing ankle peaks ~5 m/s)
    # from foot flat to the next heel strike the stance ball stays put
    for s0, s1 in zip(strikes[2:-1], strikes[3:], strict=True):
        side = "l" if left[s0, 0] else "r"
        ball = p[s0 + 10:s1, 0, JOINT[f"{side}_metatarsal"]]
        assert np.ptp(ball, axis=0).max() < 1e-6
    root = p[:, 0, 0]
    assert np.all(np.diff(root[:, 0]) > 0)  # always moving forward


@pytest.mark.parametrize("knee_min", [8.0, 18.0])
def test_knee_stance_min_is_the_least_stance_knee_flexion(knee_min):
    p, t, left, strikes = _walk([{"knee_stance_min": np.radians(knee_min)}])
    least = []
    for s0, s1 in zip(strikes[2:-1], strikes[3:], strict=True):  # single support: after toe-off
        side = "l" if left[s0, 1] else "r"
        least.append(_knee(p[s0 + int(0.3 * (s1 - s0)):s1, 1], side).min())
    assert np.allclose(least, knee_min, atol=0.5)


def test_knee_impact_is_the_knee_flexion_at_heel_strike():
    p, t, left, strikes = _walk([{"knee_impact": np.radians(12.0)}])
    for s in strikes[3:]:
        side = "l" if left[s, 1] else "r"  # the leg that just landed is the stance leg
        assert _knee(p[s, 0], side) == pytest.approx(3.0, abs=0.5)
        assert _knee(p[s, 1], side) == pytest.approx(12.0, abs=0.5)


def test_bounciness_deepens_the_double_support_dip():
    p, t, left, strikes = _walk([{"bounciness": 0.0}, {"bounciness": 3.0}])
    steady = slice(strikes[3], strikes[-1])
    excursion = np.ptp(p[steady, :, 0, 2], axis=0)
    assert excursion[1] < excursion[0] < excursion[2]
    # §2.2: y_mid_ds = y_impact - b (y_mid_swing - y_impact) / 5, so the excursion grows
    # as (1 + b / 5) times the rise from impact to mid swing (b = 0)
    assert excursion[2] / excursion[1] == pytest.approx(1.6, rel=0.15)


@pytest.mark.parametrize("clearance", [0.02, 0.05])
def test_toe_clearance_is_the_least_toe_height_in_mid_swing(clearance):
    p, t, left, strikes = _walk([{"toe_clearance": clearance}])
    for s0, s1 in zip(strikes[2:-1], strikes[3:], strict=True):
        side = "r" if left[s0, 1] else "l"  # the swing leg
        ds = double_support_fraction(1 / TIME) * (s1 - s0)  # swing starts after it
        mid = slice(s0 + int(ds + MTC_WINDOW[0] * (s1 - s0 - ds)),
                    s0 + int(ds + MTC_WINDOW[1] * (s1 - s0 - ds)))
        ankle = p[mid, 1, JOINT[f"{side}_talocrural"]]
        ball = p[mid, 1, JOINT[f"{side}_metatarsal"]]  # on the sole
        rel = ball - ankle
        pitch = np.arctan2(rel[:, 2], rel[:, 0]) - np.arctan2(-0.039, 0.073)
        tip = ball[:, 2] + (0.114 - 0.073) * 1.75 * np.sin(pitch)  # toes in line
        assert tip.min() == pytest.approx(clearance, abs=0.003)


def test_a_style_change_takes_effect_at_the_next_step():
    wide = {"arm_swing": np.radians(40.0)}
    p_same, *_ = _walk()
    p, t, left, strikes = _walk(change=(5, wide))
    before = slice(0, strikes[5])
    assert np.allclose(p[before], p_same[before])
    arm = p[:, 0, JOINT["l_elbow"]] - p[:, 0, JOINT["l_shoulder"]]
    swing = np.degrees(np.arctan2(arm[:, 0], -arm[:, 2]))
    assert np.ptp(swing[strikes[2]:strikes[5]]) == pytest.approx(30.0, abs=2.0)
    assert swing[strikes[6]:].max() == pytest.approx(40.0, abs=2.0)
