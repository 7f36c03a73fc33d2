"""Compiled rotation chains of ElevWalker's pose (pelvis, trunk, arms), bit for bit.

numpy's stacked 3×3 product ``a @ b`` (OpenBLAS's dgemm on this machine) computes each
entry as a fused multiply-add chain over the inner index, ``fma(a2, b2, fma(a1, b1,
a0 b0))``, not as the rounded sum of three products (measured: 0 of 180,000 entries
differ from that chain on random matrices, a third differ from the plain sum).
:func:`_mm` and :func:`_tmm` reproduce it with LLVM's ``fma`` intrinsic, so the kernels
here give the numpy code's values exactly (docs/architecture.md, "Posing speed").
Elementary rotations are built as :func:`crowdwalk.body.rotation_x` (``_y``, ``_z``)
builds them (exact zeros and ones included, which the chains multiply too).
"""

from __future__ import annotations

import numba as nb
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

__all__ = ["as_rows", "pelvis_rotations", "shifted_stance_leg", "smooth_one", "smoothstep",
           "stance_foot", "upper_body"]

_jit = nb.njit(cache=True, nogil=True)


def as_rows(values, shape: tuple) -> np.ndarray:
    """``values`` (a scalar or an array broadcastable to ``shape``) as a C-contiguous
    float64 array of ``shape`` for the kernels (itself where it is one already)."""
    if (isinstance(values, np.ndarray) and values.shape == shape
            and values.dtype == np.float64 and values.flags.c_contiguous):
        return values
    return np.ascontiguousarray(np.broadcast_to(np.asarray(values, dtype=float), shape))


@intrinsic
def _fma(typingctx, a, b, c):
    """a·b + c rounded once (LLVM ``llvm.fma.f64``)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(d, [d, d, d]),
                                            "llvm.fma.f64")
        return builder.call(fn, args)

    return sig, codegen


@_jit
def _mm(a, b, out):  # pragma: no cover - compiled
    """out = a @ b (3, 3) as numpy computes it (fma chain over the inner index)."""
    for i in range(3):
        for j in range(3):
            x = a[i, 0] * b[0, j]
            x = _fma(a[i, 1], b[1, j], x)
            out[i, j] = _fma(a[i, 2], b[2, j], x)


@_jit
def _tmm(a, b, out):  # pragma: no cover - compiled
    """out = aᵀ @ b (3, 3) as numpy computes ``np.swapaxes(a, -1, -2) @ b``."""
    for i in range(3):
        for j in range(3):
            x = a[0, i] * b[0, j]
            x = _fma(a[1, i], b[1, j], x)
            out[i, j] = _fma(a[2, i], b[2, j], x)


@_jit
def _elementary(angle, i, j, out):  # pragma: no cover - compiled
    """Rotation (3, 3) in the (i, j) plane: ``crowdwalk.body._elementary_kernel``."""
    k = 3 - i - j
    c, s = np.cos(angle), np.sin(angle)
    for r in range(3):
        for q in range(3):
            out[r, q] = 0.0
    out[k, k] = 1.0
    out[i, i] = c
    out[j, j] = c
    out[i, j] = -s
    out[j, i] = s


@_jit
def pelvis_rotations(yaw, lst, tilt):  # pragma: no cover - compiled
    """(k, 3, 3) ``rotation_z(yaw) @ rotation_x(lst) @ rotation_y(tilt)`` of angles (k,)
    [rad], numpy's values."""
    k = yaw.shape[0]
    out = np.empty((k, 3, 3))
    a, b, ab = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    for r in range(k):
        _elementary(yaw[r], 0, 1, a)
        _elementary(lst[r], 1, 2, b)
        _mm(a, b, ab)
        _elementary(tilt[r], 2, 0, b)
        _mm(ab, b, out[r])
    return out


@_jit
def upper_body(local, r_pelvis, yaw_angle, sway, tilt, heading, arm_out, swing, elbow,
               vl5, skullbase, shoulder, elbow_joint):  # pragma: no cover - compiled
    """The KLAW upper body (``elevwalker._upper_body_arguments``) into ``local`` (k, J, 3,
    3), row by row, numpy's values: trunk = Rz(yaw_angle) Rx(sway) Ry(tilt); vl5 =
    r_pelvisᵀ trunk; skullbase = trunkᵀ Rz(heading); per arm s (0 left, 1 right) the
    shoulder trunkᵀ Rz(yaw_angle) Rx(arm_out[:, s]) Ry(swing[:, s]) and the elbow
    Ry(elbow[:, s]). Angles (k,) or (k, 2) [rad]; joint indices into J."""
    yaw, m, ab = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    trunk, upper = np.empty((3, 3)), np.empty((3, 3))
    for r in range(local.shape[0]):
        _elementary(yaw_angle[r], 0, 1, yaw)
        _elementary(sway[r], 1, 2, m)
        _mm(yaw, m, ab)
        _elementary(tilt[r], 2, 0, m)
        _mm(ab, m, trunk)
        _tmm(r_pelvis[r], trunk, local[r, vl5])
        _elementary(heading[r], 0, 1, m)
        _tmm(trunk, m, local[r, skullbase])
        for s in range(2):
            _elementary(arm_out[r, s], 1, 2, m)
            _mm(yaw, m, ab)
            _elementary(swing[r, s], 2, 0, m)
            _mm(ab, m, upper)
            _tmm(trunk, upper, local[r, shoulder[s]])
            _elementary(elbow[r, s], 2, 0, local[r, elbow_joint[s]])


@_jit
def stance_foot(yaw, slope, pitch, ball, heel_offset, ball_offset, ankle_height
                ):  # pragma: no cover - compiled
    """``crowdwalk.gait.foot.stance_foot_pose`` of k feet, numpy's values: foot rotations
    (k, 3, 3) Rz(yaw) Ry(−pitch), ankles (k, 3) [m] (the pivot, heel or ball, plus the
    rotated pivot→ankle offset, summed as numpy's ``einsum("kab,kb->ka")`` sums: (b0 +
    b2) + b1) and toe angles (k,) [rad]. Angles (k,) [rad], ball (k, 3) [m], dimensions
    (k,) [m]."""
    k = yaw.shape[0]
    r_foot, ankle, toe = np.empty((k, 3, 3)), np.empty((k, 3)), np.empty(k)
    rz, ry = np.empty((3, 3)), np.empty((3, 3))
    pivot, local = np.empty(3), np.empty(3)
    for r in range(k):
        _elementary(yaw[r], 0, 1, rz)
        _elementary(-pitch[r], 2, 0, ry)
        _mm(rz, ry, r_foot[r])
        if pitch[r] >= slope[r]:  # on the heel: foot.heel(body)
            cp = np.cos(slope[r])
            d0, d1, d2 = cp * np.cos(yaw[r]), cp * np.sin(yaw[r]), np.sin(slope[r])
            hb = heel_offset[r] + ball_offset[r]
            pivot[0] = ball[r, 0] - hb * d0
            pivot[1] = ball[r, 1] - hb * d1
            pivot[2] = ball[r, 2] - hb * d2
            local[0] = heel_offset[r]
            toe[r] = 0.0
        else:
            pivot[0], pivot[1], pivot[2] = ball[r, 0], ball[r, 1], ball[r, 2]
            local[0] = -ball_offset[r]
            toe[r] = pitch[r] - slope[r]
        local[1] = 0.0
        local[2] = ankle_height[r]
        m = r_foot[r]
        for a in range(3):
            ankle[r, a] = pivot[a] + ((m[a, 0] * local[0] + m[a, 2] * local[2])
                                      + m[a, 1] * local[1])
    return r_foot, ankle, toe


@_jit
def smooth_one(v):  # pragma: no cover - compiled
    """:func:`smoothstep` of one float, for other kernels (``np.clip`` semantics: NaN kept)."""
    v = v if (np.isnan(v) or v > 0.0) else 0.0  # np.clip(v, 0.0, 1.0)
    v = v if (np.isnan(v) or v < 1.0) else 1.0
    return v * v * (3.0 - 2.0 * v)


@_jit
def _smoothstep_kernel(x, out):  # pragma: no cover - compiled
    for i in range(x.size):
        out[i] = smooth_one(x[i])


def smoothstep(x) -> np.ndarray:
    """``np.clip(x, 0, 1)`` as s, then s² (3 − 2s), elementwise [1]; the numpy code's
    values (a float array of any shape, or what numpy gives for anything else)."""
    x = np.asarray(x)
    if x.dtype != np.float64 or x.ndim == 0:
        x = np.clip(x, 0.0, 1.0)
        return x * x * (3.0 - 2.0 * x)
    flat = np.ascontiguousarray(x).reshape(-1)
    out = np.empty(flat.size)
    _smoothstep_kernel(flat, out)
    return out.reshape(x.shape)


@_jit
def shifted_stance_leg(thigh, shank, phi_shank, phi_thigh, heading, offset
                       ):  # pragma: no cover - compiled
    """``elevwalker._shifted_stance_leg``: shank and thigh elevations (k,), (k,) [rad]
    that move the stance hip by ``offset`` (k, 3) [m] (sagittal two-link IK from the
    ankle), the numpy code's operations per element."""
    k = thigh.shape[0]
    out_shank, out_thigh = np.empty(k), np.empty(k)
    for r in range(k):
        ch, sh = np.cos(heading[r]), np.sin(heading[r])
        l1, l2 = thigh[r], shank[r]
        fwd = -l2 * np.sin(phi_shank[r]) - l1 * np.sin(phi_thigh[r])
        up = l2 * np.cos(phi_shank[r]) + l1 * np.cos(phi_thigh[r])
        fwd = fwd + offset[r, 0] * ch + offset[r, 1] * sh
        up = up + offset[r, 2]
        dist = np.hypot(fwd, up)
        lo, hi = np.abs(l1 - l2) + 1e-6, 0.999 * (l1 + l2)
        dist = dist if (np.isnan(dist) or dist > lo) else lo  # np.clip
        dist = dist if (np.isnan(dist) or dist < hi) else hi
        line = np.arctan2(-fwd, up)
        c_hip = (l1 * l1 + dist * dist - l2 * l2) / (2 * l1 * dist)
        c_hip = c_hip if (np.isnan(c_hip) or c_hip > -1.0) else -1.0
        c_hip = c_hip if (np.isnan(c_hip) or c_hip < 1.0) else 1.0
        c_ankle = (l2 * l2 + dist * dist - l1 * l1) / (2 * l2 * dist)
        c_ankle = c_ankle if (np.isnan(c_ankle) or c_ankle > -1.0) else -1.0
        c_ankle = c_ankle if (np.isnan(c_ankle) or c_ankle < 1.0) else 1.0
        out_shank[r] = line - np.arccos(c_ankle)
        out_thigh[r] = line + np.arccos(c_hip)
    return out_shank, out_thigh


@_jit
def rows_finite(positions, local):  # pragma: no cover - compiled
    """(k,) bool: every entry of row r of ``positions`` (k, J, 3) and ``local`` (k, J, 3,
    3) is finite (``np.isfinite(...).all(axis=...)`` of both, and-ed)."""
    k = positions.shape[0]
    out = np.ones(k, np.bool_)
    for r in range(k):
        ok = True
        for v in positions[r].flat:
            if not np.isfinite(v):
                ok = False
                break
        if ok:
            for v in local[r].flat:
                if not np.isfinite(v):
                    ok = False
                    break
        out[r] = ok
    return out
