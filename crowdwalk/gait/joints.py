"""Compiled last stage of ElevWalker: swing-leg IK, swing foot and the joint rotations.

One agent at a time (numba), after the two Gauss–Newton solves of
:mod:`crowdwalk.gait.complexes`: the optional two-link IK that pulls the swing ankle to
its goal, the analytic swing talocrural angle for the data foot elevation (§4.2), the
push-off toe angle, and the local rotations of every joint (legs §4.3, upper body §8) in
the order of :data:`crowdwalk.body.JOINT_NAMES` (BVH semantics, identity elsewhere).
The arithmetic is :func:`crowdwalk.gait.elevwalker.elevwalker_pose`'s, row by row.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from crowdwalk.body import JOINT, LEG_JOINTS
from crowdwalk.gait.complexes import (
    _matmul,
    _rodrigues,
    _times_rotation_y,
    _wrap,
)

__all__ = ["assemble_arguments"]

_jit = nb.njit(cache=True, nogil=True)
_VL5, _SHOULDER, _ELBOW = JOINT["vl5"], (JOINT["l_shoulder"], JOINT["r_shoulder"]), (
    JOINT["l_elbow"], JOINT["r_elbow"])  # fmt: skip


@_jit
def _rot_y(angle, out):
    c, s = np.cos(angle), np.sin(angle)
    out[:] = 0.0
    out[0, 0], out[0, 2], out[1, 1], out[2, 0], out[2, 2] = c, s, 1.0, -s, c


@_jit
def _rot_x(angle, out):
    c, s = np.cos(angle), np.sin(angle)
    out[:] = 0.0
    out[0, 0], out[1, 1], out[1, 2], out[2, 1], out[2, 2] = 1.0, c, -s, s, c


@_jit
def _rot_z(angle, out):
    c, s = np.cos(angle), np.sin(angle)
    out[:] = 0.0
    out[0, 0], out[0, 1], out[1, 0], out[1, 1], out[2, 2] = c, -s, s, c, 1.0


@_jit
def _t_matmul(a, b, out):
    """out = aᵀ @ b."""
    for i in range(3):
        for j in range(3):
            out[i, j] = a[0, i] * b[0, j] + a[1, i] * b[1, j] + a[2, i] * b[2, j]


@_jit
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@_jit
def _single_dof_forward(parent, axis, ch, sh, phi):
    """:func:`crowdwalk.gait.elevwalker.solve_single_dof` for the segment w = +x (the
    foot, heel→toe): joint angle [rad] and whether it reaches φ."""
    qw = axis[0]  # axis · w
    wc = (1.0 - axis[0] * qw, -axis[1] * qw, -axis[2] * qw)
    ws = (0.0, axis[2], -axis[1])  # axis × w
    wq = (axis[0] * qw, axis[1] * qw, axis[2] * qw)
    d, e, f = np.empty(3), np.empty(3), np.empty(3)
    for a in range(3):
        d[a] = parent[a, 0] * wc[0] + parent[a, 1] * wc[1] + parent[a, 2] * wc[2]
        e[a] = parent[a, 0] * ws[0] + parent[a, 1] * ws[1] + parent[a, 2] * ws[2]
        f[a] = parent[a, 0] * wq[0] + parent[a, 1] * wq[1] + parent[a, 2] * wq[2]
    cphi, sphi = np.cos(phi), np.sin(phi)
    hd, he, hf = d[0] * ch + d[1] * sh, e[0] * ch + e[1] * sh, f[0] * ch + f[1] * sh
    A, B, C = hd * cphi + d[2] * sphi, he * cphi + e[2] * sphi, hf * cphi + f[2] * sphi
    R = np.hypot(A, B)
    ratio = -C / (R if R > 1e-12 else 1e-12)
    ok = abs(ratio) <= 1.0 and R > 1e-12
    base = np.arctan2(B, A)
    delta = np.arccos(min(max(ratio, -1.0), 1.0))
    best, score = 0.0, -np.inf
    for cand in (base + delta, base - delta):
        c, s = np.cos(cand), np.sin(cand)
        g = (hd * c + he * s + hf) * sphi - (d[2] * c + e[2] * s + f[2]) * cphi
        if g > score:
            best, score = cand, g
    return _wrap(best), ok and score > 1e-6


@_jit
def _two_link_ik(hip, goal, r_thigh, l1, l2, out):
    """:func:`crowdwalk.gait.elevwalker._two_link_ik` for one leg: fills the thigh
    orientation ``out`` (3, 3), returns the knee angle [rad]."""
    to_goal = goal - hip
    dist = np.sqrt(to_goal[0] ** 2 + to_goal[1] ** 2 + to_goal[2] ** 2)
    dist_c = min(max(dist, abs(l1 - l2) + 1e-6), 0.999 * (l1 + l2))
    u = to_goal / max(dist, 1e-9)
    y_old, x_old = r_thigh[:, 1], r_thigh[:, 0]
    y_axis = y_old - u * (y_old[0] * u[0] + y_old[1] * u[1] + y_old[2] * u[2])
    y_axis /= max(np.sqrt(y_axis[0] ** 2 + y_axis[1] ** 2 + y_axis[2] ** 2), 1e-12)
    v = np.empty(3)
    _cross(y_axis, u, v)  # in the leg plane, perpendicular to the hip→goal line
    if v[0] * x_old[0] + v[1] * x_old[1] + v[2] * x_old[2] < 0:
        v = -v  # knee forward
    cos_b = min(max((l1**2 + dist_c**2 - l2**2) / (2 * l1 * dist_c), -1.0), 1.0)
    sin_b = np.sqrt(1.0 - cos_b**2)
    knee_new = hip + l1 * (cos_b * u + sin_b * v)
    ankle_new = hip + dist_c * u
    z_axis = (hip - knee_new) / l1
    x_axis = np.empty(3)
    _cross(y_axis, z_axis, x_axis)
    for a in range(3):
        out[a, 0], out[a, 1], out[a, 2] = x_axis[a], y_axis[a], z_axis[a]
    shank = ankle_new - knee_new
    s0 = out[0, 0] * shank[0] + out[1, 0] * shank[1] + out[2, 0] * shank[2]
    s2 = out[0, 2] * shank[0] + out[1, 2] * shank[1] + out[2, 2] * shank[2]
    return np.arctan2(-s0, -s2)


@_jit
def _assemble(left, phase, heading, stance_fraction, r_pelvis, r_thigh_st, knee_st,
              tc_st, sub_st, x_ankle, toe_st, hip_sw, r_thigh_sw, knee_sw, r_shank_sw,
              tc_sw, phi_sw, phi_st, thigh, shank, ik, use, goal, toe_given, arm_swing,
              elbow_flexion, n_joints):  # fmt: skip
    k = phase.shape[0]
    local = np.zeros((k, n_joints, 3, 3))
    knee_out = np.empty(k)
    ok_foot = np.zeros(k, np.bool_)
    thigh_ik, shank_sw, foot_sw = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    m = np.empty((3, 3))
    legs = LEG_JOINTS
    for i in range(k):
        for j in range(n_joints):
            for a in range(3):
                local[i, j, a, a] = 1.0
        r_thigh = r_thigh_sw[i]
        knee = knee_sw[i]
        shank_sw[:] = r_shank_sw[i]
        if ik:  # swing ankle pulled to its goal where asked, r_shank re-formed for all
            if use[i]:
                knee = _two_link_ik(hip_sw[i], goal[i], r_thigh_sw[i], thigh[i], shank[i],
                                    thigh_ik)  # fmt: skip
                r_thigh = thigh_ik
            _times_rotation_y(r_thigh, np.cos(knee), np.sin(knee), shank_sw)
        knee_out[i] = knee
        # swing talocrural for the foot elevation (heel→toe is π/2 + φ from the vertical)
        ch, sh = np.cos(heading[i]), np.sin(heading[i])
        ang, ok_foot[i] = _single_dof_forward(shank_sw, tc_sw[i], ch, sh,
                                              0.5 * np.pi + phi_sw[i, 0])  # fmt: skip
        _rodrigues(tc_sw[i], ang, m)
        _matmul(shank_sw, m, foot_sw)
        pitch = np.arcsin(min(max(foot_sw[2, 0], -1.0), 1.0))
        push = stance_fraction[i] - 0.5 + 0.05
        flat = 1.0 - min(max(phase[i] / push, 0.0), 1.0) ** 2
        toe_sw = toe_given[i] if np.isfinite(toe_given[i]) else flat * min(pitch, 0.0)
        st = legs[0] if left[i] else legs[1]
        sw = legs[1] if left[i] else legs[0]
        loc = local[i]
        loc[0] = r_pelvis[i]
        _t_matmul(r_pelvis[i], r_thigh_st[i], loc[st[0]])
        _rot_y(-knee_st[i], loc[st[1]])
        _rodrigues(tc_st[i], x_ankle[i, 0], loc[st[2]])
        _rodrigues(sub_st[i], x_ankle[i, 1], loc[st[3]])
        _rot_y(toe_st[i], loc[st[4]])
        _t_matmul(r_pelvis[i], r_thigh, loc[sw[0]])
        _rot_y(knee, loc[sw[1]])
        _rodrigues(tc_sw[i], ang, loc[sw[2]])
        _rot_y(toe_sw, loc[sw[4]])
        # §8: trunk upright along ψ, arms swing with the opposite thigh
        _rot_z(heading[i], m)
        _t_matmul(r_pelvis[i], m, loc[_VL5])
        thigh_left = phi_st[i, 2] if left[i] else phi_sw[i, 2]
        thigh_right = phi_sw[i, 2] if left[i] else phi_st[i, 2]
        for side in range(2):
            arm = arm_swing * (thigh_right if side == 0 else thigh_left)
            _rot_y(-arm, m)
            _rot_x(0.08 if side == 0 else -0.08, foot_sw)
            _matmul(m, foot_sw, loc[_SHOULDER[side]])
            _rot_y(-(elbow_flexion + 0.5 * max(arm, 0.0)), loc[_ELBOW[side]])
    return local, knee_out, ok_foot


def assemble_arguments(left, phase, heading, stance_fraction, r_pelvis, r_thigh_st, knee_st,
                       tc_st, sub_st, x_ankle, toe_st, hip_sw, r_thigh_sw, knee_sw,
                       r_shank_sw, tc_sw, phi_sw, phi_st, thigh, shank, use, goal, toe_given,
                       arm_swing, elbow_flexion, n_joints) -> list:  # fmt: skip
    """The arguments of the compiled ``_assemble`` (a list, for a caller that runs it on
    parts of the rows with more after it), which returns the local joint rotations (k, J,
    3, 3) of k walkers, the swing knee angle (k,) [rad] and whether the swing talocrural
    angle reaches the data foot elevation (k,).

    Parameters
    ----------
    left : (k,) bool, the left leg is the stance leg.
    phase : (k,) stance phase t [1]; heading : (k,) ψ [rad]; stance_fraction : (k,) [1].
    r_pelvis, r_thigh_st : (k, 3, 3) world orientations; knee_st : (k,) stance knee [rad].
    tc_st, sub_st : (k, 3) stance talocrural/subtalar axes; x_ankle : (k, 2) their angles
        [rad]; toe_st : (k,) stance toe angle [rad].
    hip_sw : (k, 3) swing hip [m]; r_thigh_sw, r_shank_sw : (k, 3, 3); knee_sw : (k,)
        [rad] — the swing hip solve; tc_sw : (k, 3) swing talocrural axes.
    phi_sw, phi_st : (k, 4) data elevations of the swing and stance legs [rad].
    thigh, shank : (k,) [m].
    use : (k,) bool or None, where the swing ankle goes to ``goal`` (k, 3) [m] by
        two-link IK (None: no IK stage).
    toe_given : (k,) swing toe angle [rad] where finite.
    arm_swing, elbow_flexion : the style's §8 parameters; n_joints : J.
    """
    k = len(phase)
    f = np.ascontiguousarray
    ik = use is not None
    use = np.zeros(k, np.bool_) if use is None else f(use, dtype=np.bool_)
    goal = np.zeros((k, 3)) if goal is None else f(goal, dtype=float)
    return [
        f(left, dtype=np.bool_), f(phase, dtype=float), f(heading, dtype=float),
        f(np.broadcast_to(stance_fraction, (k,)), dtype=float), f(r_pelvis),
        f(r_thigh_st), f(knee_st), f(tc_st), f(sub_st), f(x_ankle), f(toe_st),
        f(hip_sw), f(r_thigh_sw), f(knee_sw), f(r_shank_sw), f(tc_sw),
        f(phi_sw, dtype=float), f(phi_st, dtype=float), f(thigh), f(shank), ik,
        use, goal, f(np.broadcast_to(toe_given, (k,)), dtype=float),
        float(arm_swing), float(elbow_flexion), int(n_joints),
    ]  # fmt: skip
