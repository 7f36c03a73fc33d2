"""The Animator's compiled walk terms (crowdwalk.gait.animator_kernels) give the numpy code
they replaced bit for bit (docs/architecture.md, "Posing speed")."""

from __future__ import annotations

import numpy as np

from crowdwalk.gait import animator_kernels as ak
from crowdwalk.gait.animator import _toe_off_shape
from crowdwalk.gait.datasets import sample
from crowdwalk.gait.foot import direction, wrap_angle
from crowdwalk.gait.posing_kernels import smoothstep

RNG = np.random.default_rng(17)
N, K = 60, 4000  # agents, rows asked (agents repeated, as the Animator's re-walks do)


def _phases(k: int, hi: float) -> np.ndarray:
    """Uniform phases with the ends, their neighbours and exact grid points mixed in."""
    x = RNG.uniform(0.0, hi, k)
    x[:40] = np.array([0.0, hi, np.nextafter(hi, 0), 1e-300, 0.25, 0.5 - 1e-6, 0.01, 0.1] * 5)
    return x


def _agents(k: int) -> np.ndarray:
    return RNG.integers(0, N, k).astype(np.intp)


def _same(got, want):
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape and got.dtype == want.dtype
    assert np.array_equal(got, want, equal_nan=True)


def test_crossfade_legs_is_the_numpy_code():
    angles, prev = RNG.normal(size=(N, 100, 4)), RNG.normal(size=(N, 100, 4))
    a, phase = _agents(K), _phases(K, 0.5)
    for crossfade in (True, False):
        # Animator._legs before pose17
        t = np.concatenate([phase, phase + 0.5])
        rows = np.tile(a, 2)
        legs = sample(angles, t, rows=rows)
        if crossfade:
            w = np.tile(smoothstep(2.0 * phase), 2)[:, None]
            before = sample(prev, t, rows=rows)
            legs = before + w * (legs - before)
        st, sw = ak.crossfade_legs(angles, prev, a, phase, crossfade)
        _same(st, legs[:K])
        _same(sw, legs[K:])


def test_headings_are_the_numpy_code():
    psi0, psi1 = RNG.uniform(-4, 4, N), RNG.uniform(-4, 4, N)
    spin = np.where(RNG.random(N) < 0.5, 0.0, RNG.uniform(-1, 1, N))
    spin_start = RNG.choice([0.0, 0.3, 1.0, 0.6], N)
    a, phase = _agents(K), _phases(K, 0.5)
    # Animator._heading and _spin_progress before pose17
    tau = 2.0 * phase
    sp = spin[a]
    turn = wrap_angle(psi1[a] - psi0[a])
    t0 = spin_start[a]
    progress = smoothstep((tau - t0) / np.maximum(1.0 - t0, 1e-9))
    want = psi0[a] + (turn - sp) * smoothstep(tau) + sp * progress
    _same(ak.headings(psi0, psi1, spin, spin_start, a, phase), want)


def test_swing_toes_are_the_numpy_code():
    toe_out, toe_start = RNG.uniform(-0.3, 0.3, N), RNG.uniform(-0.8, 0.8, N)
    toe_off = RNG.choice([0.0, 0.2, 0.45, 0.3], N)
    stance_left, has_trail = RNG.random(N) < 0.5, RNG.random(N) < 0.5
    trail_yaw = RNG.uniform(-4, 4, N)
    a, tau = _agents(K), _phases(K, 1.0)
    psi = RNG.uniform(-4, 4, K)
    limit = np.radians(40.0)
    # Animator._swing_toe before pose17
    toe1, t_off = toe_out[a], toe_off[a]
    side_sw = np.where(stance_left[a], -1.0, 1.0)
    held = np.clip(side_sw * wrap_angle(trail_yaw[a] - psi), -limit, limit)
    toe0 = np.where(has_trail[a], held, toe_start[a])
    want = toe0 + (toe1 - toe0) * smoothstep((tau - t_off) / np.maximum(1.0 - t_off, 1e-9))
    _same(ak.swing_toes(toe_out, toe_off, stance_left, trail_yaw, has_trail, toe_start, a,
                        tau, psi, limit), want)


def test_bezier_points_are_the_einsum():
    ctrl, tau = RNG.normal(size=(K, 4, 3)), _phases(K, 1.0)
    u = 1.0 - tau
    w = np.stack([u**3, 3 * u * u * tau, 3 * u * tau * tau, tau**3], axis=1)
    _same(ak.bezier_points(ctrl, tau, u**3, tau**3), np.einsum("kc,kcd->kd", w, ctrl))


def test_corrections_are_the_numpy_code():
    toe_off = RNG.choice([0.0, 0.2, 0.45, 0.3, 1e-12], N)
    d0, d1, toe_vel = (RNG.normal(size=(N, 3)) for _ in range(3))
    hip_fix0, hip_vel, hip_drop = (RNG.normal(size=(N, 3)) for _ in range(3))
    duration = RNG.uniform(0.3, 0.8, N)
    use_bezier, has_trail, join_long, join_whole = (RNG.random(N) < 0.5 for _ in range(4))
    a, tau = _agents(K), _phases(K, 1.0)
    blend_, in_, out_, half, whole = 0.7, 0.5, 0.3, 0.5, 1.0
    for c1 in (True, False):
        # Animator._walk's corrected terms before pose17
        t_off = toe_off[a]
        s = smoothstep((tau - t_off) / np.maximum(1.0 - t_off, 1e-9))[:, None]
        offset = (1.0 - s) * d0[a] + s * d1[a]
        swing = np.maximum(1.0 - t_off, 1e-9)
        if c1:
            beta = blend_ * swing
            u = np.clip((tau - t_off) / beta, 0.0, 1.0)
            offset += toe_vel[a] * (duration[a] * beta * _toe_off_shape(u))[:, None]
        ramp = (smoothstep((tau - t_off) / (in_ * swing))
                * smoothstep((1.0 - tau) / (out_ * swing)))
        blend = np.where(use_bezier[a], ramp, 0.0)
        pinned = has_trail[a] & (tau < t_off)
        toes = np.where(has_trail[a], 0.0, np.nan)
        over = np.where(join_long[a] | join_whole[a], whole, half)
        hip_fix = hip_fix0[a] * (1.0 - smoothstep(tau / over))[:, None]
        b = np.where(join_whole[a], whole, half)
        x = np.clip(tau / b, 0.0, 1.0)
        hip_fix += hip_vel[a] * (duration[a] * b * x * (1.0 - x) ** 2)[:, None]
        hip_fix += hip_drop[a] * smoothstep((tau - 0.4) / 0.6)[:, None]
        progress = ak.toe_off_progress(a, tau, toe_off, blend_)
        if c1:
            _same(progress, u)
        got = ak.corrections(a, tau, toe_off, d0, d1, toe_vel, duration, use_bezier,
                             has_trail, join_long, join_whole, hip_fix0, hip_vel, hip_drop, c1,
                             _toe_off_shape(progress), blend_, in_, out_, half, whole)
        for g, w in zip(got, (offset, blend, pinned, toes, hip_fix), strict=True):
            _same(g, w)


def test_pinned_feet_are_the_numpy_code():
    trail_yaw, trail_slope = RNG.uniform(-4, 4, N), RNG.uniform(-0.3, 0.3, N)
    trail_slope[:5] = 0.0
    trail_ball = RNG.normal(size=(N, 3))
    toe_off = RNG.choice([0.0, 0.2, 0.45, 0.3], N)
    toe_offset, ball_offset = RNG.uniform(0.15, 0.2, N), RNG.uniform(0.1, 0.13, N)
    ankle_height = RNG.uniform(0.05, 0.08, N)
    a, phase = _agents(K), _phases(K, 0.5)
    pitch = RNG.uniform(-1.0, 1.0, K)
    pitch[:20] = trail_slope[a[:20]]  # toes exactly flat
    # Animator._pinned_foot before pose17 (after its pitch)
    yaw, slope = trail_yaw[a], trail_slope[a]
    ch, sh = np.cos(yaw), np.sin(yaw)
    flat = np.stack([ch, sh, np.zeros_like(yaw)], axis=1)
    up = np.array([0.0, 0.0, 1.0])
    along = direction(yaw, slope)
    toe_len = toe_offset[a] - ball_offset[a]
    tip = trail_ball[a] + toe_len[:, None] * along
    w = smoothstep(2.0 * phase / np.maximum(toe_off[a], 1e-9))
    toe_angle = (1.0 - w) * np.minimum(pitch - slope, 0.0)
    toe_pitch = pitch - toe_angle
    c, s_ = np.cos(pitch), np.sin(pitch)
    ankle_to_ball = (flat * (ball_offset[a] * c + ankle_height[a] * s_)[:, None]
                     + up * (ball_offset[a] * s_ - ankle_height[a] * c)[:, None])
    ball_to_tip = toe_len[:, None] * (flat * np.cos(toe_pitch)[:, None]
                                      + up * np.sin(toe_pitch)[:, None])  # fmt: skip
    want = (tip - ball_to_tip - ankle_to_ball, toe_angle, tip - ball_to_tip)
    got = ak.pinned_feet(a, phase, pitch, trail_yaw, trail_slope, trail_ball, toe_off,
                         toe_offset, ball_offset, ankle_height)
    for g, w_ in zip(got, want, strict=True):
        _same(g, w_)



def test_sole_points_are_the_numpy_code():
    from crowdwalk.body import LEG_JOINTS

    nj = 20
    positions, rotations = RNG.normal(size=(K, nj, 3)), RNG.normal(size=(K, nj, 3, 3))
    heel_offset, ankle_height = RNG.uniform(0.04, 0.07, N), RNG.uniform(0.05, 0.08, N)
    toe_offset, ball_offset = RNG.uniform(0.15, 0.2, N), RNG.uniform(0.1, 0.13, N)
    stance_left = RNG.random(N) < 0.5
    heel_ball, ball_toe = np.linspace(0.0, 1.0, 5), np.array([1.0])
    a = _agents(K)
    # Animator._swing_sole before pose17
    sw = LEG_JOINTS[np.where(stance_left[a], 1, 0)]
    rows = np.arange(K)
    ankle, ball = positions[rows, sw[:, 2]], positions[rows, sw[:, 4]]
    r_sub, r_mtp = rotations[rows, sw[:, 3]], rotations[rows, sw[:, 4]]
    heel = (ankle - r_sub[:, :, 0] * heel_offset[a][:, None]
            - r_sub[:, :, 2] * ankle_height[a][:, None])
    tip = ball + r_mtp[:, :, 0] * (toe_offset[a] - ball_offset[a])[:, None]
    hb = heel[:, None] + heel_ball[None, :, None] * (ball - heel)[:, None]
    bt = ball[:, None] + ball_toe[None, :, None] * (tip - ball)[:, None]
    got = ak.sole_points(positions, rotations, np.ascontiguousarray(sw, dtype=np.intp), a,
                         heel_offset, ankle_height, toe_offset, ball_offset, heel_ball,
                         ball_toe)
    _same(got, np.concatenate([hb, bt], axis=1))
