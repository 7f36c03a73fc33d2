"""ElevWalker's compiled terms (crowdwalk.gait.elevwalker_kernels) give the numpy code of
``elevwalker_pose`` they replaced bit for bit (docs/architecture.md, "Posing speed")."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from crowdwalk.body import JOINT, JOINT_NAMES
from crowdwalk.gait import elevwalker_kernels as ek
from crowdwalk.gait import posing_kernels as pk
from crowdwalk.gait.datasets import trunk_motion
from crowdwalk.gait.elevwalker import (
    BOUNCE_DIP,
    BOUNCE_LOW,
    THIGH_HALF,
    THIGH_MID,
    GaitStyle,
    _upper_body_arguments,
)

RNG = np.random.default_rng(19)


def _same(got, want):
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape and got.dtype == want.dtype
    assert np.array_equal(got, want, equal_nan=True)
    # signed zeros too (the pelvis's cos/sin and the shifted leg see them)
    assert np.array_equal(np.signbit(got), np.signbit(want))


def _stance_terms_numpy(left, h, hip_separation, width, sway, phase, list_amplitude,
                        list_shape, list_scale, rotation_amplitude, rotation_shape, styled,
                        bounciness, heading, phi_st, phi_sw, thigh, shank, offset):
    """elevwalker_pose before pose19: from the side to the pelvis's angles (``offset`` None:
    none; ``list_scale`` None: none; ``styled``: the KLAW attributes' rotation and dip)."""
    k = left.size
    side_st = np.where(left, 1.0, -1.0)
    c, s, z = np.cos(heading), np.sin(heading), np.zeros_like(heading)  # _frame
    normal = np.stack([-s, c, z], axis=-1)
    half_hips = 0.5 * hip_separation
    sway = sway * h * np.sin(2.0 * np.pi * phase)
    half_width = 0.5 * width
    rotation = 0.0 if not styled else (-side_st * rotation_amplitude * rotation_shape)
    if styled:  # _bounce_dip
        shape = 0.5 * (1.0 + np.cos(4.0 * np.pi * (phase - BOUNCE_LOW)))
        dip = np.zeros((k, 3))
        dip[:, 2] = -(bounciness - 1.0) * BOUNCE_DIP * h * shape
        offset = dip if offset is None else offset + dip
    w_stance = side_st * (half_width - half_hips - sway)
    w_swing = side_st * (half_hips - half_width - sway)
    phi = phi_st.copy()
    if offset is not None:
        f = pk.as_rows  # _shifted_stance_leg
        phi[:, 1], phi[:, 2] = pk.shifted_stance_leg(
            f(thigh, (k,)), f(shank, (k,)), f(phi[:, 1], (k,)), f(phi[:, 2], (k,)),
            f(heading, (k,)), f(offset, (k, 3)))
        w_stance = w_stance - np.einsum("ka,ka->k", offset, normal)
    lst = side_st * list_amplitude * list_shape
    if list_scale is not None:
        lst = lst * list_scale
    tilt_data = 0.5 * (phi_st[:, 3] + phi_sw[:, 3])
    return side_st, normal, w_stance, w_swing, phi, lst, heading + rotation, tilt_data


@pytest.mark.parametrize("k", [1, 2, 3, 7, 64, 3000])
@pytest.mark.parametrize("styled, shifted, scaled", [(True, True, True), (False, True, False),
                                                     (True, False, True), (False, False, True)])
def test_stance_terms_are_the_numpy_code(k, styled, shifted, scaled):
    left = RNG.random(k) < 0.5
    h, hips = RNG.uniform(1.4, 2.0, k), RNG.uniform(0.15, 0.3, k)
    width = RNG.uniform(0.0, 0.4, k)
    phase = RNG.uniform(0.0, 0.5, k)
    phase[:3] = [0.0, 0.25, 0.5 - 1e-6][:k]
    heading = RNG.uniform(-4.0, 4.0, k)
    heading[: min(k, 2)] = [-0.0, 0.0][: min(k, 2)]  # signed zeros stay as numpy adds them
    amp, shape, scale = RNG.uniform(0, 0.2, k), RNG.uniform(-1, 1, k), RNG.uniform(0, 1, k)
    rot_amp, rot_shape = RNG.uniform(0, 0.3, k), RNG.uniform(-1, 1, k)
    bounce = RNG.uniform(0.0, 4.0, k)
    phi_st, phi_sw = RNG.uniform(-0.6, 0.6, (k, 4)), RNG.uniform(-0.6, 0.6, (k, 4))
    thigh = RNG.uniform(0.38, 0.5, k)
    shank = thigh * RNG.uniform(0.85, 1.05, k)
    offset = RNG.normal(0.0, 0.03, (k, 3)) * (RNG.random((k, 1)) < 0.8)  # zero rows too
    zeros = np.zeros(k)
    want = _stance_terms_numpy(left, h, hips, width, 0.012, phase, amp, shape,
                               scale if scaled else None, rot_amp, rot_shape, styled, bounce,
                               heading, phi_st, phi_sw, thigh, shank,
                               offset if shifted else None)  # fmt: skip
    got = ek.stance_terms(
        left, h, hips, width, 0.012, np.sin(2.0 * np.pi * phase), amp, shape,
        scale if scaled else zeros, scaled, rot_amp if styled else zeros, rot_shape, styled,
        bounce if styled else zeros, BOUNCE_DIP,
        np.cos(4.0 * np.pi * (phase - BOUNCE_LOW)) if styled else zeros, heading,
        np.cos(heading), np.sin(heading), phi_st, phi_sw, thigh, shank,
        offset if shifted else np.zeros((k, 3)), shifted)  # fmt: skip
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        _same(g, w)


def test_pelvis_hips_are_the_numpy_code():
    k = 5000
    yaw, lst, tilt = (RNG.uniform(-4, 4, k), RNG.uniform(-0.3, 0.3, k),
                      RNG.uniform(-0.4, 0.4, k))  # fmt: skip
    yaw[:2] = [-0.0, 0.0]
    hip_st = RNG.normal(0.0, 20.0, (k, 3))
    side = np.where(RNG.random(k) < 0.5, 1.0, -1.0)
    hips = RNG.uniform(0.15, 0.3, k)
    # elevwalker_pose before pose19
    r_pelvis = pk.pelvis_rotations(yaw, lst, tilt)
    y_pelvis = r_pelvis[:, :, 1]
    half_hips = 0.5 * hips
    root = hip_st - (side * half_hips)[:, None] * y_pelvis
    hip_sw = root - (side * half_hips)[:, None] * y_pelvis
    got = ek.pelvis_hips(yaw, lst, tilt, hip_st, side, hips)
    for g, w in zip(got, (r_pelvis, root, hip_sw), strict=True):
        _same(g, w)


def _swing_goal_numpy(ankle_sw, swing_offset, swing_target, swing_blend, swing_goal):
    """elevwalker_pose's swing-ankle goal before pose19 (None: not given)."""
    k = ankle_sw.shape[0]
    goal = ankle_sw.copy()
    use = np.zeros(k, dtype=bool)
    if swing_offset is not None:
        offset = np.asarray(swing_offset, dtype=float)
        goal += offset
        use |= np.any(offset != 0.0, axis=1)
    if swing_target is not None and swing_blend is not None:
        blend = np.clip(np.asarray(swing_blend, dtype=float), 0.0, 1.0)
        goal += blend[:, None] * (np.asarray(swing_target, dtype=float) - goal)
        use |= blend > 0
    if swing_goal is not None:
        absolute = np.asarray(swing_goal, dtype=float)
        pinned = np.isfinite(absolute).all(axis=1)
        goal = np.where(pinned[:, None], absolute, goal)
        use |= pinned
    return goal, use


@pytest.mark.parametrize("given", [(True, True, True), (True, False, False),
                                   (False, True, False), (False, False, True),
                                   (True, True, False)])
def test_swing_goal_is_the_numpy_code(given):
    k = 4000
    ankle = RNG.normal(0.0, 10.0, (k, 3))
    offset = RNG.normal(0.0, 0.05, (k, 3)) * (RNG.random((k, 1)) < 0.7)  # zero rows too
    offset[:5] = [-0.0, 0.0, -0.0]
    target = RNG.normal(0.0, 10.0, (k, 3))
    blend = RNG.uniform(-0.5, 1.5, k)  # clipped both ways
    blend[:4] = [np.nan, 0.0, 1.0, -0.0]
    absolute = np.where(RNG.random((k, 1)) < 0.3, RNG.normal(0.0, 10.0, (k, 3)), np.nan)
    absolute[:20:4, 1] = np.inf  # a non-finite entry: not pinned
    absolute[1:20:4, 0] = 1.0  # part-NaN rows: not pinned
    has_offset, has_target, has_absolute = given
    want = _swing_goal_numpy(ankle, offset if has_offset else None,
                             target if has_target else None, blend if has_target else None,
                             absolute if has_absolute else None)  # fmt: skip
    none3 = np.zeros((k, 3))
    got = ek.swing_goal(ankle, offset if has_offset else none3, has_offset,
                        target if has_target else none3,
                        blend if has_target else np.zeros(k), has_target,
                        absolute if has_absolute else none3, has_absolute)  # fmt: skip
    for g, w in zip(got, want, strict=True):
        _same(g, w)


def _styled_upper_body_numpy(local, r_pelvis, heading, phase, side_st, thigh_left,
                             thigh_right, a, from_data):
    """elevwalker._styled_upper_body before pose19 (its terms in numpy, then pose16's
    ``posing_kernels.upper_body``)."""
    tilt = a.torso_tilt
    if from_data:
        motion = trunk_motion()
        shoulder = -side_st * a.shoulder_rotation * motion.rotation_shape(phase)
        tilt = tilt + motion.tilt_wave(phase)
    else:
        shoulder = side_st * a.shoulder_rotation * np.cos(2.0 * np.pi * phase)
    sway = -side_st * a.torso_sway * np.sin(2.0 * np.pi * phase)
    k = local.shape[0]
    arm_out, swing, elbow = np.empty((k, 2)), np.empty((k, 2)), np.empty((k, 2))
    for s, (thigh, sign) in enumerate(((thigh_right, 1.0), (thigh_left, -1.0))):
        signal = np.clip((thigh - THIGH_MID) / THIGH_HALF, -1.0, 1.0)
        arm_out[:, s] = sign * a.arm_out
        swing[:, s] = -a.arm_swing * signal
        elbow[:, s] = -(a.elbow_min + (a.elbow_max - a.elbow_min) * 0.5 * (signal + 1.0))
    pk.upper_body(local, np.ascontiguousarray(r_pelvis), heading + shoulder, sway, tilt,
                  heading, arm_out, swing, elbow, JOINT["vl5"], JOINT["skullbase"],
                  np.array([JOINT["l_shoulder"], JOINT["r_shoulder"]]),
                  np.array([JOINT["l_elbow"], JOINT["r_elbow"]]))


@pytest.mark.parametrize("from_data", [True, False])
def test_styled_upper_body_is_the_numpy_code(from_data):
    k, nj = 3000, len(JOINT_NAMES)
    attributes = SimpleNamespace(**{name: RNG.uniform(lo, hi, k) for name, lo, hi in (
        ("shoulder_rotation", 0.0, 0.4), ("torso_tilt", -0.2, 0.3), ("torso_sway", 0.0, 0.1),
        ("arm_out", 0.0, 0.4), ("arm_swing", 0.0, 0.8), ("elbow_min", 0.0, 0.5),
        ("elbow_max", 0.5, 1.5))})  # fmt: skip
    local = RNG.normal(size=(k, nj, 3, 3))
    want = local.copy()
    r_pelvis = pk.pelvis_rotations(*(RNG.uniform(-3, 3, k) for _ in range(3)))
    heading, phase = RNG.uniform(-4, 4, k), RNG.uniform(0.0, 0.5, k)
    left = RNG.random(k) < 0.5
    side = np.where(left, 1.0, -1.0)
    phi_st, phi_sw = RNG.uniform(-0.8, 0.8, (k, 4)), RNG.uniform(-0.8, 0.8, (k, 4))
    thigh_left = np.where(left, phi_st[:, 2], phi_sw[:, 2])
    thigh_right = np.where(left, phi_sw[:, 2], phi_st[:, 2])
    _styled_upper_body_numpy(want, r_pelvis, heading, phase, side, thigh_left, thigh_right,
                             attributes, from_data)  # fmt: skip
    ek.styled_upper_body(local, *_upper_body_arguments(
        k, r_pelvis, heading, phase, left, side, phi_st, phi_sw, attributes,
        GaitStyle(trunk_from_data=from_data)))
    _same(local, want)
    assert (np.abs((thigh_left - THIGH_MID) / THIGH_HALF) > 1).any()  # clipped arms too
