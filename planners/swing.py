"""Swing-ankle Bezier curves and their adjustment around obstacles (§5.2), vectorised."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planners.config import PlannerConfig
from planners.leg import Leg
from planners.profile import GroundProfile

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


def adjust_swings(start_s, start_z, end_s, end_z, profile: GroundProfile, leg: Leg,
                  config: PlannerConfig) -> SwingResult:
    """Swing-ankle curves from ``start`` to ``end`` footholds, adjusted per §5.2.

    Parameters
    ----------
    start_s, start_z, end_s, end_z : ndarray, shape (C,)
        Lift-off and touch-down footholds (ground under the ankle) [m].
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
    """
    start_s = np.asarray(start_s, dtype=float).reshape(-1)
    end_s = np.asarray(end_s, dtype=float).reshape(-1)
    C = start_s.size
    feet = {name: _per_curve(getattr(leg, name), C)
            for name in ("heel_offset", "toe_offset", "ankle_height", "foot_length")}
    a = feet["ankle_height"]
    p0 = np.stack([start_s, np.asarray(start_z, dtype=float).reshape(-1) + a], axis=-1)
    p3 = np.stack([end_s, np.asarray(end_z, dtype=float).reshape(-1) + a], axis=-1)
    mid = 0.5 * (p0 + p3)
    p1 = mid + np.array([0.0, config.swing_lift])
    controls = np.stack([p0, p1, p1.copy(), p3], axis=1)  # (C, 4, 2)
    top = np.maximum(p0[:, 1], p3[:, 1]) + config.max_swing_lift
    samples = config.bezier_samples
    basis_t = bernstein(np.linspace(0.0, 1.0, samples)).T  # (4, T)
    t_mid = np.linspace(0.0, 1.0, samples)
    t_mid = 0.5 * (t_mid[:-1] + t_mid[1:])
    influence = (3 * t_mid * (1 - t_mid) ** 2, 3 * t_mid**2 * (1 - t_mid))  # P1, P2

    ok = np.zeros(C, dtype=bool)
    rounds = np.zeros(C, dtype=int)
    active = np.arange(C)
    for round_ in range(config.max_adjustments + 1):
        ctrl = controls[active]
        pts = np.stack([ctrl[..., 0] @ basis_t, ctrl[..., 1] @ basis_t], axis=-1)
        view = _FootView({k: v[active] for k, v in feet.items()})
        deficit = sole_clearance(pts, start_s[active], end_s[active], profile, view, config)
        clear = ~(deficit > 1e-9).any(axis=1)
        ok[active[clear]] = True
        keep = ~clear
        active, pts, deficit = active[keep], pts[keep], deficit[keep]
        if active.size == 0 or round_ == config.max_adjustments:
            break
        rounds[active] += 1
        rows = np.arange(active.size)
        # Ties (a level obstacle top, a symmetric curve) are broken on values rounded to
        # 1 nm so that translating the problem cannot change the adjustment path.
        summit = np.argmax(np.round(pts[..., 1] - pts[:, :1, 1], 9), axis=1)
        left_half = np.arange(samples - 1)[None, :] < summit[:, None]
        moves = np.zeros((active.size, 2, 2))  # (curve, P1/P2, s/z)
        for side, half in ((0, left_half), (1, ~left_half)):
            d = np.where(half, deficit, -np.inf)
            worst = np.argmax(np.round(d, 9), axis=1)
            need = d[rows, worst]
            hit = need > 1e-9
            target = 0.5 * (pts[rows, worst] + pts[rows, worst + 1])
            target[:, 1] += np.maximum(need, 0.0)
            u = target - mid[active]
            u[:, 1] = np.maximum(u[:, 1], _MIN_UPWARD * np.abs(u[:, 0]) + 1e-9)
            u /= np.linalg.norm(u, axis=1, keepdims=True)
            weight = influence[side][worst]
            dist = np.clip(2.0 * need / np.maximum(weight * u[:, 1], 1e-3) + 0.002, 0.005, 0.3)
            moves[:, side] = np.where(hit[:, None], dist[:, None] * u, 0.0)
        # A half without collision follows the other one upward by the same amount.
        lift = moves[:, :, 1]
        moves[:, 0, 1] = np.where(lift[:, 0] > 0, lift[:, 0], lift[:, 1])
        moves[:, 1, 1] = np.where(lift[:, 1] > 0, lift[:, 1], lift[:, 0])
        new = controls[active]
        new[:, 1:3] += moves
        new[:, 1:3, 0] = np.clip(new[:, 1:3, 0], start_s[active, None], end_s[active, None])
        controls[active] = new
        inside = ~(new[:, 1:3, 1] > top[active, None]).any(axis=1)
        active = active[inside]
        if active.size == 0:
            break
    pts_z = controls[..., 1] @ basis_t
    best = np.argmax(pts_z, axis=1)
    summit = np.stack([(controls[..., 0] @ basis_t)[np.arange(C), best],
                       pts_z[np.arange(C), best]], axis=-1)
    return SwingResult(controls, ok, summit, rounds)


class _FootView:
    """Attribute access to per-curve foot arrays (a Leg with array fields)."""

    def __init__(self, fields: dict[str, np.ndarray]):
        self.__dict__.update(fields)
