"""Compiled per-agent terms of the Animator's walk (legs, heading, toe-out, corrections).

Each :meth:`crowdwalk.gait.animator.Animator._walk` gathered some twenty state columns of
its agents and combined them in ~100 small numpy operations, a fixed ~0.2 ms per call
(~13 calls per frame of the 1,000-walker stadium; docs/architecture.md, "Posing speed").
These nogil kernels do the same arithmetic per agent, in the numpy code's order, so they
give its values bit for bit: ``np.clip``'s and ``np.maximum``'s NaN semantics, Python's
float ``%`` (numpy's ``np.remainder``), ``** 2`` as a product (as numpy), the Catmull-Rom
samples of :func:`crowdwalk.gait.datasets.sample` (its kernel) and ``einsum("kc,kcd->kd")``
summed in index order (measured: 0 of 60,000 entries differ). Cubes are numpy's, passed
in (so is the toe-off hand-over's shape, ``animator._toe_off_shape``): numpy's ``x ** 3``
is its own (AVX-512, SVML) ``pow`` here, which differs from glibc's (numba's) in ~6 % of
values and from ``x * x * x`` in ~25 %.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from crowdwalk.gait.complexes import _wrap  # foot.wrap_angle of one float
from crowdwalk.gait.datasets import _sample_kernel
from crowdwalk.gait.posing_kernels import smooth_one as _smooth

__all__ = ["bezier_points", "corrections", "crossfade_legs", "headings", "pinned_feet",
           "sole_points", "swing_toes", "toe_off_progress"]

_jit = nb.njit(cache=True, nogil=True)


@_jit
def _clip(v, lo, hi):  # pragma: no cover - compiled
    """``np.clip(v, lo, hi)`` of one float (NaN kept, ties to the bound)."""
    v = v if (np.isnan(v) or v > lo) else lo
    return v if (np.isnan(v) or v < hi) else hi


@_jit
def _at_least(v, lo):  # pragma: no cover - compiled
    """``np.maximum(v, lo)`` of one float (NaN kept)."""
    return v if (np.isnan(v) or v >= lo) else lo


@_jit
def crossfade_legs(angles, prev_angles, a, phase, crossfade):  # pragma: no cover - compiled
    """``Animator._legs``: stance leg at t and swing leg at t + 0.5, (k, 4) each [rad], of
    agents a (k,) at stance phases (k,) — samples of ``angles`` (n, S, 4), crossfaded
    from ``prev_angles`` by smoothstep(2t) where ``crossfade``."""
    k = a.shape[0]
    t = np.empty(2 * k)
    rows = np.empty(2 * k, np.intp)
    for r in range(k):
        t[r], t[k + r] = phase[r], phase[r] + 0.5
        rows[r], rows[k + r] = a[r], a[r]
    legs = np.empty((2 * k, 4))
    _sample_kernel(angles, t, rows, legs)
    if crossfade:
        before = np.empty((2 * k, 4))
        _sample_kernel(prev_angles, t, rows, before)
        for r in range(k):
            w = _smooth(2.0 * phase[r])
            for c in range(4):
                legs[r, c] = before[r, c] + w * (legs[r, c] - before[r, c])
                legs[k + r, c] = before[k + r, c] + w * (legs[k + r, c] - before[k + r, c])
    return legs[:k], legs[k:]


@_jit
def headings(psi0, psi1, spin, spin_start, a, phase):  # pragma: no cover - compiled
    """``Animator._heading``: ψ (k,) [rad] of agents a (k,) at stance phases (k,), from
    ψ0 to ψ1 over the step, the spin turn's part turning with the spin."""
    k = a.shape[0]
    out = np.empty(k)
    for r in range(k):
        i = a[r]
        tau = 2.0 * phase[r]
        turn = _wrap(psi1[i] - psi0[i])
        t0 = spin_start[i]
        progress = _smooth((tau - t0) / _at_least(1.0 - t0, 1e-9))
        out[r] = psi0[i] + (turn - spin[i]) * _smooth(tau) + spin[i] * progress
    return out


@_jit
def swing_toes(toe_out, toe_off, stance_left, trail_yaw, has_trail, toe_start, a, tau, psi,
               max_start):  # pragma: no cover - compiled
    """``Animator._swing_toe``: the swing foot's toe-out (k,) [rad] of agents a (k,) at
    step phases tau (k,), heading psi (k,)."""
    k = a.shape[0]
    out = np.empty(k)
    for r in range(k):
        i = a[r]
        side_sw = -1.0 if stance_left[i] else 1.0
        t_off = toe_off[i]
        if has_trail[i]:
            toe0 = _clip(side_sw * _wrap(trail_yaw[i] - psi[r]), -max_start, max_start)
        else:
            toe0 = toe_start[i]
        s = _smooth((tau[r] - t_off) / _at_least(1.0 - t_off, 1e-9))
        out[r] = toe0 + (toe_out[i] - toe0) * s
    return out


@_jit
def bezier_points(ctrl, tau, u_cubed, tau_cubed):  # pragma: no cover - compiled
    """``animator._bezier``: cubic Bezier points (k, 3) of control points (k, 4, 3) at
    parameters tau (k,) (the einsum's index-order sum); (1 − tau)³ and tau³ (k,) numpy's."""
    k = tau.shape[0]
    out = np.empty((k, 3))
    for r in range(k):
        t = tau[r]
        u = 1.0 - t
        w0, w1, w2, w3 = u_cubed[r], 3 * u * u * t, 3 * u * t * t, tau_cubed[r]
        for d in range(3):
            out[r, d] = ((w0 * ctrl[r, 0, d] + w1 * ctrl[r, 1, d]) + w2 * ctrl[r, 2, d]
                         + w3 * ctrl[r, 3, d])
    return out


@_jit
def toe_off_progress(a, tau, toe_off, toe_off_blend):  # pragma: no cover - compiled
    """u (k,) = clip((τ − toe-off) / β, 0, 1), β = ``toe_off_blend`` (1 − toe-off): the
    progress of the toe-off hand-over of agents a (k,) at step phases tau (k,)."""
    k = a.shape[0]
    out = np.empty(k)
    for r in range(k):
        t_off = toe_off[a[r]]
        beta = toe_off_blend * _at_least(1.0 - t_off, 1e-9)
        out[r] = _clip((tau[r] - t_off) / beta, 0.0, 1.0)
    return out


@_jit
def corrections(a, tau, toe_off, d0, d1, toe_vel, duration, use_bezier, has_trail,
                join_long, join_whole, hip_fix0, hip_vel, hip_drop, toe_off_c1, shape,
                toe_off_blend, bezier_in, bezier_out, hip_blend, hip_blend_clamped
                ):  # pragma: no cover - compiled
    """The step corrections of ``Animator._walk`` for agents a (k,) at step phases tau
    (k,): swing-ankle offset (k, 3) [m] (toe-off blend and, with ``toe_off_c1``, the C¹
    hand-over, its shape h(u) (k,) at :func:`toe_off_progress` u given), Bezier blend
    (k,), pinned rows (k,) bool, rigid-toe angle (k,) (0 or NaN), stance-hip offset
    (k, 3) [m] (continuity, its C¹ term, the drop toward the landing; both join terms
    over ``hip_blend_clamped`` where ``join_whole``, the restart after a stop)."""
    k = a.shape[0]
    offset, hip_fix = np.empty((k, 3)), np.empty((k, 3))
    blend, toes = np.empty(k), np.empty(k)
    pinned = np.empty(k, np.bool_)
    for r in range(k):
        i = a[r]
        t = tau[r]
        t_off = toe_off[i]
        s = _smooth((t - t_off) / _at_least(1.0 - t_off, 1e-9))
        swing = _at_least(1.0 - t_off, 1e-9)
        for c in range(3):
            offset[r, c] = (1.0 - s) * d0[i, c] + s * d1[i, c]
        if toe_off_c1:
            beta = toe_off_blend * swing
            size = duration[i] * beta * shape[r]
            for c in range(3):
                offset[r, c] = offset[r, c] + toe_vel[i, c] * size
        ramp = _smooth((t - t_off) / (bezier_in * swing)) * _smooth((1.0 - t) / (bezier_out
                                                                                 * swing))
        blend[r] = ramp if use_bezier[i] else 0.0
        pinned[r] = has_trail[i] and t < t_off
        toes[r] = 0.0 if has_trail[i] else np.nan
        over = hip_blend_clamped if (join_long[i] or join_whole[i]) else hip_blend
        keep = 1.0 - _smooth(t / over)
        b = hip_blend_clamped if join_whole[i] else hip_blend
        x = _clip(t / b, 0.0, 1.0)
        c1 = duration[i] * b * x * (1.0 - x) ** 2
        drop = _smooth((t - 0.4) / 0.6)
        for c in range(3):
            v = hip_fix0[i, c] * keep
            v = v + hip_vel[i, c] * c1
            hip_fix[r, c] = v + hip_drop[i, c] * drop
    return offset, blend, pinned, toes, hip_fix


@_jit
def pinned_feet(a, phase, pitch, trail_yaw, trail_slope, trail_ball, toe_off, toe_offset,
                ball_offset, ankle_height):  # pragma: no cover - compiled
    """``Animator._pinned_foot`` of agents a (k,) at stance phases (k,), the trailing foot
    pitched ``pitch`` (k,) [rad] (numpy's: its tan and arctan are not glibc's): ankle
    (k, 3) [m], toe angle (k,) [rad], ball (k, 3) [m]. Body columns are the n agents'."""
    k = a.shape[0]
    ankle, ball = np.empty((k, 3)), np.empty((k, 3))
    toe_angle = np.empty(k)
    for r in range(k):
        i = a[r]
        yaw, slope, p = trail_yaw[i], trail_slope[i], pitch[r]
        ch, sh = np.cos(yaw), np.sin(yaw)
        cp = np.cos(slope)
        along = (cp * np.cos(yaw), cp * np.sin(yaw), np.sin(slope))  # foot.direction
        toe_len = toe_offset[i] - ball_offset[i]
        w = _smooth(2.0 * phase[r] / _at_least(toe_off[i], 1e-9))
        bent = p - slope
        bent = bent if (np.isnan(bent) or bent <= 0.0) else 0.0  # np.minimum(., 0)
        angle = (1.0 - w) * bent
        toe_angle[r] = angle
        toe_pitch = p - angle
        c, s = np.cos(p), np.sin(p)
        x = ball_offset[i] * c + ankle_height[i] * s  # ankle → ball: flat x + up y
        y = ball_offset[i] * s - ankle_height[i] * c
        ct, st = np.cos(toe_pitch), np.sin(toe_pitch)
        flat = (ch, sh, 0.0)
        up = (0.0, 0.0, 1.0)
        for d in range(3):
            tip = trail_ball[i, d] + toe_len * along[d]
            b = tip - toe_len * (flat[d] * ct + up[d] * st)
            ball[r, d] = b
            ankle[r, d] = b - (flat[d] * x + up[d] * y)
    return ankle, toe_angle, ball


@_jit
def sole_points(positions, rotations, joints, a, heel_offset, ankle_height, toe_offset,
                ball_offset, heel_ball, ball_toe):  # pragma: no cover - compiled
    """``Animator._swing_sole``: points (k, q, 3) [m] along the swing sole of k walked
    poses (``positions`` (k, J, 3), ``rotations`` (k, J, 3, 3)), the swing leg's joints
    ``joints`` (k, 5), of agents a (k,): heel → ball at fractions ``heel_ball``, then
    ball → toe tip at ``ball_toe``. Body columns are the n agents'."""
    k, p, q = a.shape[0], heel_ball.shape[0], ball_toe.shape[0]
    out = np.empty((k, p + q, 3))
    heel, ball, tip = np.empty(3), np.empty(3), np.empty(3)
    for r in range(k):
        i = a[r]
        tc, sub, mtp = joints[r, 2], joints[r, 3], joints[r, 4]
        toe_len = toe_offset[i] - ball_offset[i]
        for d in range(3):
            heel[d] = (positions[r, tc, d] - rotations[r, sub, d, 0] * heel_offset[i]
                       - rotations[r, sub, d, 2] * ankle_height[i])
            ball[d] = positions[r, mtp, d]
            tip[d] = ball[d] + rotations[r, mtp, d, 0] * toe_len
        for s in range(p):
            for d in range(3):
                out[r, s, d] = heel[d] + heel_ball[s] * (ball[d] - heel[d])
        for s in range(q):
            for d in range(3):
                out[r, p + s, d] = ball[d] + ball_toe[s] * (tip[d] - ball[d])
    return out
