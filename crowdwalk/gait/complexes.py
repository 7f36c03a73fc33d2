"""Compiled Gauss–Newton solves of the stance-ankle and swing-hip complexes (§4.3).

ElevWalker's two iterative solves, one agent at a time in a numba kernel (the batched
numpy version spent most of a crowd frame in small array operations):

- **stance ankle** — talocrural and subtalar angles x = (θ_tc, θ_sub) [rad] such that the
  stance shank has the data elevation and the hip the stance width (Eq. 8), with the
  analytic stance knee (§4.2) inside;
- **swing hip** — intrinsic Y-X-Z Euler angles x [rad] of the swing hip such that the
  thigh has the data elevation, the ankle the swing width and the thigh the toe-out,
  with the analytic swing knee inside.

The iteration is the one the batched version ran, per agent: warm start (the previous
frame's solution), up to two chord steps with the previous frame's Jacobian while they reduce
the residual, then Gauss–Newton steps with forward-difference Jacobians (ε = 1e-6) and
a 0.5 rad trust region, until every residual is below the tolerance [rad or m].
Matrices are the world orientations of the segment frames (columns x fwd, y left, z up).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from crowdwalk.workers import row_threads

__all__ = ["MIN_POSE_ROWS", "solve_stance_ankle", "solve_swing_hip"]

_EPS = 1e-6  # forward-difference step [rad]
#: Fewer rows per thread are solved in one call [-]: the solves are row-independent and
#: release the GIL, so parts of a frame's walkers are solved at once in the process's row
#: threads (:func:`crowdwalk.workers.row_threads`), bit for bit one call's result; a part
#: costs ~2.5 µs per row against 50-100 µs (loaded machine) to hand it to a thread.
MIN_POSE_ROWS = 128
_CHORDS = 2  # chord steps with the previous frame's Jacobian
# The per-agent helpers and the solver run without numba's reference-counted runtime
# (``_nrt=False``): with it every array view handed from one compiled function to the
# next took an atomic incref/decref pair, 28 % of the solves' time (perf); they only
# read and write arrays their caller allocated (slice copies are written as loops).
# The batch kernels that allocate the outputs keep the runtime (``_jit_nrt``).
_jit = nb.njit(cache=True, nogil=True, _nrt=False)
_jit_nrt = nb.njit(cache=True, nogil=True)


@_jit
def _wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


@_jit
def _matmul(a, b, out):
    for i in range(3):
        a0, a1, a2 = a[i, 0], a[i, 1], a[i, 2]
        for j in range(3):
            out[i, j] = a0 * b[0, j] + a1 * b[1, j] + a2 * b[2, j]


@_jit
def _rodrigues(axis, angle, out):
    """Rotation about a unit axis (3,) by angle [rad] (right-hand rule)."""
    x, y, z = axis[0], axis[1], axis[2]
    c, s = np.cos(angle), np.sin(angle)
    C = 1.0 - c
    out[0, 0] = c + x * x * C
    out[0, 1] = x * y * C - z * s
    out[0, 2] = x * z * C + y * s
    out[1, 0] = y * x * C + z * s
    out[1, 1] = c + y * y * C
    out[1, 2] = y * z * C - x * s
    out[2, 0] = z * x * C - y * s
    out[2, 1] = z * y * C + x * s
    out[2, 2] = c + z * z * C


@_jit
def _times_rotation_y(a, c, s, out):
    """out = a @ rotation_y(angle) of an angle with cosine c and sine s."""
    for i in range(3):
        a0, a1, a2 = a[i, 0], a[i, 1], a[i, 2]
        out[i, 0] = a0 * c - a2 * s
        out[i, 1] = a1
        out[i, 2] = a0 * s + a2 * c


@_jit
def _times_rotation_x(a, c, s, out):
    """out = a @ rotation_x(angle) of an angle with cosine c and sine s."""
    for i in range(3):
        a0, a1, a2 = a[i, 0], a[i, 1], a[i, 2]
        out[i, 0] = a0
        out[i, 1] = a1 * c + a2 * s
        out[i, 2] = -a1 * s + a2 * c


@_jit
def _times_rotation_z(a, c, s, out):
    """out = a @ rotation_z(angle) of an angle with cosine c and sine s."""
    for i in range(3):
        a0, a1, a2 = a[i, 0], a[i, 1], a[i, 2]
        out[i, 0] = a0 * c + a1 * s
        out[i, 1] = -a0 * s + a1 * c
        out[i, 2] = a2


@_jit
def _knee(parent, ch, sh, cphi, sphi):
    """Cosine and sine of the knee angle giving the distal segment (rest direction −z,
    hinge +y of the parent frame ``parent`` (3, 3)) the sagittal elevation φ (cosine
    ``cphi``, sine ``sphi``); and whether that angle exists.

    :func:`crowdwalk.gait.elevwalker.solve_single_dof` for axis y and segment −z: the
    circle of Eq. 2 is v = d cos θ + e sin θ with d = −parent[:, 2], e = −parent[:, 0],
    Eq. 3 is A cos θ + B sin θ = 0, its roots θ = atan2(B, A) ± π/2.
    """
    d0, d1, d2 = -parent[0, 2], -parent[1, 2], -parent[2, 2]
    e0, e1, e2 = -parent[0, 0], -parent[1, 0], -parent[2, 0]
    hd, he = d0 * ch + d1 * sh, e0 * ch + e1 * sh
    A, B = hd * cphi + d2 * sphi, he * cphi + e2 * sphi
    R = np.hypot(A, B)
    ca, sa = (A / R, B / R) if R > 0.0 else (1.0, 0.0)
    best_c, best_s, score = 0.0, 0.0, -np.inf
    for c, s in ((-sa, ca), (sa, -ca)):  # atan2(B, A) + π/2, then − π/2
        g = (hd * c + he * s) * sphi - (d2 * c + e2 * s) * cphi
        if g > score:
            best_c, best_s, score = c, s, g
    return best_c, best_s, R > 1e-12 and score > 1e-6


@_jit
def _stance(i, x, r_foot, ankle, tc_axis, sub_axis, shank, thigh, ch, sh, phi_shank,
            c_thigh, s_thigh, normal, w_stance, rot, r_shank, r_thigh, hip, res):  # fmt: skip
    """Stance chain of agent i at x (2,): fills r_shank, r_thigh, hip (3,), res (2,);
    returns the knee's :func:`_knee`. ``rot`` (2, 3, 3) is scratch."""
    _rodrigues(sub_axis[i], -x[1], rot[0])  # transposed subtalar rotation
    _matmul(r_foot[i], rot[0], rot[1])  # talus
    _rodrigues(tc_axis[i], -x[0], rot[0])  # transposed talocrural rotation
    _matmul(rot[1], rot[0], r_shank)
    c, s, ok = _knee(r_shank, ch, sh, c_thigh, s_thigh)
    _times_rotation_y(r_shank, c, s, r_thigh)
    width = 0.0
    for a in range(3):
        hip[a] = ankle[i, a] + shank * r_shank[a, 2] + thigh * r_thigh[a, 2]
        width += (ankle[i, a] - hip[a]) * normal[i, a]
    # shank elevation of the knee→ankle vector −r_shank[:, 2]
    fwd = -(r_shank[0, 2] * ch + r_shank[1, 2] * sh)
    res[0] = _wrap(np.arctan2(fwd, r_shank[2, 2]) - phi_shank)
    res[1] = width - w_stance
    return c, s, ok


@_jit
def _swing(i, x, r_pelvis, hip_sw, thigh, shank, ch, sh, c_knee, s_knee, phi_thigh, normal,
           side, toe_out, w_swing, rot, r_thigh, r_shank, ankle, res):  # fmt: skip
    """Swing chain of agent i at x (3,): fills r_thigh, r_shank, ankle (3,), res (3,);
    returns the knee's :func:`_knee`. ``rot`` (2, 3, 3) is scratch."""
    _times_rotation_y(r_pelvis[i], np.cos(x[0]), np.sin(x[0]), rot[0])
    _times_rotation_x(rot[0], np.cos(x[1]), np.sin(x[1]), rot[1])
    _times_rotation_z(rot[1], np.cos(x[2]), np.sin(x[2]), r_thigh)
    c, s, ok = _knee(r_thigh, ch, sh, c_knee, s_knee)
    _times_rotation_y(r_thigh, c, s, r_shank)
    width = 0.0
    f_n = 0.0
    f_f = 0.0
    fw = (ch, sh, 0.0)
    for a in range(3):
        ankle[a] = hip_sw[i, a] - thigh * r_thigh[a, 2] - shank * r_shank[a, 2]
        width += (ankle[a] - hip_sw[i, a]) * normal[i, a]
        f_n += r_thigh[a, 0] * normal[i, a]
        f_f += r_thigh[a, 0] * fw[a]
    fwd = -(r_thigh[0, 2] * ch + r_thigh[1, 2] * sh)
    res[0] = _wrap(np.arctan2(fwd, r_thigh[2, 2]) - phi_thigh)
    res[1] = width - w_swing
    res[2] = _wrap(side * np.arctan2(f_n, f_f) - toe_out)
    return c, s, ok


@_jit
def _converged(res, tol):
    for v in res:
        if not (abs(v) < tol):  # NaN is not converged
            return False
    return True


@_jit
def _finite(a):
    for v in a.flat:
        if not np.isfinite(v):
            return False
    return True


@_jit
def _fill(a, value):
    """Every entry of a (1-D or 2-D) set to ``value`` (no temporary: NRT-free)."""
    for v in range(a.size):
        a.flat[v] = value


@_jit
def _copy(dst, src):
    """dst[:] = src for 1-D arrays, NRT-free."""
    for v in range(src.size):
        dst[v] = src[v]


@_jit
def _norm(v):
    total = 0.0
    for e in v:
        total += e * e
    return np.sqrt(total)


@_jit
def _step(jac, res, lhs, rhs, dx, m):
    """Gauss–Newton step dx = −(JᵀJ + 1e-12 I)⁻¹ Jᵀ r of m unknowns, clipped to ±0.5
    rad; zero when the Jacobian or residual is not finite. ``lhs`` (m, m) and ``rhs``
    (m,) are scratch."""
    for a in range(m):
        rhs[a] = 0.0
        for b in range(m):
            lhs[a, b] = 0.0
            for c in range(m):
                lhs[a, b] += jac[c, a] * jac[c, b]
            rhs[a] -= jac[b, a] * res[b]
        lhs[a, a] += 1e-12
    if not (_finite(lhs) and _finite(rhs)):
        _fill(dx, 0.0)
        return
    # Gaussian elimination with partial pivoting
    for c in range(m):
        p = c
        for r in range(c + 1, m):
            if abs(lhs[r, c]) > abs(lhs[p, c]):
                p = r
        if lhs[p, c] == 0.0:
            _fill(dx, 0.0)
            return
        if p != c:
            for j in range(m):
                lhs[c, j], lhs[p, j] = lhs[p, j], lhs[c, j]
            rhs[c], rhs[p] = rhs[p], rhs[c]
        for r in range(c + 1, m):
            f = lhs[r, c] / lhs[c, c]
            for j in range(c, m):
                lhs[r, j] -= f * lhs[c, j]
            rhs[r] -= f * rhs[c]
    for c in range(m - 1, -1, -1):
        v = rhs[c]
        for j in range(c + 1, m):
            v -= lhs[c, j] * dx[j]
        dx[c] = v / lhs[c, c]
    for c in range(m):
        dx[c] = min(max(dx[c], -0.5), 0.5)  # trust region: at most 0.5 rad per iteration


def _solver(chain, m):
    """Compiled Gauss–Newton ``solve(i, x, jac, args, tol, max_iter, scratch)`` of m
    unknowns over ``chain(i, x, *args, res)``, which fills the residual res (m,) and the
    chain outputs in ``args`` and returns the knee angle's cosine, sine and whether it
    exists. m is a compile-time constant of ``solve`` (a closure variable): its loops and
    :func:`_step`'s are unrolled (the same operations in the same order: the same
    values; the solves ~6–7 % faster)."""

    @_jit
    def solve(i, x, jac, args, tol, max_iter, scratch):
        """Agent i from x (m,), in place; ``jac`` (m, m) in: the previous frame's
        Jacobian (NaN: none), out: the latest. On return the chain outputs belong to x;
        returns the knee angle, knee solvable and converged at x.

        Up to two chord steps reuse the previous Jacobian while they reduce the
        residual; then Gauss–Newton steps with forward differences.
        """
        res, res_try, res_nb, x_try, dx, lhs, rhs = scratch
        kc, ks, knee_ok = chain(i, x, *args, res)
        at_x = True  # the chain outputs belong to x
        ok = _converged(res, tol)
        for _ in range(_CHORDS):
            if ok or not _finite(jac):
                break
            _step(jac, res, lhs, rhs, dx, m)
            for a in range(m):
                x_try[a] = x[a] + dx[a]
            kc_try, ks_try, ok_try = chain(i, x_try, *args, res_try)
            norm, norm_try = _norm(res), _norm(res_try)
            if not norm_try < norm:
                at_x = False
                _fill(jac, np.nan)  # stale Jacobian: difference it anew
                break
            _copy(x, x_try)
            _copy(res, res_try)
            kc, ks, knee_ok = kc_try, ks_try, ok_try
            ok = _converged(res, tol)
        for _ in range(max_iter):
            if ok:
                break
            for c in range(m):
                _copy(x_try, x)
                x_try[c] += _EPS
                chain(i, x_try, *args, res_nb)
                for a in range(m):
                    jac[a, c] = (res_nb[a] - res[a]) / _EPS
            _step(jac, res, lhs, rhs, dx, m)
            for a in range(m):
                x[a] += dx[a]
            kc, ks, knee_ok = chain(i, x, *args, res)
            at_x = True
            ok = _converged(res, tol)
        if not at_x:
            kc, ks, knee_ok = chain(i, x, *args, res)
        return np.arctan2(ks, kc), knee_ok, ok and _finite(x)

    return solve


_solve_stance = _solver(_stance, 2)
_solve_swing = _solver(_swing, 3)


@_jit_nrt
def _scratch(m):
    """Work arrays of :func:`_solver`'s solve for m unknowns."""
    return (np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m),
            np.empty((m, m)), np.empty(m))  # fmt: skip


@_jit_nrt
def _stance_gn(r_foot, ankle, tc_axis, sub_axis, shank, thigh, heading, phi_shank,
               phi_thigh, normal, w_stance, x0, jac0, tol, max_iter):  # fmt: skip
    k = x0.shape[0]
    x, jac = x0.copy(), jac0.copy()
    done, knee, knee_ok = np.zeros(k, np.bool_), np.empty(k), np.zeros(k, np.bool_)
    r_shank, r_thigh, hip = np.empty((k, 3, 3)), np.empty((k, 3, 3)), np.empty((k, 3))
    rot, scratch = np.empty((2, 3, 3)), _scratch(2)
    for i in range(k):
        ch, sh = np.cos(heading[i]), np.sin(heading[i])
        args = (r_foot, ankle, tc_axis, sub_axis, shank[i], thigh[i], ch, sh, phi_shank[i],
                np.cos(phi_thigh[i]), np.sin(phi_thigh[i]), normal, w_stance[i], rot,
                r_shank[i], r_thigh[i], hip[i])  # fmt: skip
        knee[i], knee_ok[i], done[i] = _solve_stance(i, x[i], jac[i], args, tol, max_iter,
                                                     scratch)  # fmt: skip
    return x, done, jac, r_shank, knee, knee_ok, r_thigh, hip


@_jit_nrt
def _swing_gn(r_pelvis, hip_sw, thigh, shank, heading, phi_knee, phi_thigh, normal, side,
              toe_out, w_swing, x0, jac0, tol, max_iter):  # fmt: skip
    k = x0.shape[0]
    x, jac = x0.copy(), jac0.copy()
    done, knee, knee_ok = np.zeros(k, np.bool_), np.empty(k), np.zeros(k, np.bool_)
    r_thigh, r_shank, ankle = np.empty((k, 3, 3)), np.empty((k, 3, 3)), np.empty((k, 3))
    rot, scratch = np.empty((2, 3, 3)), _scratch(3)
    for i in range(k):
        ch, sh = np.cos(heading[i]), np.sin(heading[i])
        args = (r_pelvis, hip_sw, thigh[i], shank[i], ch, sh, np.cos(phi_knee[i]),
                np.sin(phi_knee[i]), phi_thigh[i], normal, side[i], toe_out[i], w_swing[i],
                rot, r_thigh[i], r_shank[i], ankle[i])  # fmt: skip
        knee[i], knee_ok[i], done[i] = _solve_swing(i, x[i], jac[i], args, tol, max_iter,
                                                    scratch)  # fmt: skip
    return x, done, jac, r_thigh, knee, knee_ok, r_shank, ankle


def _f(a, shape=None) -> np.ndarray:
    arr = np.ascontiguousarray(a, dtype=np.float64)
    if shape is None or arr.shape == shape:
        return arr
    return np.ascontiguousarray(np.broadcast_to(arr, shape))


def _jacobian(jac, k: int, m: int) -> np.ndarray:
    return np.full((k, m, m), np.nan) if jac is None else _f(jac, (k, m, m))


def solve_stance_ankle(r_foot, ankle, tc_axis, sub_axis, shank, thigh, heading, phi_shank,
                       phi_thigh, normal, w_stance, x0, jacobian, tol, max_iter):  # fmt: skip
    """Stance ankle complex of k agents (§4.3, Eq. 8).

    Parameters
    ----------
    r_foot : (k, 3, 3) stance foot world orientation.
    ankle : (k, 3) stance ankle world position [m].
    tc_axis, sub_axis : (k, 3) talocrural and subtalar unit axes (parent frames).
    shank, thigh : (k,) segment lengths [m].
    heading : (k,) sagittal-plane orientation ψ [rad].
    phi_shank, phi_thigh : (k,) data elevations of the stance shank and thigh [rad].
    normal : (k, 3) sagittal-plane normal (left).
    w_stance : (k,) required (ankle − hip) · normal [m].
    x0 : (k, 2) warm start (θ_tc, θ_sub) [rad]; jacobian : (k, 2, 2) or None.
    tol : residual tolerance [rad or m]; max_iter : Gauss–Newton iterations.

    Returns
    -------
    x (k, 2) [rad], converged (k,), Jacobians (k, 2, 2) (NaN where none was formed),
    shank orientation (k, 3, 3), knee angle (k,) [rad], knee solvable (k,), thigh
    orientation (k, 3, 3), stance hip (k, 3) [m].
    """
    k = len(x0)
    return row_threads().map(
        _stance_gn, k, _f(r_foot), _f(ankle), _f(tc_axis, (k, 3)), _f(sub_axis, (k, 3)),
        _f(shank), _f(thigh), _f(heading), _f(phi_shank), _f(phi_thigh),
        _f(normal), _f(w_stance), _f(x0), _jacobian(jacobian, k, 2),
        float(tol), int(max_iter), min_rows=MIN_POSE_ROWS,
    )  # fmt: skip


def solve_swing_hip(r_pelvis, hip_sw, thigh, shank, heading, phi_knee, phi_thigh, normal,
                    side, toe_out, w_swing, x0, jacobian, tol, max_iter):  # fmt: skip
    """Swing hip complex of k agents (§4.3).

    Parameters
    ----------
    r_pelvis : (k, 3, 3) pelvis world orientation.
    hip_sw : (k, 3) swing hip world position [m].
    thigh, shank : (k,) segment lengths [m].
    heading : (k,) sagittal-plane orientation ψ [rad].
    phi_knee, phi_thigh : (k,) data elevations of the swing shank and thigh [rad].
    normal : (k, 3) sagittal-plane normal (left).
    side : (k,) +1 when the swing leg is the left one, −1 the right one.
    toe_out : (k,) thigh toe-out [rad]; w_swing : (k,) required (ankle − hip) · normal [m].
    x0 : (k, 3) warm start (Y-X-Z Euler angles) [rad]; jacobian : (k, 3, 3) or None.
    tol : residual tolerance [rad or m]; max_iter : Gauss–Newton iterations.

    Returns
    -------
    x (k, 3) [rad], converged (k,), Jacobians (k, 3, 3) (NaN where none was formed),
    thigh orientation (k, 3, 3), knee angle (k,) [rad], knee solvable (k,), shank
    orientation (k, 3, 3), swing ankle (k, 3) [m].
    """
    k = len(x0)
    return row_threads().map(
        _swing_gn, k, _f(r_pelvis), _f(hip_sw), _f(thigh), _f(shank), _f(heading),
        _f(phi_knee), _f(phi_thigh), _f(normal), _f(side), _f(toe_out),
        _f(w_swing), _f(x0), _jacobian(jacobian, k, 3), float(tol),
        int(max_iter), min_rows=MIN_POSE_ROWS,
    )  # fmt: skip
