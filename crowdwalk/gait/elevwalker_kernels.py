"""Compiled per-agent arithmetic of :func:`crowdwalk.gait.elevwalker.elevwalker_pose`
between its solves: the stance side's terms, the pelvis and hips, the swing-ankle goal,
the KLAW upper body's terms.

``elevwalker_pose`` combined its (k,) columns in ~100 small numpy operations, a fixed
~0.25 ms per call (1,269 calls, 214,410 rows in the replay of the 1,000-walker stadium;
docs/architecture.md, "Posing speed"). These nogil kernels do the same arithmetic per
agent in the numpy code's order, so they give its values bit for bit: ``np.clip``'s NaN
semantics, ``einsum("ka,ka->k")`` of three summed as (x0 + x2) + x1 (measured: the other
orders differ in ~20 % of rows). Transcendental functions stay numpy's, computed by the
caller and passed in (``tan``, ``arctan`` differ from glibc's, numba's, on this AVX-512
CPU; ``sin``, ``cos`` of the heading and the phase are passed in as well).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from crowdwalk.gait.animator_kernels import _clip
from crowdwalk.gait.posing_kernels import pelvis_rotations, shifted_stance_leg, upper_body

__all__ = ["pelvis_hips", "stance_terms", "styled_upper_body", "swing_goal"]

_jit = nb.njit(cache=True, nogil=True)


@_jit
def stance_terms(left, height, hip_separation, width, sway, sin_phase, list_amplitude,
                 list_shape, list_scale, scaled, rotation_amplitude, rotation_shape, styled,
                 bounciness, dip_amplitude, dip_cos, heading, cos_heading, sin_heading, phi_st,
                 phi_sw, thigh, shank, offset, shifted):  # pragma: no cover - compiled
    """The stance side's terms of k agents.

    ``left`` (k,) bool stance side; ``height``, ``hip_separation``, ``width`` (stance
    width: the style's ``step_width`` H or the stride width) (k,) [m]; ``sway`` the
    style's amplitude [1], ``sin_phase`` sin 2πt (k,); the list's amplitude (k,) [rad],
    shape (k,) and factor (k,) (where ``scaled``); the pelvic rotation's amplitude (k,)
    [rad] and shape (k,) (where ``styled``); the bounciness (k,) [1] (where ``styled``),
    ``dip_amplitude`` [body heights] and cos 4π(t − low) (k,); heading (k,) [rad] and its
    cos, sin; stance and swing elevations (k, 4) [rad]; thigh, shank (k,)
    [m]; the stance hip's offset (k, 3) [m] (where ``shifted``; with ``styled`` the dip is
    added to it).

    Returns side (k,) (+1 left stance), the sagittal normal (k, 3), Eq. 8's stance width
    (k,) [m] less offset · normal, the swing width (k,) [m], the stance elevations (k, 4)
    [rad] (shank and thigh moved by the offset: ``posing_kernels.shifted_stance_leg``),
    the list L (k,) [rad], the pelvis's yaw ψ + rotation (k,) [rad] and the data tilt
    (k,) [rad]; elevwalker_pose's values.
    """
    k = left.shape[0]
    side, w_stance, w_swing = np.empty(k), np.empty(k), np.empty(k)
    normal, off = np.empty((k, 3)), np.empty((k, 3))
    lst, yaw, tilt_data = np.empty(k), np.empty(k), np.empty(k)
    phi = phi_st.copy()
    move = shifted or styled
    for r in range(k):
        s = 1.0 if left[r] else -1.0
        side[r] = s
        half_hips = 0.5 * hip_separation[r]
        sw = sway * height[r] * sin_phase[r]
        half_width = 0.5 * width[r]
        w_stance[r] = s * (half_width - half_hips - sw)
        w_swing[r] = s * (half_hips - half_width - sw)
        normal[r, 0], normal[r, 1], normal[r, 2] = -sin_heading[r], cos_heading[r], 0.0
        rotation = -s * rotation_amplitude[r] * rotation_shape[r] if styled else 0.0
        yaw[r] = heading[r] + rotation
        x = s * list_amplitude[r] * list_shape[r]
        lst[r] = x * list_scale[r] if scaled else x
        tilt_data[r] = 0.5 * (phi_st[r, 3] + phi_sw[r, 3])
        for a in range(3):
            off[r, a] = offset[r, a] if shifted else 0.0
        if styled:  # _bounce_dip: 0, 0, down; added to the offset (or the offset itself)
            dip = -(bounciness[r] - 1.0) * dip_amplitude * height[r] * (0.5 * (1.0 + dip_cos[r]))
            if shifted:
                off[r, 0], off[r, 1], off[r, 2] = off[r, 0] + 0.0, off[r, 1] + 0.0, \
                    off[r, 2] + dip
            else:
                off[r, 0], off[r, 1], off[r, 2] = 0.0, 0.0, dip
        if move:
            dot = (off[r, 0] * normal[r, 0] + off[r, 2] * normal[r, 2]) + off[r, 1] * normal[r, 1]
            w_stance[r] = w_stance[r] - dot
    if move:
        shank_new, thigh_new = shifted_stance_leg(thigh, shank, phi_st[:, 1].copy(),
                                                  phi_st[:, 2].copy(), heading, off)
        for r in range(k):
            phi[r, 1], phi[r, 2] = shank_new[r], thigh_new[r]
    return side, normal, w_stance, w_swing, phi, lst, yaw, tilt_data


@_jit
def pelvis_hips(yaw, lst, tilt, hip_st, side, hip_separation):  # pragma: no cover - compiled
    """Pelvis rotations (k, 3, 3) ``rotation_z(yaw) @ rotation_x(lst) @ rotation_y(tilt)``
    (angles (k,) [rad]), the root (k, 3) [m] half the hip separation from the stance hip
    ``hip_st`` (k, 3) [m] along the pelvis's y axis (toward the swing side: side (k,), +1
    left stance) and the swing hip (k, 3) [m] as far beyond; elevwalker_pose's values."""
    r_pelvis = pelvis_rotations(yaw, lst, tilt)
    k = yaw.shape[0]
    root, hip_sw = np.empty((k, 3)), np.empty((k, 3))
    for r in range(k):
        half = side[r] * (0.5 * hip_separation[r])
        for a in range(3):
            y = r_pelvis[r, a, 1]
            root[r, a] = hip_st[r, a] - half * y
            hip_sw[r, a] = root[r, a] - half * y
    return r_pelvis, root, hip_sw


@_jit
def swing_goal(ankle_sw, offset, has_offset, target, blend, has_target, absolute,
               has_absolute):  # pragma: no cover - compiled
    """The swing ankle's goal (k, 3) [m] and where it is used (k,) bool: the data's ankle
    ``ankle_sw`` (k, 3) [m] plus ``offset`` (k, 3) [m] (used where non-zero), blended
    toward ``target`` (k, 3) [m] by ``blend`` (k,) clipped to [0, 1] (used where > 0),
    replaced by ``absolute`` (k, 3) [m] where its row is finite (used there); each where
    its flag is set. elevwalker_pose's values."""
    k = ankle_sw.shape[0]
    goal = ankle_sw.copy()
    use = np.zeros(k, np.bool_)
    for r in range(k):
        if has_offset:
            for a in range(3):
                goal[r, a] = goal[r, a] + offset[r, a]
                use[r] |= offset[r, a] != 0.0
        if has_target:
            b = _clip(blend[r], 0.0, 1.0)
            for a in range(3):
                goal[r, a] = goal[r, a] + b * (target[r, a] - goal[r, a])
            use[r] |= b > 0.0
        if has_absolute:
            pinned = (np.isfinite(absolute[r, 0]) and np.isfinite(absolute[r, 1])
                      and np.isfinite(absolute[r, 2]))
            if pinned:
                for a in range(3):
                    goal[r, a] = absolute[r, a]
                use[r] = True
    return goal, use


@_jit
def styled_upper_body(local, r_pelvis, heading, left, side, phi_st, phi_sw, from_data,
                      shoulder_shape, tilt_wave, sin_phase, shoulder_rotation, torso_tilt,
                      torso_sway, arm_out, arm_swing, elbow_min, elbow_max, thigh_mid,
                      thigh_half, vl5, skullbase, shoulders, elbows
                      ):  # pragma: no cover - compiled
    """``elevwalker._upper_body_arguments``' terms of k walkers, then
    ``posing_kernels.upper_body`` into ``local`` (k, J, 3, 3): the shoulders' rotation
    −side · rotation · shape (``from_data``: the trunk's measured shape) or side ·
    rotation · cos 2πt (``shoulder_shape`` the one or the other, (k,)), the tilt plus
    ``tilt_wave`` (k,) [rad] where ``from_data``, the sway −side · sway · sin 2πt, each arm
    with the opposite thigh's elevation (``phi_st``, ``phi_sw`` (k, 4) [rad], ``left``
    (k,) bool stance side) normalised by ``thigh_mid``, ``thigh_half`` [rad] and clipped
    to [−1, 1]. Attributes (k,) [rad]; joint indices into J. Its numpy code's values."""
    k = local.shape[0]
    yaw, sway, tilt = np.empty(k), np.empty(k), np.empty(k)
    out, swing, elbow = np.empty((k, 2)), np.empty((k, 2)), np.empty((k, 2))
    for r in range(k):
        s = -side[r] if from_data else side[r]
        yaw[r] = heading[r] + s * shoulder_rotation[r] * shoulder_shape[r]
        tilt[r] = torso_tilt[r] + tilt_wave[r] if from_data else torso_tilt[r]
        sway[r] = -side[r] * torso_sway[r] * sin_phase[r]
        thigh_left = phi_st[r, 2] if left[r] else phi_sw[r, 2]
        thigh_right = phi_sw[r, 2] if left[r] else phi_st[r, 2]
        for a in range(2):  # left arm with the right thigh, right arm with the left
            thigh, sign = (thigh_right, 1.0) if a == 0 else (thigh_left, -1.0)
            signal = _clip((thigh - thigh_mid) / thigh_half, -1.0, 1.0)
            out[r, a] = sign * arm_out[r]
            swing[r, a] = -arm_swing[r] * signal
            elbow[r, a] = -(elbow_min[r] + (elbow_max[r] - elbow_min[r]) * 0.5 * (signal + 1.0))
    upper_body(local, r_pelvis, yaw, sway, tilt, heading, out, swing, elbow, vl5, skullbase,
               shoulders, elbows)
