"""Swing-ankle Bezier curves and their adjustment around obstacles (§5.2), vectorised."""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from planners.config import PlannerConfig
from planners.leg import Leg
from planners.profile import RASTER_CELL, GroundProfile

__all__ = ["SwingResult", "bernstein", "bezier_points", "adjust_swings", "sole_clearance"]

#: Steepest-allowed lower bound of the upward component of a control-point move [-].
_MIN_UPWARD = 0.3


def bernstein(t: np.ndarray) -> np.ndarray:
    """Cubic Bernstein basis at parameters ``t`` (T,): shape (T, 4)."""
    t = np.asarray(t, dtype=float)[:, None]
    k = np.arange(4)
    coef = np.array([1.0, 3.0, 3.0, 1.0])
    return coef * t**k * (1 - t) ** (3 - k)


def bezier_points(controls: np.ndarray, samples: int) -> np.ndarray:
    """Points of cubic Bezier curves: controls (..., 4, 2) [m] -> (..., samples, 2) [m]."""
    basis = bernstein(np.linspace(0.0, 1.0, samples))
    return np.einsum("tk,...kd->...td", basis, controls)


@dataclass(frozen=True)
class SwingResult:
    """Adjusted swing curves.

    Attributes
    ----------
    controls : ndarray, shape (C, 4, 2)
        Bezier control points of the swing ankle in (s, z) [m].
    ok : ndarray of bool, shape (C,)
        Curve clears the ground by the margin inside the legal region.
    summit : ndarray, shape (C, 2)
        Highest sampled ankle point (s, z) [m].
    rounds : ndarray of int, shape (C,)
        Adjustment rounds used (0 when the initial curve was clear).
    """

    controls: np.ndarray
    ok: np.ndarray
    summit: np.ndarray
    rounds: np.ndarray


def _per_curve(value, count: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(value, dtype=float), (count,)).copy()


def sole_clearance(points: np.ndarray, start_s: np.ndarray, end_s: np.ndarray,
                   profile: GroundProfile, leg: Leg, config: PlannerConfig):
    """Clearance deficit of each sampled segment of the swing foot.

    Rule (checked conservatively per segment between consecutive samples: lowest ankle
    point of the segment against the highest ground over the segment's whole extent):
    away from the footholds the sole of a level foot, heel to toe, stays ``clearance``
    [m] above the ground; within half a foot length of either foothold (lift-off and
    touch-down, where the real foot rotates about its toe or heel) only the ankle's own
    path must stay above the ground (over a straight piece of ground, up to the rise of a
    legal foot slope over the segment).
    ``profile`` may be a :class:`GroundProfile` (exact) or a conservative
    :class:`~planners.profile.HeightRaster`.

    Parameters
    ----------
    points : ndarray, shape (C, T, 2)
        Sampled ankle points [m].
    start_s, end_s : ndarray, shape (C,)
        Arc lengths of lift-off and touch-down footholds [m].
    leg : Leg
        Foot geometry [m]; its fields may be arrays of shape (C,).

    Returns
    -------
    deficit : ndarray, shape (C, T-1)
        Required minus actual clearance [m]; > 0 is a collision.
    """
    count = points.shape[0]
    heel = _per_curve(leg.heel_offset, count)[:, None]
    toe = _per_curve(leg.toe_offset, count)[:, None]
    ankle = _per_curve(leg.ankle_height, count)[:, None]
    zone = 0.5 * _per_curve(leg.foot_length, count)[:, None]
    s, z = points[..., 0], points[..., 1]
    s_lo = np.minimum(s[:, :-1], s[:, 1:])
    s_hi = np.maximum(s[:, :-1], s[:, 1:])
    z_lo = np.minimum(z[:, :-1], z[:, 1:])
    in_zone = (s_hi <= start_s[:, None] + zone) | (s_lo >= end_s[:, None] - zone)
    a = np.where(in_zone, s_lo, s_lo - heel)
    b = np.where(in_zone, s_hi, s_hi + toe)
    ground = profile.max_height(a, b)
    # In the lift-off and touch-down zones, over a straight piece of ground (no vertex in
    # the segment), the ankle may sit below the segment's highest ground by the rise a
    # legal foot slope allows over it; over an edge or kink it must pass above it.
    straight = profile.vertices_between(s_lo, s_hi) == 0
    allowance = np.where(straight, config.max_foot_slope * (s_hi - s_lo), 0.0)
    need = np.where(in_zone, -allowance, config.clearance)
    return need - (z_lo - ankle - ground)


def adjust_swings(start_s, start_z, end_s, end_z, profile, leg: Leg,
                  config: PlannerConfig) -> SwingResult:
    """Swing-ankle curves from ``start`` to ``end`` footholds, adjusted per §5.2.

    Parameters
    ----------
    start_s, start_z, end_s, end_z : ndarray, shape (C,)
        Lift-off and touch-down footholds (ground under the ankle) [m].
    profile : GroundProfile or HeightRaster
        The ground; a profile is checked through its conservative raster of
        :data:`~planners.profile.RASTER_CELL` cells.
    leg : Leg
        Foot geometry [m]; its fields may be arrays of shape (C,).

    Notes
    -----
    §5.2: both control points start ``swing_lift`` above the chord midpoint M. While the
    curve collides, it is split at its summit; each colliding half moves its control
    point from M toward its worst collision point (up and outward), the other half's
    control point follows upward by the same amount. Deviations: the distance of a move
    is the one that would lift the worst sample clear (from its Bernstein weight) instead
    of a fixed increment, which needs 1-3 rounds instead of tens; control points are
    kept between the footholds in s (the ankle never moves backward) and the curve is
    illegal once a control point is ``max_swing_lift`` above the higher foothold's ankle.
    The collision rule is :func:`sole_clearance`'s; compiled (:func:`_adjust`), one curve
    at a time.
    """
    start_s = np.asarray(start_s, dtype=float).reshape(-1)
    end_s = np.asarray(end_s, dtype=float).reshape(-1)
    C = start_s.size
    feet = [_per_curve(getattr(leg, name), C)
            for name in ("heel_offset", "toe_offset", "ankle_height", "foot_length")]
    if isinstance(profile, GroundProfile):
        margin = 2 * float(feet[3].max()) if C else 0.0
        lo = np.floor((float(start_s.min(initial=0.0)) - margin) / RASTER_CELL) * RASTER_CELL
        profile = profile.raster(lo, float(end_s.max(initial=0.0)) + margin, RASTER_CELL)
    samples = config.bezier_samples
    t = np.linspace(0.0, 1.0, samples)
    t_mid = 0.5 * (t[:-1] + t[1:])
    influence = np.stack([3 * t_mid * (1 - t_mid) ** 2, 3 * t_mid**2 * (1 - t_mid)])
    basis = np.ascontiguousarray(bernstein(t).T)  # (4, T)
    controls = np.empty((C, 4, 2))
    summit = np.empty((C, 2))
    ok = np.zeros(C, dtype=np.bool_)
    rounds = np.zeros(C, dtype=np.int64)
    _adjust(start_s, _per_curve(start_z, C), end_s, _per_curve(end_z, C), *feet,
            profile.start, profile.cell, profile.table(TABLE_LEVELS), profile.vertex_cum,
            basis,
            influence, config.clearance, config.swing_lift, config.max_swing_lift,
            config.max_foot_slope, config.max_adjustments, controls, summit, ok, rounds)
    return SwingResult(controls, ok, summit, rounds)


_jit = nb.njit(cache=True, nogil=True)
#: Kernels that allocate nothing: compiled without numba's runtime, so that the arrays
#: they take are not reference-counted at every call (atomic increments and decrements).
_leaf = nb.njit(cache=True, nogil=True, _nrt=False)
#: Levels of the raster's range-maximum table the kernel uses: spans up to 2**7 cells
#: (0.5 m) take two look-ups, longer ones a few more.
TABLE_LEVELS = 7


@_leaf
def _round9(x):
    """``np.round(x, 9)`` of a float."""
    return np.rint(x * 1e9) / 1e9


@_leaf
def _cell(x, start, cell, scale, c):
    """:func:`planners.profile.cell_index` of one arc length ``x`` [m] in a raster of
    ``c`` cells (``scale`` = 1 / ``cell``)."""
    f = min(max((x - start) * scale, 0.0), c - 1.0)
    k = int(f)
    r = f - k
    # only within rounding of an edge (far less than 1e-6 cells) can k be one off
    if r < 1e-6 or r > 1.0 - 1e-6:
        if k > 0 and start + cell * k > x:
            k -= 1
        elif k < c - 1 and start + cell * (k + 1) <= x:
            k += 1
    return k


@_leaf
def _raster_max(a, b, start, cell, scale, table):
    """:meth:`HeightRaster.max_height` of one interval [m], from the raster's
    range-maximum table (L, c)."""
    c = table.shape[1]
    ia = _cell(a, start, cell, scale, c)
    return _cells_max(ia, max(_cell(b, start, cell, scale, c), ia), table)


@_leaf
def _cells_max(ia, ib, table):
    """:func:`_raster_max` of the cells ``ia``..``ib`` (``ib`` >= ``ia``)."""
    levels = table.shape[0]
    span = ib - ia + 1
    k = 0
    while (2 << k) <= span and k + 1 < levels:
        k += 1
    width = 1 << k
    best = table[k, ia]
    i = ia + width
    while i + width <= ib + 1:  # spans longer than the table's widest level
        best = max(best, table[k, i])
        i += width
    return max(best, table[k, ib - width + 1])


@_leaf
def _raster_vertices(a, b, start, cell, scale, vertex_cum):
    """:meth:`HeightRaster.vertices_between` of one interval."""
    c = vertex_cum.size - 1
    ia = _cell(a, start, cell, scale, c)
    ib = max(_cell(b, start, cell, scale, c), ia)
    return vertex_cum[ib + 1] - vertex_cum[ia]


@_jit
def _adjust(start_s, start_z, end_s, end_z, heel, toe, ankle, foot, r_start, cell, table,
            vertex_cum, basis, influence, clearance, swing_lift, max_swing_lift,
            max_foot_slope, max_adjustments, controls, out_summit, ok, rounds):
    """§5.2 adjustment of each curve (see :func:`adjust_swings`); fills ``controls``
    (C, 4, 2), ``out_summit`` (C, 2) (the highest sample of the final curve), ``ok`` (C,)
    and ``rounds`` (C,)."""
    T = basis.shape[1]
    scratch = np.empty((3, T))
    for c in range(start_s.size):
        ok[c], rounds[c] = adjust_one(
            start_s[c], start_z[c], end_s[c], end_z[c], heel[c], toe[c], ankle[c], foot[c],
            r_start, cell, table, vertex_cum, basis, influence, clearance, swing_lift,
            max_swing_lift, max_foot_slope, max_adjustments, controls[c], out_summit[c],
            scratch)


@_leaf
def adjust_one(start_s, start_z, end_s, end_z, heel, toe, ankle, foot, r_start, cell,
               table, vertex_cum, basis, influence, clearance, swing_lift, max_swing_lift,
               max_foot_slope, max_adjustments, ctrl, out_summit, scratch):
    """§5.2 adjustment of one curve: fills ``ctrl`` (4, 2) and ``out_summit`` (2,);
    returns (ok, rounds). ``scratch`` is (3, T) work space."""
    T = basis.shape[1]
    scale = 1.0 / cell
    ps = scratch[0]
    pz = scratch[1]
    deficit = scratch[2]
    ok = False
    c = table.shape[1]
    rounds = 0
    p0s, p0z = start_s, start_z + ankle
    p3s, p3z = end_s, end_z + ankle
    ms, mz = 0.5 * (p0s + p3s), 0.5 * (p0z + p3z)
    ctrl[0, 0], ctrl[0, 1] = p0s, p0z
    ctrl[1, 0], ctrl[1, 1] = ms, mz + swing_lift
    ctrl[2, 0], ctrl[2, 1] = ms, mz + swing_lift
    ctrl[3, 0], ctrl[3, 1] = p3s, p3z
    top = max(p0z, p3z) + max_swing_lift
    zone = 0.5 * foot
    for round_ in range(max_adjustments + 1):
        for i in range(T):
            ps[i] = (ctrl[0, 0] * basis[0, i] + ctrl[1, 0] * basis[1, i]
                     + ctrl[2, 0] * basis[2, i] + ctrl[3, 0] * basis[3, i])
            pz[i] = (ctrl[0, 1] * basis[0, i] + ctrl[1, 1] * basis[1, i]
                     + ctrl[2, 1] * basis[2, i] + ctrl[3, 1] * basis[3, i])
        clear = True
        for i in range(T - 1):  # sole_clearance
            s_lo, s_hi = min(ps[i], ps[i + 1]), max(ps[i], ps[i + 1])
            z_lo = min(pz[i], pz[i + 1])
            in_zone = (s_hi <= p0s + zone) or (s_lo >= p3s - zone)
            if in_zone:  # _raster_max and _raster_vertices of [s_lo, s_hi]
                ia = _cell(s_lo, r_start, cell, scale, c)
                ib = max(_cell(s_hi, r_start, cell, scale, c), ia)
                ground = _cells_max(ia, ib, table)
                straight = vertex_cum[ib + 1] - vertex_cum[ia] == 0
                need = -(max_foot_slope * (s_hi - s_lo) if straight else 0.0)
            else:
                ia = _cell(s_lo - heel, r_start, cell, scale, c)
                ib = max(_cell(s_hi + toe, r_start, cell, scale, c), ia)
                ground = _cells_max(ia, ib, table)
                need = clearance
            deficit[i] = need - (z_lo - ankle - ground)
            if deficit[i] > 1e-9:
                clear = False
        if clear:
            ok = True
            break
        if round_ == max_adjustments:
            break
        rounds += 1
        summit, high = 0, _round9(pz[0] - pz[0])
        for i in range(1, T):
            v = _round9(pz[i] - pz[0])
            if v > high:
                summit, high = i, v
        move_s0 = move_z0 = move_s1 = move_z1 = 0.0
        for side in range(2):
            worst, worst_r = 0, -np.inf
            for i in range(T - 1):
                if (i < summit) == (side == 0):
                    r = _round9(deficit[i])
                    if r > worst_r:
                        worst, worst_r = i, r
            need = deficit[worst] if worst_r > -np.inf else -np.inf
            if not need > 1e-9:
                continue
            us = 0.5 * (ps[worst] + ps[worst + 1]) - ms
            uz = 0.5 * (pz[worst] + pz[worst + 1]) + need - mz
            uz = max(uz, 0.3 * abs(us) + 1e-9)
            norm = np.sqrt(us * us + uz * uz)
            us, uz = us / norm, uz / norm
            weight = influence[side, worst]
            dist = min(max(2.0 * need / max(weight * uz, 1e-3) + 0.002, 0.005), 0.3)
            if side == 0:
                move_s0, move_z0 = dist * us, dist * uz
            else:
                move_s1, move_z1 = dist * us, dist * uz
        # a half without collision follows the other one upward by the same amount
        if not move_z0 > 0:
            move_z0 = move_z1
        if not move_z1 > 0:
            move_z1 = move_z0
        ctrl[1, 0] = min(max(ctrl[1, 0] + move_s0, p0s), p3s)
        ctrl[1, 1] += move_z0
        ctrl[2, 0] = min(max(ctrl[2, 0] + move_s1, p0s), p3s)
        ctrl[2, 1] += move_z1
        if ctrl[1, 1] > top or ctrl[2, 1] > top:
            break
    high = -np.inf  # the final curve's highest sample
    for i in range(T):
        zi = (ctrl[0, 1] * basis[0, i] + ctrl[1, 1] * basis[1, i]
              + ctrl[2, 1] * basis[2, i] + ctrl[3, 1] * basis[3, i])
        if zi > high:
            high = zi
            out_summit[0] = (ctrl[0, 0] * basis[0, i] + ctrl[1, 0] * basis[1, i]
                             + ctrl[2, 0] * basis[2, i] + ctrl[3, 0] * basis[3, i])
    out_summit[1] = high
    return ok, rounds


class _FootView:
    """Attribute access to per-curve foot arrays (a Leg with array fields)."""

    def __init__(self, fields: dict[str, np.ndarray]):
        self.__dict__.update(fields)
