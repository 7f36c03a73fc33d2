"""ElevInterp: elevation-angle datasets for a requested step length and height.

Sun & Metaxas (2001), §5 ("inverse motion interpolation"). Each source dataset is placed
in a Height/Length space by measuring the step it produces for a body (Eq. 10,
:func:`step_of`). A request (SL, SH) is located in the Delaunay triangulation of those
points, its barycentric coordinates blend the three vertex datasets (Eq. 9), and when the
blend misses the request (f is non-linear, §5.1 step 5) a Gauss–Newton search on the
blend weights makes it exact. Solved datasets are inserted into the triangulation (step
6), so later nearby requests fall in small triangles and skip the search.

Implementation notes (deviations and choices, each measured in the tests/benchmark):

- One space instead of two. The paper keeps a dataset space with coordinates
  (SL/leg_length, SH/leg_length) next to the physical space. Eq. 10 is homogeneous in the
  leg dimensions, f(ds; s·L) = s·f(ds; L), so for a given body *shape* (leg dimensions
  divided by leg length) the physical space divided by the leg length *is* that dataset
  space. We keep one triangulation per body shape in these normalised coordinates: all
  bodies made by ``Body.from_heights`` share one, whatever their height, and the cache
  (triangulation plus inserted datasets) is keyed by the shape rounded to 0.5 %.
- Slopes. There are no measured slope datasets. Step height is reached by interpolating
  between the level datasets (SH ≈ −0.01 H) and the stair datasets (SH ≈ +0.08 H up,
  −0.06 H down); the hull of the measured points is the legal region (for a 1.75 m body
  a triangle with corners about (0.87, −0.02), (0.26, +0.14), (0.37, −0.11) m). Level
  steps up to ~0.8 m and moderate up/down steps are served; slopes' long steps with
  large rises are clamped to the nearest point of the hull and flagged (``clamped``).
- Eq. 10 is extended with the §4.1 foot–floor model (a pitched-down foot rolls on its
  ball, a pitched-up one on its heel) and measured between footholds; the pelvis terms
  cancel in the sagittal projection and are dropped.
- Gauss–Newton runs on the two free barycentric weights of a triangle (the blend stays
  an affine combination of three measured curves, every weight ≥ −0.2) with
  finite-difference Jacobians, batched over all requests. Eq. 10 folds where toe-first
  and heel-first landings are blended, so a request that the located triangle cannot
  reach is retried in the neighbouring triangles, then with weights ≥ −1. What still
  misses (a few % of the hull area, errors ≤ 1.5 cm) keeps its best blend and is
  flagged (``clamped``, ``converged`` False).
- Level steps (extensions, switches ``ElevInterpConfig.level_datum`` and
  ``heel_rise``, on by default; docs/architecture.md "Level steps"). Eq. 10 puts this
  body's level datasets 0.7–2 cm below the stance foot, so the paper's SH = 0 request
  blends in a stair dataset. A level request is served by the level datasets alone
  (the "level line"), a low rise with its height measured from theirs; the blend is
  then closed by the trailing foot (a higher heel through push-off, closed form on the
  ball's circle) and the length solved again, so the swing foot lands on the floor. The
  line extrapolates ``level_line_beyond`` (1.5) end intervals past the shortest and the
  longest level dataset, and a closed line step is served at the requested height.
- Low rises (extension, switch ``ElevInterpConfig.low_rise_blend``, on by default): a rise
  below ``level_fade`` blends the triangulation's dataset with the level line, the line's
  share fading out with the rise, so a step of a few mm is not suddenly a blend with the
  stair datasets (docs/architecture.md "Low rises blended with the level line").
- Speed blend (extension, switch ``ElevInterpConfig.speed_blend``; the paper blends by
  step length and height only). Given each step's walking speed, the level datasets
  (Bovi's xs … l) blended by *speed* replace, in mid-stance and mid-swing, the level
  datasets blended by the step's *length*: the curves gain the residual
  ``(L(speed) − L(length)) · sin²(2πt)``, faded out with step height. The window is zero
  at t = 0 and t = 0.5, the rows Eq. 10 reads, so the produced step is unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numba as nb
import numpy as np
from scipy.spatial import ConvexHull, Delaunay, cKDTree

from crowdwalk.errors import invalid
from crowdwalk.gait.datasets import STAIR_CLOSURES, ElevationDataset, load_datasets, sample

__all__ = [
    "ElevInterp",
    "ElevInterpConfig",
    "LegLike",
    "SagittalLeg",
    "StepDatasets",
    "dataset_step",
    "lift_swing_toe",
    "step_of",
]

LEG_FIELDS = ("thigh", "shank", "ankle_height", "heel_offset", "ball_offset")
"""Leg dimensions the forward kinematics use; ``ball_offset`` falls back to ``toe_offset``."""


def _dimension(leg: LegLike, name: str) -> float | np.ndarray:
    """A leg dimension [m]; the roll point is the ball if the leg has one, else the toe."""
    if name == "ball_offset" and getattr(leg, "ball_offset", None) is None:
        name = "toe_offset"
    return getattr(leg, name)


class LegLike(Protocol):
    """Anything with sagittal leg dimensions [m], floats or (n,) arrays (e.g. ``body.Body``).

    An optional ``ball_offset`` (ankle to first metatarsal head) is the forefoot roll
    point; without it the foot rolls on the toe tip (``toe_offset``).
    """

    thigh: float | np.ndarray
    shank: float | np.ndarray
    ankle_height: float | np.ndarray
    heel_offset: float | np.ndarray
    toe_offset: float | np.ndarray


@dataclass(frozen=True)
class SagittalLeg:
    """Sagittal leg dimensions [m] for :func:`step_of` (floats or (n,) arrays).

    ``thigh`` hip→knee, ``shank`` knee→ankle, ``ankle_height`` ankle centre above the
    sole, ``heel_offset`` / ``ball_offset`` / ``toe_offset`` distance along the sole from
    the ankle to the back of the heel / the first metatarsal head (forefoot roll point) /
    the toe tip.
    """

    thigh: float | np.ndarray
    shank: float | np.ndarray
    ankle_height: float | np.ndarray
    heel_offset: float | np.ndarray
    toe_offset: float | np.ndarray
    ball_offset: float | np.ndarray | None = None

    @classmethod
    def from_body_height(cls, height: float | np.ndarray) -> SagittalLeg:
        """Segment lengths from body height [m] with Winter (2009, Fig. 4.1) proportions.

        thigh 0.245 H, shank 0.246 H, ankle height 0.039 H, foot length 0.152 H of which
        a quarter lies behind the ankle (heel) and three quarters ahead (toe); the ball
        (first metatarsal head) 0.073 H ahead of the ankle — the proportions of
        ``crowdwalk.body`` and ``planners.Leg``.
        """
        h = np.asarray(height, dtype=float)
        if not np.all(np.isfinite(h) & (h > 0)):
            raise invalid("SagittalLeg", "height", "finite and > 0 [m]", height)
        if h.ndim == 0:
            h = float(h)
        return cls(0.245 * h, 0.246 * h, 0.039 * h, 0.038 * h, 0.114 * h, 0.073 * h)

    @property
    def length(self) -> float | np.ndarray:
        """Leg length: thigh + shank + ankle height [m]."""
        return self.thigh + self.shank + self.ankle_height


def _segment(phi: np.ndarray) -> np.ndarray:
    """Unit vector proximal→distal for an elevation angle [rad]; shape phi.shape + (2,)."""
    return np.stack([np.sin(phi), -np.cos(phi)], axis=-1)


@nb.njit(cache=True, nogil=True)
def _step_of_kernel(stance, swing, thigh, shank, ankle_h, heel, toe, out):  # pragma: no cover
    """:func:`step_of` of m leg pairs (stance, swing (m, 3); dimensions (m,)) into out
    (m, 2): the numpy code's arithmetic in the same order (bitwise equal)."""
    for a in range(stance.shape[0]):
        f = stance[a, 0]
        c, s = np.cos(f), np.sin(f)
        if f <= 0.0:
            px, w = toe[a], -toe[a]
        else:
            px, w = -heel[a], heel[a]
        ax = px + w * c + ankle_h[a] * (-s)
        ay = 0.0 + w * s + ankle_h[a] * c
        p1, p2 = stance[a, 1], stance[a, 2]
        hx = ax - shank[a] * np.sin(p1) - thigh[a] * np.sin(p2)
        hy = ay - shank[a] * (-np.cos(p1)) - thigh[a] * (-np.cos(p2))
        q1, q2 = swing[a, 1], swing[a, 2]
        sx = hx + thigh[a] * np.sin(q2) + shank[a] * np.sin(q1)
        sy = hy + thigh[a] * (-np.cos(q2)) + shank[a] * (-np.cos(q1))
        g = swing[a, 0]
        c, s = np.cos(g), np.sin(g)
        if g >= 0.0:
            out[a, 0] = sx - heel[a] * c - ankle_h[a] * (-s) + heel[a]
            out[a, 1] = sy - heel[a] * s - ankle_h[a] * c
        else:
            out[a, 0] = sx + toe[a] * c - ankle_h[a] * (-s) - toe[a]
            out[a, 1] = sy + toe[a] * s - ankle_h[a] * c


@nb.njit(cache=True, nogil=True)
def _level_line_kernel(xs, keys, angles, phases, length, props, beyond
                       ):  # pragma: no cover - compiled
    """:meth:`ElevInterp._level_line`'s arithmetic per request, the numpy code's order
    (bitwise equal): level datasets' Eq. 10 lengths xs (m,) ascending, key rows (m, 2, 4),
    curves (m, N, 4), phases (m, 2); lengths (k,) and leg dimensions props (k, 5) [leg
    lengths]. Returns curves (k, N, 4), phases (k, 2), steps (k, 2)."""
    k, m, n = length.shape[0], xs.shape[0], angles.shape[1]
    j = np.empty(k, np.intp)
    f, lo, span = np.empty(k), np.empty(k), np.empty(k)
    for r in range(k):
        i = 0  # np.searchsorted(xs, length) (side "left"), less one, clipped
        while i < m and xs[i] < length[r]:
            i += 1
        i = min(max(i - 1, 0), m - 2)
        j[r], lo[r], span[r] = i, xs[i], xs[i + 1] - xs[i]
        v = (length[r] - lo[r]) / span[r]
        v = v if (np.isnan(v) or v > -beyond) else -beyond  # np.clip
        f[r] = v if (np.isnan(v) or v < 1.0 + beyond) else 1.0 + beyond
    stance, swing = np.empty((k, 3)), np.empty((k, 3))
    step = np.empty((k, 2))
    for rounds in range(4):  # three secant steps, then the step of the final weight
        for r in range(k):
            w, i = f[r], j[r]
            for c in range(3):
                stance[r, c] = (1.0 - w) * keys[i, 0, c] + w * keys[i + 1, 0, c]
                swing[r, c] = (1.0 - w) * keys[i, 1, c] + w * keys[i + 1, 1, c]
        _step_of_kernel(stance, swing, props[:, 0], props[:, 1], props[:, 2], props[:, 3],
                        props[:, 4], step)
        if rounds < 3:
            for r in range(k):
                v = f[r] + (length[r] - step[r, 0]) / span[r]
                v = v if (np.isnan(v) or v > -beyond) else -beyond
                f[r] = v if (np.isnan(v) or v < 1.0 + beyond) else 1.0 + beyond
    curves = np.empty((k, n, 4))
    blended = np.empty((k, 2))
    for r in range(k):
        w, i = f[r], j[r]
        for s in range(n):
            for c in range(4):
                curves[r, s, c] = (1.0 - w) * angles[i, s, c] + w * angles[i + 1, s, c]
        for c in range(2):
            blended[r, c] = (1.0 - w) * phases[i, c] + w * phases[i + 1, c]
    return curves, blended, step


@nb.njit(cache=True, nogil=True)
def _clamp_kernel(target, hull, centre):  # pragma: no cover - compiled
    """:meth:`_ShapeSpace.clamp`'s arithmetic per target (k, 2), the numpy code's order
    (bitwise equal): the counter-clockwise polygon ``hull`` (h, 2), its vertex mean
    ``centre`` (2,). Returns the clamped targets (k, 2) and whether outside (k,)."""
    k, h = target.shape[0], hull.shape[0]
    out = np.empty((k, 2))
    outside = np.zeros(k, np.bool_)
    proj = np.empty((h, 2))
    for r in range(k):
        best, best_d = 0, 0.0
        for e in range(h):
            n = e + 1 if e + 1 < h else 0  # np.roll(hull, -1)
            e0, e1 = hull[n, 0] - hull[e, 0], hull[n, 1] - hull[e, 1]
            r0, r1 = target[r, 0] - hull[e, 0], target[r, 1] - hull[e, 1]
            u = (r0 * e0 + r1 * e1) / (e0 * e0 + e1 * e1)
            u = u if (np.isnan(u) or u > 0.0) else 0.0  # np.clip(u, 0, 1)
            u = u if (np.isnan(u) or u < 1.0) else 1.0
            proj[e, 0], proj[e, 1] = hull[e, 0] + u * e0, hull[e, 1] + u * e1
            d0, d1 = target[r, 0] - proj[e, 0], target[r, 1] - proj[e, 1]
            d = np.sqrt(d0 * d0 + d1 * d1)
            if e == 0 or (not np.isnan(best_d) and (np.isnan(d) or d < best_d)):
                best, best_d = e, d  # np.argmin: the first least (the first NaN)
            cross = e0 * r1 - e1 * r0
            if cross < -1e-12 * np.sqrt(e0 * e0 + e1 * e1):
                outside[r] = True
        if outside[r]:
            for c in range(2):
                out[r, c] = proj[best, c] + 1e-9 * (centre[c] - proj[best, c])
        else:
            out[r, 0], out[r, 1] = target[r, 0], target[r, 1]
    return out, outside


def _flat_rows(a: np.ndarray, shape: tuple) -> np.ndarray:
    """``a`` broadcast to ``shape``, C-contiguous (no broadcast where it has the shape)."""
    if a.shape == shape:
        return np.ascontiguousarray(a)
    return np.ascontiguousarray(np.broadcast_to(a, shape))


def step_of(stance: np.ndarray, swing: np.ndarray, leg: LegLike) -> np.ndarray:
    """Step length and height a pair of leg silhouettes produces (Eq. 10, extended).

    Sagittal forward kinematics from the stance foot's ground contact up the stance leg
    and down the swing leg (Sun & Metaxas 2001, Eq. 10, Fig. 11). Deviations from Eq. 10:
    the pelvis terms are dropped (both hips project onto the same sagittal point, so the
    pelvis segment cancels), and the feet follow the foot–floor model of §4.1 — a foot
    with a negative elevation rolls on its ball (first metatarsal head, the toes flat on
    the ground; the toe tip if the leg has no ``ball_offset``), with a positive one on
    its heel — the contact model of ``gait.elevwalker``. Step
    length and height are measured between *footholds* (the ground point below the ankle
    once the foot is flat, the ``planners`` convention): the stance foothold is the
    origin, the swing foothold is where the swing foot lands.

    Parameters
    ----------
    stance, swing : numpy.ndarray
        Shape (..., ≥3) elevation angles [rad], columns foot, shank, thigh(, pelvis):
        stance leg at ``t = 0.5`` and swing leg at ``t = 0`` (heel strike) for a dataset.
    leg : LegLike
        Leg dimensions [m], floats or arrays broadcastable to ``stance.shape[:-1]``.

    Returns
    -------
    numpy.ndarray
        Shape (..., 2): step length and step height [m].
    """
    stance = np.asarray(stance, dtype=float)
    swing = np.asarray(swing, dtype=float)
    dims = [np.asarray(_dimension(leg, k), dtype=float) for k in LEG_FIELDS]
    if stance.shape[-1] >= 3 and swing.shape[-1] >= 3:  # the code below, compiled
        shape = np.broadcast_shapes(stance.shape[:-1], swing.shape[:-1], *(d.shape for d in dims))
        flat = [_flat_rows(a[..., :3], shape + (3,)).reshape(-1, 3) for a in (stance, swing)]
        flat += [_flat_rows(d, shape).reshape(-1) for d in dims]
        out = np.empty((flat[0].shape[0], 2))
        _step_of_kernel(*flat, out)
        return out.reshape(shape + (2,))
    return _step_of_numpy(stance, swing, dims)


def _step_of_numpy(stance: np.ndarray, swing: np.ndarray, dims: list) -> np.ndarray:
    """:func:`step_of` in numpy, ``dims`` the leg's LEG_FIELDS arrays [m]: what
    ``_step_of_kernel`` compiles (and the path for stance/swing with fewer than 3 columns)."""
    thigh, shank, ankle_h, heel, toe = (d[..., None] for d in dims)
    # ``toe`` is the forefoot roll point (ball)
    # Stance foot: pivot on the ball (foot pitched down) or on the heel, pivot fixed.
    f_st = stance[..., 0:1]
    u_st = np.concatenate([np.cos(f_st), np.sin(f_st)], axis=-1)  # heel→toe
    n_st = np.concatenate([-np.sin(f_st), np.cos(f_st)], axis=-1)  # sole normal, up
    on_toe = f_st <= 0.0
    pivot_x = np.where(on_toe, toe, -heel)
    pivot = np.concatenate([pivot_x, np.zeros_like(pivot_x)], axis=-1)
    ankle = pivot + np.where(on_toe, -toe, heel) * u_st + ankle_h * n_st
    hip = ankle - shank * _segment(stance[..., 1]) - thigh * _segment(stance[..., 2])
    # Swing leg down from the hip.
    ankle_sw = hip + thigh * _segment(swing[..., 2]) + shank * _segment(swing[..., 1])
    f_sw = swing[..., 0:1]
    u_sw = np.concatenate([np.cos(f_sw), np.sin(f_sw)], axis=-1)
    n_sw = np.concatenate([-np.sin(f_sw), np.cos(f_sw)], axis=-1)
    heel_sw = ankle_sw - heel * u_sw - ankle_h * n_sw
    toe_sw = ankle_sw + toe * u_sw - ankle_h * n_sw
    on_heel = f_sw >= 0.0
    length = np.where(on_heel, heel_sw[..., 0:1] + heel, toe_sw[..., 0:1] - toe)
    height = np.where(on_heel, heel_sw[..., 1:2], toe_sw[..., 1:2])
    return np.concatenate([length, height], axis=-1)


def dataset_step(angles: ElevationDataset | np.ndarray, leg: LegLike) -> np.ndarray:
    """Step length and height [m] a dataset produces for a leg (Eq. 10 via :func:`step_of`).

    Parameters
    ----------
    angles : ElevationDataset or numpy.ndarray
        One dataset, an (N, 4) curve or a batch (n, N, 4) of curves [rad].
    leg : LegLike
        Leg dimensions [m], floats or (n,) arrays.

    Returns
    -------
    numpy.ndarray
        Shape (2,) or (n, 2): step length, step height [m]. The stance leg is read at
        t = 0.5 and the swing leg at t = 0 (its heel strike; §5.1).
    """
    curves = angles.angles if isinstance(angles, ElevationDataset) else np.asarray(angles)
    if curves.ndim == 3:
        n = curves.shape[0]
        return step_of(sample(curves, np.full(n, 0.5)), sample(curves, np.zeros(n)), leg)
    return step_of(sample(curves, 0.5), sample(curves, 0.0), leg)


@dataclass(frozen=True)
class ElevInterpConfig:
    """Parameters of :class:`ElevInterp`.

    Attributes
    ----------
    tolerance : float
        Accepted distance between the requested and the produced step [m]; a blend
        further off is refined by Gauss–Newton.
    max_iterations : int
        Gauss–Newton iterations per request.
    insert_spacing : float
        Solved datasets closer than this to a dataset already in the triangulation are
        not inserted [1, leg lengths]; bounds the cache (the "rounded request").
    max_inserted : int
        Inserted datasets kept per body shape; beyond it no more are inserted.
    shape_resolution : float
        Leg proportions (dimension / leg length) are rounded to this to key the cache [1].
    extrapolation : float
        Gauss–Newton keeps every blend weight ≥ −extrapolation [1] in the located and the
        neighbouring triangles ...
    last_resort_extrapolation : float
        ... and ≥ −last_resort_extrapolation [1] in a final pass for requests those miss
        (where Eq. 10 folds between toe-first and heel-first landings).
    speed_blend : bool
        Requests with a ``speed`` also blend the level datasets by walking speed (an
        extension of §5, see the module notes); False (default) is the paper's
        ElevInterp. Off by default: measured on lone walkers it raises the hip and knee
        RMS against Winter (docs/architecture.md, "Speed blend").
    speed_fade : float
        The speed residual fades linearly to zero at this |step height| [leg lengths].
    level_datum : bool
        Level requests are served from the level datasets alone (an extension of §5,
        module notes): SH = 0 by the two level datasets whose Eq. 10 lengths bracket the
        request (extrapolated a little beyond the slowest and fastest), a low rise by
        the triangulation with its height measured from the level datasets' own Eq. 10
        height, so neither blends in the stair datasets. False: the paper's space.
    heel_rise : bool
        Near-level datasets are closed by the trailing foot (an extension of §5, module
        notes): the foot elevation is lowered (heel raised, rolling on the ball) from
        mid-stance through push-off so that Eq. 10 lands the swing foot at the requested
        height, instead of the Animator bending the swing knee to reach it. False: the
        blended dataset as it is.
    level_fade : float
        Datum and heel rise fade linearly to zero at this |step height| [leg lengths].
    level_line_beyond : float
        The level line (``level_datum``) is extrapolated linearly at most this many of
        its end intervals beyond the shortest and the longest level dataset [1] (a
        longer or shorter level request leaves the line for the triangulation, which
        blends in the stair datasets). 1.5 (was 0.6): a 1.95 m body's level datasets
        start at 0.67 m, its 0.8 m/s step is 0.54 m (docs/architecture.md "Level line
        extrapolation").
    knee_closure : bool
        With ``heel_rise``, what the trailing foot cannot close the trailing knee does,
        extending toward straight at the other heel strike (an extension of §5,
        docs/architecture.md "Knee closure of long level steps"); False: such steps (a
        1.75 m body's level steps beyond about 0.81 m) are served from the paper's
        triangulation, clamped, the swing foot 0.5-2 cm below the floor.
    stair_closure : {"swing", "linear"}
        The shipped stair datasets used when no ``datasets`` are given
        (:func:`~crowdwalk.gait.datasets.load_datasets`): "swing" (default), Bovi's stair
        cycles closed over the swing, the stance as measured; "linear", closed linearly
        over the whole cycle (before gait11: the ascending stance knee 20° more flexed
        than Bovi's; docs/architecture.md "Stair datasets closed over the swing").
    low_rise_blend : bool
        With ``level_datum``, a low rise (0 < |SH| < ``level_fade``) is served by the
        paper's triangulation blended with the level line at its length, the line's
        share ``1 − |SH| / level_fade`` (1 at level, 0 at ``level_fade``), then closed to
        its height by the trailing foot (``heel_rise``) as before (an extension of §5,
        docs/architecture.md "Low rises blended with the level line"). Default on:
        without it a 1 mm rise left the level line for a blend with the stair datasets
        (a 0.5 m step: angles 22° off the level step's); False: that.
    """

    tolerance: float = 0.002
    max_iterations: int = 12
    insert_spacing: float = 0.005
    max_inserted: int = 4096
    shape_resolution: float = 0.005
    extrapolation: float = 0.2
    last_resort_extrapolation: float = 1.0
    speed_blend: bool = False
    speed_fade: float = 0.04
    level_datum: bool = True
    heel_rise: bool = True
    level_fade: float = 0.04
    level_line_beyond: float = 1.5
    knee_closure: bool = True
    stair_closure: str = "swing"
    low_rise_blend: bool = True

    def __post_init__(self) -> None:
        owner = "ElevInterpConfig"
        if self.stair_closure not in STAIR_CLOSURES:
            raise invalid(owner, "stair_closure", f"one of {STAIR_CLOSURES}", self.stair_closure)
        units = {"tolerance": "m", "insert_spacing": "1", "shape_resolution": "1",
                 "speed_fade": "1", "level_fade": "1"}
        for name, unit in units.items():
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise invalid(owner, name, f"finite and > 0 [{unit}]", value)
        for name in ("extrapolation", "last_resort_extrapolation", "level_line_beyond"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise invalid(owner, name, "finite and >= 0 [1]", value)
        if self.max_iterations < 1:
            raise invalid(owner, "max_iterations", ">= 1 [1]", self.max_iterations)
        if self.max_inserted < 0:
            raise invalid(owner, "max_inserted", ">= 0 [1]", self.max_inserted)


@dataclass(frozen=True, eq=False)
class StepDatasets:
    """Datasets produced for a batch of n step requests.

    Attributes
    ----------
    angles : numpy.ndarray
        (n, N, 4) elevation angles [rad] (foot, shank, thigh, pelvis), t = k / N.
    step_length, step_height : numpy.ndarray
        (n,) step each dataset produces for its body by Eq. 10 [m].
    target : numpy.ndarray
        (n, 2) the request actually served (after clamping) [m].
    clamped : numpy.ndarray
        (n,) bool, the request could not be served exactly: it lay outside the legal
        region (``target`` is then the nearest point of it), or inside it where no blend
        reaches it (a fold of Eq. 10; ``converged`` False). Either way the dataset is the
        nearest blend found and ``step_length``/``step_height`` say what it produces.
    refined : numpy.ndarray
        (n,) bool, Gauss–Newton was needed (the barycentric blend missed).
    converged : numpy.ndarray
        (n,) bool, the produced step is within ``tolerance`` of ``target``.
    stance_fraction, double_support : numpy.ndarray
        (n,) blended phase fractions of the stride [1].
    """

    angles: np.ndarray
    step_length: np.ndarray
    step_height: np.ndarray
    target: np.ndarray
    clamped: np.ndarray
    refined: np.ndarray
    converged: np.ndarray
    stance_fraction: np.ndarray
    double_support: np.ndarray


def _key_rows(curves: np.ndarray) -> np.ndarray:
    """Angles (n, 2, 4) [rad] of curves (n, N, 4) at t = 0.5 (stance) and t = 0 (swing)."""
    return np.stack([sample(curves, np.full(len(curves), 0.5)), curves[:, 0]], axis=1)


def _leg_of(props: np.ndarray) -> SagittalLeg:
    """SagittalLeg from an (..., 5) array of dimensions in LEG_FIELDS order."""
    ball = props[..., 4]
    return SagittalLeg(*(props[..., i] for i in range(4)), toe_offset=ball, ball_offset=ball)


def _delaunay(points: np.ndarray) -> Delaunay:
    """Delaunay triangulation with its barycentric transforms computed in closed form.

    Measured: SciPy computes the transforms lazily with one LAPACK call per triangle,
    which under OpenBLAS threading on this loaded 2-core machine took 1.2 s CPU for 800
    points (2 ms with OPENBLAS_NUM_THREADS=1). The 2×2 inverses here take microseconds
    and are handed to SciPy's cache so ``find_simplex`` uses them. Qhull's incremental
    ``add_points`` had the same cost at every insertion, so the triangulation is rebuilt.
    """
    tri = Delaunay(points)
    p = points[tri.simplices]  # (m, 3, 2)
    t = np.stack([p[:, 0] - p[:, 2], p[:, 1] - p[:, 2]], axis=-1)  # columns r_i - r_n
    det = t[:, 0, 0] * t[:, 1, 1] - t[:, 0, 1] * t[:, 1, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.stack([np.stack([t[:, 1, 1], -t[:, 0, 1]], -1),
                        np.stack([-t[:, 1, 0], t[:, 0, 0]], -1)], axis=1) / det[:, None, None]
    inv[np.abs(det) <= 1e-14 * np.abs(t).max(axis=(1, 2)) ** 2] = np.nan  # degenerate
    tri._transform = np.concatenate([inv, p[:, 2][:, None, :]], axis=1)
    return tri


class _ShapeSpace:
    """Triangulated Height/Length space of one body shape, lengths in leg lengths."""

    def __init__(self, shape: np.ndarray, curves: np.ndarray, phases: np.ndarray,
                 spacing: float):
        self.shape = shape
        self.spacing = spacing  # inserted datasets at least this far apart [leg lengths]
        self.capacity = max(64, 2 * len(curves))
        n, n_samples, _ = curves.shape
        self.angles = np.empty((self.capacity, n_samples, 4))
        self.angles[:n] = curves
        self.phases = np.empty((self.capacity, 2))
        self.phases[:n] = phases
        self.keys = np.empty((self.capacity, 2, 4))  # rows at t = 0.5 (stance) and t = 0
        self.keys[:n] = _key_rows(curves)
        self.count = n
        self.n_sources = n
        points = step_of(self.keys[:n, 0], self.keys[:n, 1], _leg_of(shape))
        self.points = points
        self.hull = points[ConvexHull(points).vertices]  # counter-clockwise polygon
        self.tri = _delaunay(points)
        self.tree = cKDTree(points)

    def clamp(self, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Targets moved onto the hull where outside; (k, 2) and (k,) bool (compiled:
        :func:`_clamp_kernel`; tests/gait/test_elevinterp.py holds the numpy code it compiles)."""
        return _clamp_kernel(np.ascontiguousarray(target, dtype=float), self.hull,
                             self.hull.mean(axis=0))

    def locate(self, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Indices (k,) of the containing triangles and barycentric weights (k, 3)."""
        simplex = self.tri.find_simplex(target, tol=1e-9)
        lost = simplex < 0
        if np.any(lost):  # round-off on the hull boundary
            simplex[lost] = self.tri.find_simplex(target[lost], bruteforce=True, tol=1e-6)
        lost = simplex < 0
        if np.any(lost):  # nearest triangle by centroid, last resort
            centroids = self.tri.points[self.tri.simplices].mean(axis=1)
            d = np.linalg.norm(target[lost, None] - centroids[None], axis=-1)
            simplex[lost] = np.argmin(d, axis=1)
        weights = self.weights_in(simplex, target)
        return simplex, weights

    def weights_in(self, simplex: np.ndarray, target: np.ndarray) -> np.ndarray:
        """Barycentric coordinates (k, 3) of targets w.r.t. given triangles (may be < 0)."""
        transform = self.tri.transform[simplex]
        b = np.einsum("kij,kj->ki", transform[:, :2], target - transform[:, 2])
        return np.concatenate([b, 1.0 - b.sum(axis=1, keepdims=True)], axis=1)

    def insert(self, curves: np.ndarray, phases: np.ndarray, limit: int) -> int:
        """Insert solved datasets (§5.1 step 6); returns how many were inserted."""
        room = limit - (self.count - self.n_sources)
        if room <= 0 or len(curves) == 0:
            return 0
        keys = _key_rows(curves)
        points = step_of(keys[:, 0], keys[:, 1], _leg_of(self.shape))
        far = self.tree.query(points)[0] > self.spacing
        grid = np.round(points / self.spacing).astype(np.int64)
        _, first = np.unique(grid, axis=0, return_index=True)
        pick = np.zeros(len(points), bool)
        pick[first] = True
        pick &= far
        inside = self.tri.find_simplex(points) >= 0
        pick &= inside
        idx = np.flatnonzero(pick)[:room]
        if len(idx) == 0:
            return 0
        self._grow(self.count + len(idx))
        sl = slice(self.count, self.count + len(idx))
        self.angles[sl], self.phases[sl], self.keys[sl] = curves[idx], phases[idx], keys[idx]
        self.count += len(idx)
        self.points = np.vstack([self.points, points[idx]])
        self.tri = _delaunay(self.points)
        self.tree = cKDTree(self.points)
        return len(idx)

    def _grow(self, needed: int) -> None:
        if needed <= self.capacity:
            return
        self.capacity = max(needed, 2 * self.capacity)
        for name in ("angles", "phases", "keys"):
            old = getattr(self, name)
            new = np.empty((self.capacity, *old.shape[1:]))
            new[: self.count] = old[: self.count]
            setattr(self, name, new)


class ElevInterp:
    """Inverse motion interpolation (Sun & Metaxas 2001, §5): (SL, SH) → dataset.

    Parameters
    ----------
    datasets : sequence of ElevationDataset, optional
        Source datasets (default: :func:`crowdwalk.gait.datasets.load_datasets`). At
        least three whose steps are not collinear; all with the same sample count N.
    config : ElevInterpConfig, optional

    Examples
    --------
    >>> interp = ElevInterp()
    >>> leg = SagittalLeg.from_body_height(np.array([1.6, 1.8]))
    >>> out = interp.request(leg, step_length=[0.65, 0.70], step_height=[0.0, 0.05])
    >>> out.angles.shape
    (2, 100, 4)
    """

    def __init__(
        self,
        datasets: Sequence[ElevationDataset] | None = None,
        config: ElevInterpConfig | None = None,
    ):
        config = config or ElevInterpConfig()
        datasets = list(load_datasets(config.stair_closure) if datasets is None else datasets)
        if len(datasets) < 3:
            raise invalid("ElevInterp", "datasets", "at least 3 datasets", len(datasets))
        sizes = {d.samples for d in datasets}
        if len(sizes) != 1:
            raise invalid("ElevInterp", "datasets", "of one sample count N", sorted(sizes))
        self.datasets = tuple(datasets)
        self.config = config
        self._curves = np.stack([d.angles for d in datasets])
        self._phases = np.array([[d.stance_fraction, d.double_support] for d in datasets])
        self._level = np.array([i for i, d in enumerate(datasets) if d.kind == "level"], int)
        self._spaces: dict[tuple[int, ...], _ShapeSpace] = {}
        self.stats = {"requests": 0, "refined": 0, "clamped": 0, "inserted": 0, "failed": 0}

    # -- public -----------------------------------------------------------------------
    def request(
        self, leg: LegLike, step_length: np.ndarray | float, step_height: np.ndarray | float,
        *, speed: np.ndarray | float | None = None,
    ) -> StepDatasets:
        """Datasets that produce the requested steps for the given bodies (batched).

        Parameters
        ----------
        leg : LegLike
            Leg dimensions [m] (``thigh``, ``shank``, ``ankle_height``, ``heel_offset``,
            ``toe_offset``, optional ``ball_offset``), floats or (n,) arrays — e.g. a
            ``body.Body``.
        step_length : float or numpy.ndarray
            (n,) requested step lengths [m], > 0, foothold to foothold.
        step_height : float or numpy.ndarray
            (n,) requested rise of the new foothold over the stance foothold [m].
        speed : float or numpy.ndarray, optional
            (n,) walking speed of each step [m/s] (step length / duration); with
            ``config.speed_blend`` the level datasets are also blended by it.

        Returns
        -------
        StepDatasets
        """
        sl = np.atleast_1d(np.asarray(step_length, dtype=float))
        sh = np.atleast_1d(np.asarray(step_height, dtype=float))
        dims = [np.atleast_1d(np.asarray(_dimension(leg, k), dtype=float)) for k in LEG_FIELDS]
        try:
            arrays = np.broadcast_arrays(sl, sh, *dims)
        except ValueError:
            shapes = [a.shape for a in (sl, sh, *dims)]
            raise invalid("ElevInterp", "request", "of broadcastable shapes", shapes) from None
        sl, sh, *dims = (a.ravel() for a in arrays)
        self._validate(sl, sh, dims)
        props = np.stack(dims, axis=1)
        length = props[:, 0] + props[:, 1] + props[:, 2]
        props = props / length[:, None]
        target = np.stack([sl, sh], axis=1) / length[:, None]
        res = self.config.shape_resolution
        keys = np.round(props / res).astype(np.int64)
        shapes, which = np.unique(keys, axis=0, return_inverse=True)
        which = which.ravel()
        n, n_samples = len(sl), self._curves.shape[1]
        angles = np.empty((n, n_samples, 4))
        phases = np.empty((n, 2))
        achieved = np.empty((n, 2))
        served = np.empty((n, 2))
        flags = np.zeros((n, 3), bool)
        for g, key in enumerate(shapes):
            idx = np.flatnonzero(which == g)
            space = self._space(key, props[idx[0]])
            out = self._solve_level(space, target[idx], props[idx], length[idx])
            angles[idx], phases[idx], achieved[idx], served[idx], flags[idx] = out
        if speed is not None and self.config.speed_blend:
            v = np.broadcast_to(np.asarray(speed, dtype=float), sl.shape)
            if not np.all(np.isfinite(v) & (v > 0)):
                raise invalid("ElevInterp", "speed", "finite and > 0 [m/s]", float(v.min()))
            angles += self._speed_residual(v, served, props)
        achieved *= length[:, None]
        served *= length[:, None]
        self.stats["requests"] += n
        self.stats["clamped"] += int(flags[:, 0].sum())
        self.stats["refined"] += int(flags[:, 1].sum())
        self.stats["failed"] += int((~flags[:, 2]).sum())
        return StepDatasets(
            angles=angles,
            step_length=achieved[:, 0],
            step_height=achieved[:, 1],
            target=served,
            clamped=flags[:, 0],
            refined=flags[:, 1],
            converged=flags[:, 2],
            stance_fraction=phases[:, 0],
            double_support=phases[:, 1],
        )

    def legal_region(self, leg: LegLike) -> np.ndarray:
        """Polygon (k, 2) of servable (step length, step height) [m] for one body.

        The convex hull of the source datasets' steps, counter-clockwise.
        """
        dims = np.array([float(np.asarray(_dimension(leg, k)).ravel()[0]) for k in LEG_FIELDS])
        self._validate(np.ones(1), np.zeros(1), [dims[[i]] for i in range(5)])
        length = dims[:3].sum()
        shape = dims / length
        key = np.round(shape / self.config.shape_resolution).astype(np.int64)
        return self._space(key, shape).hull * length

    def source_steps(self, leg: LegLike) -> np.ndarray:
        """(m, 2) step length and height [m] of each source dataset for ``leg`` (Eq. 10)."""
        return dataset_step(self._curves, leg)

    # -- internals --------------------------------------------------------------------
    def _speed_residual(self, speed: np.ndarray, served: np.ndarray,
                        props: np.ndarray) -> np.ndarray:
        """(n, N, 4) [rad]: level datasets blended by speed minus blended by step length.

        Both blends are piecewise linear over the level datasets (clamped to their
        range); the length of a level dataset is its Eq. 10 step for the request's body
        shape [leg lengths]. Windowed by sin²(2πt) (zero at the Eq. 10 rows) and faded
        with |step height| over ``config.speed_fade``.
        """
        level = [i for i, d in enumerate(self.datasets) if d.name.startswith("level")]
        if len(level) < 2:
            return np.zeros((len(speed), *self._curves.shape[1:]))
        curves = self._curves[level]
        by_speed = np.argsort([self.datasets[i].speed for i in level])
        speeds = np.array([self.datasets[i].speed for i in level])[by_speed]
        lengths = dataset_step(curves[None].repeat(len(speed), 0).reshape(-1, *curves.shape[1:]),
                               _leg_of(np.repeat(props, len(level), axis=0)))
        lengths = lengths[:, 0].reshape(len(speed), len(level))  # (n, k) [leg lengths]

        def weights(x, xs):  # (n, k) hat-function weights of x (n, 1) in sorted knots xs
            x = np.clip(x, xs[:, :1], xs[:, -1:])
            j = np.clip((xs <= x).sum(axis=1, keepdims=True) - 1, 0, xs.shape[1] - 2)
            lo, hi = np.take_along_axis(xs, j, 1), np.take_along_axis(xs, j + 1, 1)
            f = (x - lo) / np.where(hi > lo, hi - lo, 1.0)
            w = np.zeros(xs.shape)
            np.put_along_axis(w, j, 1.0 - f, 1)
            np.put_along_axis(w, j + 1, f, 1)
            return w

        w_speed = np.zeros((len(speed), len(level)))
        w_speed[:, by_speed] = weights(speed[:, None], np.broadcast_to(speeds, w_speed.shape))
        by_len = np.argsort(lengths, axis=1)
        w_len = np.zeros_like(w_speed)
        np.put_along_axis(w_len, by_len, weights(served[:, :1],
                          np.take_along_axis(lengths, by_len, 1)), 1)
        t = np.arange(curves.shape[1]) / curves.shape[1]
        window = np.sin(2.0 * np.pi * t) ** 2
        fade = np.clip(1.0 - np.abs(served[:, 1]) / self.config.speed_fade, 0.0, 1.0)
        residual = np.einsum("nk,kmj->nmj", w_speed - w_len, curves)
        return residual * (window[None, :, None] * fade[:, None, None])

    def _space(self, key: np.ndarray, shape: np.ndarray) -> _ShapeSpace:
        """The triangulated space of a body shape; created with the first exact shape."""
        k = tuple(int(v) for v in key)
        if k not in self._spaces:
            self._spaces[k] = _ShapeSpace(np.asarray(shape, dtype=float), self._curves,
                                          self._phases, self.config.insert_spacing)
        return self._spaces[k]

    def _validate(self, sl: np.ndarray, sh: np.ndarray, dims: list[np.ndarray]) -> None:
        bad = ~np.isfinite(sl) | (sl <= 0)
        if np.any(bad):
            raise invalid("ElevInterp", "step_length", "finite and > 0 [m]", float(sl[bad][0]))
        bad = ~np.isfinite(sh)
        if np.any(bad):
            raise invalid("ElevInterp", "step_height", "finite [m]", float(sh[bad][0]))
        for name, d in zip(LEG_FIELDS, dims, strict=True):
            bad = ~np.isfinite(d) | (d <= 0)
            if np.any(bad):
                raise invalid("ElevInterp", f"leg.{name}", "finite and > 0 [m]", float(d[bad][0]))

    def _solve_level(self, space: _ShapeSpace, target: np.ndarray, props: np.ndarray,
                     metres: np.ndarray):
        """:meth:`_solve` with the level datum and the heel-rise closure where configured
        (lengths in leg lengths): a level request is served by the level datasets alone
        (:meth:`_level_line`), a low rise from the triangulation with its height moved
        onto the level datasets' own Eq. 10 height; the blend is closed by the trailing
        foot and the length asked again for what the closure moved it."""
        cfg = self.config
        if not (cfg.level_datum or cfg.heel_rise) or self._level.size < 2:
            return self._solve(space, target, props, metres)
        level = space.points[self._level]
        order = np.argsort(level[:, 0])
        level = level[order]
        fade = np.clip(1.0 - np.abs(target[:, 1]) / cfg.level_fade, 0.0, 1.0)
        ask = target.copy()
        if cfg.level_datum:
            ask[:, 1] += fade * np.interp(target[:, 0], *level.T)
        on_line = (fade >= 1.0) & cfg.level_datum

        def serve(ask):
            out = self._solve(space, ask, props, metres)
            if on_line.any():
                line = self._level_line(space, self._level[order], ask[on_line, 0], props[on_line])
                for mine, theirs in zip(out, line, strict=True):
                    mine[on_line] = theirs
            mix = ~on_line & (fade > 0.0) & cfg.low_rise_blend & cfg.level_datum
            if mix.any():  # low rises: the level line's share fades out with the rise
                curves, phases, step = out[0], out[1], out[2]
                line = self._level_line(space, self._level[order], ask[mix, 0], props[mix])
                u = fade[mix]
                curves[mix] = u[:, None, None] * line[0] + (1.0 - u)[:, None, None] * curves[mix]
                phases[mix] = u[:, None] * line[1] + (1.0 - u)[:, None] * phases[mix]
                step[mix] = dataset_step(curves[mix], _leg_of(props[mix]))
            return out

        out = serve(ask)
        missed = out[4][:, 0] & (fade > 0.0)
        if missed.any():  # the shifted request is not servable: the paper's request
            fade[missed], ask[missed], on_line[missed] = 0.0, target[missed], False
            out = serve(ask)
        if not cfg.heel_rise:
            curves, phases, step, served, flags = out
            return curves, phases, step, served - (ask - target), flags
        for again in (True, True, False):
            curves, phases, step, served, flags = out
            curves, step = _heel_rise(curves, phases[:, 0], step,
                                      np.where(fade > 0.0, target[:, 1], step[:, 1]), props,
                                      knee=cfg.knee_closure)
            if again:
                ask[:, 0] += np.where(fade > 0.0, target[:, 0] - step[:, 0], 0.0)
                out = serve(ask)
        served = served - (ask - target)
        # On the level line the closure took the step to the requested height, which is
        # what it serves: not the line's own Eq. 10 height less the datum interpolated
        # between the level datasets' heights (those differ by 1-4 mm along the line and
        # more beyond its ends, where the datum is clamped; a 3.8 mm difference at a
        # 1.75 m body's 0.9 m step failed the tolerance and sent it to the triangulation).
        served[on_line, 1] = target[on_line, 1]
        converged = np.linalg.norm(step - served, axis=1) <= cfg.tolerance / metres
        flags = np.stack([flags[:, 0] | ~converged, flags[:, 1], converged], axis=1)
        missed = flags[:, 0] & (fade > 0.0)
        if missed.any():  # closing did not reach the request: the paper's blend there
            paper = self._solve(space, target[missed], props[missed], metres[missed])
            for mine, theirs in zip((curves, phases, step, served, flags), paper, strict=True):
                mine[missed] = theirs
        return curves, phases, step, served, flags

    def _level_line(self, space: _ShapeSpace, level: np.ndarray, length: np.ndarray,
                    props: np.ndarray):
        """The level datasets ``level`` (m,) (by increasing Eq. 10 length) blended
        piecewise linearly by their Eq. 10 step length to produce ``length`` (k,) [leg
        lengths]: the neighbouring two, extrapolated linearly beyond the shortest and the
        longest by at most ``config.level_line_beyond`` of the end interval; the weight
        refined by secant steps on Eq. 10. Returns what :meth:`_solve` returns."""
        f = np.ascontiguousarray
        curves, phases, step = _level_line_kernel(
            f(space.points[level, 0]), f(space.keys[level]), f(space.angles[level]),
            f(space.phases[level]), f(length, dtype=float), f(props, dtype=float),
            float(self.config.level_line_beyond))
        served = np.stack([length, step[:, 1]], axis=1)
        converged = np.abs(step[:, 0] - length) <= 1e-4  # refined once more by the caller
        flags = np.stack([~converged, np.ones(len(length), bool), converged], axis=1)
        return curves, phases, step, served, flags

    def _solve(self, space: _ShapeSpace, target: np.ndarray, props: np.ndarray,
               metres: np.ndarray):
        """Steps 1–6 of §5.1 for requests of one body shape (lengths in leg lengths)."""
        cfg = self.config
        tol = cfg.tolerance / metres  # in leg lengths, per request
        target, clamped = space.clamp(target)  # extrapolation: nearest legal request
        simplex, w = space.locate(target)  # steps 1-2
        verts = space.tri.simplices[simplex]
        step = _blend_step(space, simplex, w, props)  # step 3: Eq. 9 blend, Eq. 10 measure
        err = np.linalg.norm(step - target, axis=1)
        refine = err > tol  # step 4
        # Step 5: Gauss–Newton on the barycentric weights, solved tightly (the result may be
        # inserted). Eq. 10 folds where toe-first and heel-first landings are blended (a
        # flat landing foot is highest), so a target may be reachable only from a
        # neighbouring triangle, or only with stronger extrapolation: try the located
        # triangle, then its neighbours, first with a small then a larger weight margin.
        for margin in (cfg.extrapolation, cfg.last_resort_extrapolation):
            if not np.any(err > tol):  # nothing left to refine (the loops would skip)
                break
            tris = [simplex] + [space.tri.neighbors[simplex, j] for j in range(3)]
            for tri in tris:
                rows = np.flatnonzero((err > tol) & (tri >= 0))
                if len(rows) == 0:
                    continue
                t_rows = tri[rows]
                w0 = np.clip(space.weights_in(t_rows, target[rows]), -margin, None)
                w0 /= w0.sum(axis=1, keepdims=True)
                s0 = _blend_step(space, t_rows, w0, props[rows])
                keys = space.keys[space.tri.simplices[t_rows]]
                w1, s1, e1 = _gauss_newton(
                    keys, props[rows], w0, target[rows], s0,
                    np.linalg.norm(s0 - target[rows], axis=1), 0.1 * tol[rows],
                    cfg.max_iterations, margin,
                )
                better = e1 < err[rows]
                take = rows[better]
                verts[take], w[take] = space.tri.simplices[t_rows[better]], w1[better]
                step[take], err[take] = s1[better], e1[better]
        converged = err <= tol
        curves = _blend(w, space.angles, verts)
        phases = _blend(w, space.phases, verts)
        good = converged & refine & ~clamped  # step 6: insert what needed the search
        self.stats["inserted"] += space.insert(curves[good], phases[good], cfg.max_inserted)
        flags = np.stack([clamped | ~converged, refine, converged], axis=1)
        return curves, phases, step, target, flags


_RISE_FROM, _RISE_OVER, _FALL_OVER = 0.3, 0.2, 0.2  # heel-rise window [stride fraction]
_MAX_RISE = 0.2  # largest change of the trailing foot's elevation [rad]


def _heel_rise(curves: np.ndarray, stance_fraction: np.ndarray, step: np.ndarray,
               height: np.ndarray, props: np.ndarray, knee: bool = False
               ) -> tuple[np.ndarray, np.ndarray]:
    """Datasets (k, N, 4) closed by the trailing foot, and the steps (k, 2) they produce.

    The stance foot at t = 0.5 rolls on its ball (§4.1); its ankle is ``R cos(f + β)``
    above the ground (R, β from ball offset and ankle height), so the elevation f' that
    raises it by the missing height ``height − step[:, 1]`` is closed form. The foot
    elevation changes by f' − f over a window: 0 until t = 0.3 (foot flat), smoothly 1
    at t = 0.5 (the other heel strikes), kept through push-off to the dataset's foot-off
    ``stance_fraction`` (k,) and gone 0.2 later (early swing; the toe clearance of the
    middle third is :func:`lift_swing_toe`'s). Lengths in leg lengths; elevations [rad].

    With ``knee`` (``ElevInterpConfig.knee_closure``), what the foot cannot close (the
    rise is capped, and the ankle rises at most to straight above the ball) the trailing
    knee closes: the stance shank's elevation at t = 0.5 is raised toward the thigh's
    (the knee extends, never past straight) over the same window, closed form on
    ``shank · cos``.
    """
    k, n = curves.shape[:2]
    ankle_h, ball = props[:, 2], props[:, 4]
    mid = sample(curves, np.full(k, 0.5))  # (k, 4) the stance leg at t = 0.5
    f = mid[:, 0]
    radius, beta = np.hypot(ball, ankle_h), np.arctan2(ball, ankle_h)
    z = radius * np.cos(f + beta)
    wanted = np.arccos(np.clip((z + height - step[:, 1]) / radius, -1.0, 1.0)) - beta
    delta = np.clip(np.minimum(wanted, 0.0) - f, -_MAX_RISE, _MAX_RISE)
    delta = np.where(f <= 0.0, delta, 0.0)  # a foot on its heel at t = 0.5: left as it is
    t = np.arange(n) / n
    rise = np.clip((t - _RISE_FROM) / _RISE_OVER, 0.0, 1.0)
    fall = np.clip((t[None, :] - stance_fraction[:, None]) / _FALL_OVER, 0.0, 1.0)
    window = np.where(t[None, :] < 0.5, (rise * rise * (3.0 - 2.0 * rise))[None, :],
                      1.0 - fall * fall * (3.0 - 2.0 * fall))
    closed = curves.copy()
    closed[:, :, 0] += delta[:, None] * window
    if knee:
        rest = height - step[:, 1] - (radius * np.cos(f + delta + beta) - z)
        shank, thigh = mid[:, 1:3].T
        lifted = -np.arccos(np.clip(np.cos(shank) + np.maximum(rest, 0.0) / props[:, 1],
                                    -1.0, 1.0))
        extend = np.where((rest > 0.0) & (f <= 0.0) & (shank < 0.0),
                          np.clip(np.minimum(lifted, thigh) - shank, 0.0, None), 0.0)
        closed[:, :, 1] += extend[:, None] * window
    return closed, dataset_step(closed, _leg_of(props))


def lift_swing_toe(angles: np.ndarray, leg: LegLike, stance_fraction: np.ndarray, *,
                   hip_drop: np.ndarray, clearance: np.ndarray) -> np.ndarray:
    """Datasets (k, N, 4) whose swing sole clears level ground by ``clearance`` (k,) [m].

    Sagittal forward kinematics at every sample (the stance foot on level ground with
    the §4.1 roll, the stance leg up, the swing leg down, the swing hip lowered by
    ``hip_drop`` (k,) [m] × sin(2πt), the pelvic list's drop at mid-swing) give the
    lowest point of the swing sole (heel, ball, toe tip) between foot-off
    ``stance_fraction`` (k,) and heel strike. Where the middle third of the swing comes
    closer than ``clearance``, the swing knee flexes more — thigh elevation up and shank
    elevation down by Δ·sin² over the swing, Δ the least that lifts every sample there
    (linearised, then refined twice; at most 0.2 rad); the foot keeps the data's
    elevation. An extension of §5: the data's own swing, with this body's foot, can
    graze the floor (docs/architecture.md, "Level steps"). Datasets that clear are
    returned unchanged.
    """
    out = np.array(angles, dtype=float, copy=True)
    k, n = out.shape[:2]
    clearance = np.broadcast_to(np.asarray(clearance, dtype=float), (k,))[:, None]
    thigh, shank, ankle_h, heel, ball, toe = (
        np.broadcast_to(np.asarray(_dimension(leg, f), dtype=float), (k,))[:, None]
        for f in (*LEG_FIELDS, "toe_offset"))
    half = n // 2
    t = (np.arange(half) / n)[None, :]  # the stance leg's t; the swing leg is at t + 0.5
    t_off = np.asarray(stance_fraction, dtype=float)[:, None] - 0.5
    if k and out.ndim == 3 and out.shape[2] == 4:  # the code below, compiled (its values)
        def f(a):
            return np.ascontiguousarray(a[:, 0])

        _lift_swing_toe_kernel(out, f(thigh), f(shank), f(ankle_h), f(heel), f(ball), f(toe),
                               f(clearance), f(t_off), f(np.broadcast_to(np.asarray(
                                   hip_drop, dtype=float).reshape(-1, 1), (k, 1))),
                               np.ascontiguousarray(t[0]), np.sin(2.0 * np.pi * t[0]),
                               _MAX_RISE)
        return out
    u = np.clip((t - t_off) / np.maximum(0.5 - t_off, 1e-6), 0.0, 1.0)  # through swing
    window = np.where(t >= t_off, np.sin(np.pi * u) ** 2, 0.0)
    middle = (u > 1.0 / 3.0) & (u < 2.0 / 3.0)
    drop = np.asarray(hip_drop, dtype=float).reshape(-1, 1) * np.sin(2.0 * np.pi * t)
    st = out[:, :half]
    f = st[..., 0]
    on_ball = f <= 0.0
    c, s_ = np.cos(f), np.sin(f)
    hip = (np.where(on_ball, -ball * s_, heel * s_) + ankle_h * c
           + shank * np.cos(st[..., 1]) + thigh * np.cos(st[..., 2]) - drop)
    for _ in range(3):
        sw = out[:, half:2 * half]
        ankle = hip - thigh * np.cos(sw[..., 2]) - shank * np.cos(sw[..., 1])
        g, h = np.cos(sw[..., 0]), np.sin(sw[..., 0])
        z = np.minimum(np.minimum(-heel * h, ball * h), toe * h) - ankle_h * g + ankle
        # the sole's rise per radian of knee flexion (thigh forward, shank back)
        rate = thigh * np.sin(sw[..., 2]) - shank * np.sin(sw[..., 1])
        need = np.where(middle & (z < clearance) & (rate > 0.05),
                        (clearance - z) / np.maximum(rate * window, 1e-6), 0.0)
        delta = np.clip(need.max(axis=1), 0.0, _MAX_RISE)
        if not np.any(delta > 1e-6):
            break
        out[:, half:2 * half, 2] += delta[:, None] * window
        out[:, half:2 * half, 1] -= delta[:, None] * window
    return out


@nb.njit(cache=True, nogil=True)
def _clip(x, lo, hi):
    """``np.clip``'s value for one float (NaN kept; ties to the bound)."""
    y = x if (np.isnan(x) or x > lo) else lo
    return y if (np.isnan(y) or y < hi) else hi


@nb.njit(cache=True, nogil=True)
def _lift_swing_toe_kernel(out, thigh, shank, ankle_h, heel, ball, toe, clearance, t_off,
                           hip_drop, t, sin_2pi_t, max_rise):  # pragma: no cover - compiled
    """:func:`lift_swing_toe`'s numpy code on ``out`` (k, N, 4) in place, the same
    operations in the same order per element (dimensions (k,) [m], t and sin 2πt (N/2,));
    the three passes stop together, as the batched code's ``np.any`` does."""
    k, n = out.shape[0], out.shape[1]
    half = n // 2
    window, hip = np.empty((k, half)), np.empty((k, half))
    middle = np.empty((k, half), np.bool_)
    delta = np.empty(k)
    for r in range(k):
        span = max(0.5 - t_off[r], 1e-6)
        for j in range(half):
            u = _clip((t[j] - t_off[r]) / span, 0.0, 1.0)
            if t[j] >= t_off[r]:
                w = np.sin(np.pi * u)
                window[r, j] = w * w
            else:
                window[r, j] = 0.0
            middle[r, j] = (u > 1.0 / 3.0) & (u < 2.0 / 3.0)
            drop = hip_drop[r] * sin_2pi_t[j]
            f = out[r, j, 0]
            c, s_ = np.cos(f), np.sin(f)
            lead = -ball[r] * s_ if f <= 0.0 else heel[r] * s_
            hip[r, j] = (lead + ankle_h[r] * c + shank[r] * np.cos(out[r, j, 1])
                         + thigh[r] * np.cos(out[r, j, 2]) - drop)
    for _ in range(3):
        more = False
        for r in range(k):
            best = -np.inf
            nan = False
            for j in range(half):
                sw0, sw1, sw2 = out[r, half + j, 0], out[r, half + j, 1], out[r, half + j, 2]
                ankle = hip[r, j] - thigh[r] * np.cos(sw2) - shank[r] * np.cos(sw1)
                g, h = np.cos(sw0), np.sin(sw0)
                low = min(min(-heel[r] * h, ball[r] * h), toe[r] * h)
                z = low - ankle_h[r] * g + ankle
                rate = thigh[r] * np.sin(sw2) - shank[r] * np.sin(sw1)
                if middle[r, j] and z < clearance[r] and rate > 0.05:
                    need = (clearance[r] - z) / max(rate * window[r, j], 1e-6)
                else:
                    need = 0.0
                if np.isnan(need):
                    nan = True
                elif need > best:
                    best = need
            delta[r] = _clip(np.nan if nan else best, 0.0, max_rise)
            more |= delta[r] > 1e-6
        if not more:
            break
        for r in range(k):
            for j in range(half):
                step = delta[r] * window[r, j]
                out[r, half + j, 2] += step
                out[r, half + j, 1] -= step


def _blend_step(space: _ShapeSpace, simplex: np.ndarray, weights: np.ndarray,
                props: np.ndarray) -> np.ndarray:
    """Step (k, 2) [leg lengths] of the Eq. 9 blends of the given triangles (Eq. 10)."""
    blend = _blend(weights, space.keys, space.tri.simplices[simplex])  # rows t = 0.5, t = 0
    return step_of(blend[:, 0], blend[:, 1], _leg_of(props))


def _blend(weights: np.ndarray, table: np.ndarray, verts: np.ndarray) -> np.ndarray:
    """Eq. 9's blend (k, ...) of rows ``verts`` (k, v) of ``table`` (m, ...) by ``weights``
    (k, v): ``np.einsum("kv,kv...->k...", weights, table[verts])``'s values (summed from
    0 in vertex order), without the (k, v, ...) gather (:func:`_blend_kernel`)."""
    flat = table.reshape(table.shape[0], -1)
    out = np.empty((len(verts), flat.shape[1]))
    _blend_kernel(np.ascontiguousarray(weights, dtype=float), np.ascontiguousarray(flat),
                  np.ascontiguousarray(verts, dtype=np.int64), out)
    return out.reshape((len(verts), *table.shape[1:]))


@nb.njit(cache=True, nogil=True)
def _blend_kernel(weights, table, verts, out):
    """out[r] = 0 + Σ_v weights[r, v] · table[verts[r, v]], v in order (einsum's sum)."""
    for r in range(out.shape[0]):
        for i in range(out.shape[1]):
            out[r, i] = 0.0
        for v in range(verts.shape[1]):
            wv, row = weights[r, v], table[verts[r, v]]
            for i in range(out.shape[1]):
                out[r, i] += wv * row[i]


@nb.njit(cache=True, nogil=True)
def _row_step(keys, weights, props, out):
    """Step (2,) [leg lengths] of one Eq. 9 blend: :func:`step_of` for one request.

    ``keys`` (3, 2, 4) are the triangle's key rows (stance leg at t = 0.5, swing leg at
    t = 0), ``weights`` (3,) its barycentric weights, ``props`` (5,) the leg dimensions in
    ``LEG_FIELDS`` order (the ball is the roll point).
    """
    thigh, shank, ankle_h, heel, toe = props[0], props[1], props[2], props[3], props[4]
    st0 = st1 = st2 = sw0 = sw1 = sw2 = 0.0
    for v in range(3):
        st0 += weights[v] * keys[v, 0, 0]
        st1 += weights[v] * keys[v, 0, 1]
        st2 += weights[v] * keys[v, 0, 2]
        sw0 += weights[v] * keys[v, 1, 0]
        sw1 += weights[v] * keys[v, 1, 1]
        sw2 += weights[v] * keys[v, 1, 2]
    c, s = np.cos(st0), np.sin(st0)
    if st0 <= 0.0:  # on the ball
        ax, ay = toe - toe * c - ankle_h * s, -toe * s + ankle_h * c
    else:  # on the heel
        ax, ay = -heel + heel * c - ankle_h * s, heel * s + ankle_h * c
    hx = ax - shank * np.sin(st1) - thigh * np.sin(st2)
    hy = ay + shank * np.cos(st1) + thigh * np.cos(st2)
    kx = hx + thigh * np.sin(sw2) + shank * np.sin(sw1)
    ky = hy - thigh * np.cos(sw2) - shank * np.cos(sw1)
    c, s = np.cos(sw0), np.sin(sw0)
    if sw0 >= 0.0:  # lands on the heel
        out[0] = kx - heel * c + ankle_h * s + heel
        out[1] = ky - heel * s - ankle_h * c
    else:  # on the ball
        out[0] = kx + toe * c + ankle_h * s - toe
        out[1] = ky + toe * s - ankle_h * c


@nb.njit(cache=True, nogil=True)
def _gauss_newton(keys, props, w0, target, step0, err0, tol, iterations, margin, h=1e-6):
    """Gauss–Newton on two free barycentric weights (third = 1 − sum), per request.

    ``keys`` (m, 3, 2, 4) are each request's triangle key rows, ``props`` (m, 5) its leg
    dimensions, ``w0`` (m, 3) the start weights with steps ``step0`` (m, 2) and errors
    ``err0`` (m,) against ``target`` (m, 2), ``tol`` (m,) [leg lengths].
    Weights stay ≥ ``-margin`` (a step is shortened to the bound): the blend may leave the
    triangle a little but never becomes a wild extrapolation, which sliver triangles of
    near-collinear datasets would otherwise invite. A step that does not reduce the error
    is halved (up to four times); a request that cannot improve stops. Returns the best
    weights, their steps and errors.
    """
    w, step, err = w0.copy(), step0.copy(), err0.copy()
    trial, t_step, dw = np.empty(3), np.empty(2), np.empty(3)
    jac, full = np.empty((2, 2)), np.empty(3)
    for r in range(w.shape[0]):
        live = err[r] > tol[r]
        for _ in range(iterations):
            if not live:
                break
            for j in range(2):  # forward differences, the third weight compensating
                dw[:] = w[r]
                dw[j] += h
                dw[2] -= h
                _row_step(keys[r], dw, props[r], t_step)
                jac[0, j] = (t_step[0] - step[r, 0]) / h
                jac[1, j] = (t_step[1] - step[r, 1]) / h
            a = jac[0, 0] * jac[0, 0] + jac[1, 0] * jac[1, 0]
            b = jac[0, 0] * jac[0, 1] + jac[1, 0] * jac[1, 1]
            d = jac[0, 1] * jac[0, 1] + jac[1, 1] * jac[1, 1]
            damp = 1e-12 + 1e-9 * (a + d)
            a, d = a + damp, d + damp
            e0, e1 = step[r, 0] - target[r, 0], step[r, 1] - target[r, 1]
            g0 = jac[0, 0] * e0 + jac[1, 0] * e1
            g1 = jac[0, 1] * e0 + jac[1, 1] * e1
            det = a * d - b * b
            full[0] = -(d * g0 - b * g1) / det
            full[1] = -(a * g1 - b * g0) / det
            full[2] = -(full[0] + full[1])
            scale = 1.0
            for v in range(3):
                if full[v] < 0:
                    scale = min(scale, (w[r, v] + margin) / -full[v])
            scale = max(scale, 0.0)
            pending = True
            for _ in range(5):
                for v in range(3):
                    trial[v] = w[r, v] + scale * full[v]
                _row_step(keys[r], trial, props[r], t_step)
                t_err = np.hypot(t_step[0] - target[r, 0], t_step[1] - target[r, 1])
                if t_err < err[r]:
                    w[r], step[r], err[r] = trial, t_step, t_err
                    pending = False
                    break
                scale *= 0.5
            live = not pending and err[r] > tol[r]  # no progress: stalled
    return w, step, err
