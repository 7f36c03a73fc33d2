"""Each walker's step-length grid and what level ground costs on it (cached per leg).

The grid of a leg (§6.2) is ``intervals + 1`` step lengths from ``min_step_ratio`` to
``max_step_ratio`` leg lengths; under ``PlannerConfig.step_model = "normal_mode"`` it is
shifted (by under half an increment, in steps of 1/``GRID_SHIFTS``) so that the
normal-mode step for the walker's speed is a grid node, the neutral one. What does not
depend on the ground -- the neutral step, the joint energy and knee reach of level steps
of every grid length, and the §5.2 swing curves over level ground for every stride -- is
computed once per (leg, config, shift) and gathered for each batch
(:func:`leg_grids`).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, replace

import numba as nb
import numpy as np

from planners.config import PlannerConfig
from planners.energy import normal_step, step_energy
from planners.profile import RASTER_CELL
from planners.swing import TABLE_LEVELS, adjust_one, bernstein

__all__ = ["GRID_SHIFTS", "SLOPE_EXTRA", "LegArrays", "LegGrids", "grid", "leg_grids",
           "swing_basis"]

#: Grid shifts are multiples of 1/GRID_SHIFTS increment (so the per-leg caches stay small).
GRID_SHIFTS = 16
#: Extra clearance of the reusable curves for straight sloped spans [m].
SLOPE_EXTRA = 0.03
#: Most cached (leg, shift) entries per configuration before the cache starts afresh.
CACHE_ENTRIES = 4096


class LegArrays:
    """Legs as column arrays (A, 1) that broadcast against (A, N) step arrays."""

    names = ("thigh", "shank", "foot_length", "heel_offset", "toe_offset", "ankle_height")

    def __init__(self, legs):
        for name in self.names:
            setattr(self, name, np.array([getattr(leg, name) for leg in legs])[:, None])
        self.length = self.thigh + self.shank

    def take(self, rows: np.ndarray) -> LegArrays:
        """Per-row legs (C,) for the agents ``rows`` (C,)."""
        new = object.__new__(LegArrays)
        for name, value in vars(self).items():
            setattr(new, name, value[:, 0][rows])
        return new

    def table(self) -> np.ndarray:
        """The legs as one array (A, 6): :attr:`names` in order [m]."""
        return np.concatenate([getattr(self, name) for name in self.names], axis=1)


def grid(legs, config: PlannerConfig, shift=0.0) -> tuple[np.ndarray, np.ndarray]:
    """Shortest step and increment (A,) [m] of each leg's step-length grid, shifted by
    ``shift`` (A,) increments."""
    length = np.array([leg.length for leg in legs])
    lo = config.min_step_ratio * length
    delta = (config.max_step_ratio * length - lo) / config.intervals
    return lo + np.asarray(shift, dtype=float) * delta, delta


@dataclass(frozen=True, eq=False)
class LegGrids:
    """Each agent's grid and level-ground caches (A agents, J step lengths, S = 2J - 1
    strides).

    Attributes
    ----------
    lo, delta : ndarray, shape (A,)
        Shortest grid step and grid increment [m].
    neutral : ndarray of int, shape (A,)
        Index of the neutral step (s_init of §4.2).
    normal : ndarray, shape (A,)
        Normal-mode step at the agent's speed [m]; 0 under ``step_model = "paper"``.
    per_metre : ndarray, shape (A,)
        Energy per metre of neutral steps on level ground at the agent's speed
        [J/(kg m)].
    flat_Ej : ndarray, shape (A, J)
        Ej of level steps of every grid length [J/kg].
    flat_reach : ndarray of bool, shape (A, J)
        Their key frames are reachable.
    flat_ctrl : ndarray, shape (A, 2, S, 4, 2)
        Swing curves over level ground for every stride ``2 lo + s delta``, relative to
        the lift-off foothold [m], adjusted for the clearance (index 0) and for
        ``SLOPE_EXTRA`` more (index 1).
    flat_ok : ndarray of bool, shape (A, 2, S)
    flat_slack : ndarray, shape (A, 2, S)
        How much more than ``clearance`` the sole keeps away from the footholds' zones
        [m].
    legs : ndarray, shape (A, 6)
        The legs (:meth:`LegArrays.table`) [m].
    """

    lo: np.ndarray
    delta: np.ndarray
    neutral: np.ndarray
    normal: np.ndarray
    per_metre: np.ndarray
    flat_Ej: np.ndarray
    flat_reach: np.ndarray
    flat_ctrl: np.ndarray
    flat_ok: np.ndarray
    flat_slack: np.ndarray
    legs: np.ndarray


class _Cache:
    """Entries of one configuration: rows of growing arrays, found by (leg, shift, k)."""

    def __init__(self, config: PlannerConfig):
        J = config.intervals + 1
        S = 2 * J - 1
        self.rows: dict = {}
        self.shapes = {"lo": (), "delta": (), "neutral": (), "rest": (), "flat_Ej": (J,),
                       "flat_reach": (J,), "flat_ctrl": (2, S, 4, 2), "flat_ok": (2, S),
                       "flat_slack": (2, S)}
        self.types = {"neutral": np.int64, "flat_reach": np.bool_, "flat_ok": np.bool_}
        self.arrays = {k: np.empty((0, *s), dtype=self.types.get(k, float))
                       for k, s in self.shapes.items()}
        #: the LegGrids of single walkers, by (leg, speed): a single plan's grids are
        #: gathered once (callers only read a LegGrids)
        self.singles: dict = {}

    def add(self, keys: list, values: dict) -> None:
        if len(self.rows) + len(keys) > CACHE_ENTRIES:
            self.rows.clear()
            self.arrays = {k: v[:0] for k, v in self.arrays.items()}
        start = len(self.rows)
        for i, key in enumerate(keys):
            self.rows[key] = start + i
        for k in self.arrays:
            self.arrays[k] = np.concatenate([self.arrays[k], values[k]])


_CACHES: dict[PlannerConfig, _Cache] = {}
_LAST: list = [None, None]  # the last configuration and its cache (hashing one is slow)
#: Held while the caches are read or grown (the chunks of a batch run on several threads,
#: :func:`planners.lattice.run_tasks`; a cache's rows and arrays change together).
_LOCK = threading.RLock()


def leg_grids(legs, speeds: np.ndarray, config: PlannerConfig) -> LegGrids:
    """The grids and level-ground caches of ``legs`` (A,) walking at ``speeds`` (A,)
    [m/s] (entries missing from the cache are computed together; a single walker's
    result is kept whole, per leg and speed: read it, do not write to it)."""
    speeds = np.asarray(speeds, dtype=float)
    with _LOCK:
        last_config, cache = _LAST
        if last_config is not config:
            cache = _CACHES.get(config)
            if cache is None:
                cache = _CACHES.setdefault(config, _Cache(config))
            _LAST[:] = config, cache
        if len(legs) == 1:
            key = legs[0], float(speeds[0])
            got = cache.singles.get(key)
            if got is None:
                if len(cache.singles) >= CACHE_ENTRIES:
                    cache.singles.clear()
                got = cache.singles[key] = _gathered(legs, speeds, config, cache)
            return got
        return _gathered(legs, speeds, config, cache)


def _gathered(legs, speeds: np.ndarray, config: PlannerConfig, cache: _Cache) -> LegGrids:
    """:func:`leg_grids` from the per-(leg, shift) entries of ``cache``."""
    legs_col = LegArrays(legs)
    normal_mode = config.step_model == "normal_mode"
    if normal_mode:  # each grid anchored on the normal-mode step (to 1/32 increment)
        lo, delta = grid(legs, config)
        normal = normal_step(legs_col, speeds[:, None])[:, 0]
        u = (normal - lo) / delta
        k = np.clip(np.floor(u + 0.5), 0, config.intervals).astype(int)
        shift = np.round(np.clip(u - k, -0.5, 0.5) * GRID_SHIFTS) / GRID_SHIFTS
        keys = list(zip(legs, shift.tolist(), k.tolist(), strict=True))
    else:
        normal = np.zeros(len(legs))
        keys = [(leg, 0.0, -1) for leg in legs]
    missing = list(dict.fromkeys(key for key in keys if key not in cache.rows))
    if missing:
        cache.add(missing, _entries(missing, config))
    rows = np.array([cache.rows[key] for key in keys])
    got = {k: v[rows] for k, v in cache.arrays.items()}
    # En per metre is (32 + 0.005 v^2) / v [cal/(kg m)]; the rest does not depend on v.
    v = 60.0 * speeds
    w = config.weights
    walking = w.alpha * (32.0 + 0.005 * v**2) / v
    if normal_mode:
        L = got["lo"] + got["delta"] * got["neutral"]
        walking = walking * (1.0 + w.frequency * (normal / L - 1.0) ** 2)
    return LegGrids(got["lo"], got["delta"], got["neutral"], normal, walking + got["rest"],
                    got["flat_Ej"], got["flat_reach"], got["flat_ctrl"], got["flat_ok"],
                    got["flat_slack"], legs_col.table())


def _entries(keys: list, config: PlannerConfig) -> dict:
    """Cache entries of (leg, shift, k) keys (k = -1: the most efficient level step is
    the neutral one)."""
    legs = [key[0] for key in keys]
    lo, delta = grid(legs, config, [key[1] for key in keys])
    J = config.intervals + 1
    L = lo[:, None] + delta[:, None] * np.arange(J)
    leg = LegArrays(legs)
    zero = np.zeros_like(L)
    summit = leg.ankle_height + 0.75 * config.swing_lift + zero
    # Eqs. 1-4 alone: the speed-dependent frequency term is added per speed
    paper = replace(config, step_model="paper")
    En, _, Ej, E, reachable = step_energy(zero, zero, L, zero, summit, leg, 1.0, paper)
    anchored = np.array([key[2] for key in keys])
    best = np.where(anchored >= 0, anchored, np.argmax(L / E, axis=1))
    rows = np.arange(len(keys))
    rest = (E - config.weights.alpha * En)[rows, best] / L[rows, best]  # [J/(kg m)]
    S = 2 * J - 1
    strides = 2 * lo[:, None] + delta[:, None] * np.arange(S)
    # per clearance contiguous (one compiled signature, whatever the number of legs)
    ctrl = np.empty((2, len(keys), S, 4, 2))
    ok = np.empty((2, len(keys), S), dtype=np.bool_)
    slack = np.empty((2, len(keys), S))
    basis, influence = swing_basis(config.bezier_samples)
    for extra_i, extra in enumerate((0.0, SLOPE_EXTRA)):
        _flat_curves(strides, leg.table(), RASTER_CELL, TABLE_LEVELS, basis, influence,
                     config.clearance + extra, config.clearance, config.swing_lift,
                     config.max_swing_lift, config.max_foot_slope, config.max_adjustments,
                     ctrl[extra_i], ok[extra_i], slack[extra_i])
    return {"lo": lo, "delta": delta, "neutral": best.astype(np.int64), "rest": rest,
            "flat_Ej": Ej, "flat_reach": reachable, "flat_ctrl": ctrl.swapaxes(0, 1),
            "flat_ok": ok.swapaxes(0, 1), "flat_slack": slack.swapaxes(0, 1)}


_SWING_BASES: dict = {}


def swing_basis(samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Bernstein basis (4, T) at the swing samples and the control points' influence
    (2, T-1) at the segment midpoints (as :func:`~planners.swing.adjust_swings`)."""
    if samples not in _SWING_BASES:
        t = np.linspace(0.0, 1.0, samples)
        t_mid = 0.5 * (t[:-1] + t[1:])
        influence = np.stack([3 * t_mid * (1 - t_mid) ** 2, 3 * t_mid**2 * (1 - t_mid)])
        _SWING_BASES[samples] = np.ascontiguousarray(bernstein(t).T), influence
    return _SWING_BASES[samples]


@nb.njit(cache=True, nogil=True)
def _flat_curves(strides, legs, cell, levels, basis, influence, adjusted_clearance,
                 clearance, swing_lift, max_swing_lift, max_foot_slope, max_adjustments,
                 ctrl, ok, slack):
    """§5.2 curves over level ground from 0 to every stride (B, S) [m] of each leg
    (B, 6) (:class:`LegArrays` order), adjusted for ``adjusted_clearance`` [m]; fills
    ``ctrl`` (B, S, 4, 2), ``ok`` (B, S) and the sole's ``slack`` (B, S) [m] over
    ``clearance`` away from the footholds' zones."""
    T = basis.shape[1]
    scratch = np.empty((3, T))
    summit = np.empty(2)
    for b in range(strides.shape[0]):
        heel, toe, ankle, foot = legs[b, 3], legs[b, 4], legs[b, 5], legs[b, 2]
        margin = 2 * foot
        start = np.floor((0.0 - margin) / cell) * cell
        longest = 0.0
        for q in range(strides.shape[1]):
            longest = max(longest, strides[b, q])
        count = max(1, int(np.ceil((longest + margin - start) / cell)))
        width = 0
        while (1 << width) <= count and width < levels:
            width += 1
        table = np.zeros((width, count))  # level ground: every cell at height 0
        vertex_cum = np.zeros(count + 1, dtype=np.int64)  # no vertex near the curves
        zone = 0.5 * foot
        for q in range(strides.shape[1]):
            end = strides[b, q]
            ok[b, q], _ = adjust_one(0.0, 0.0, end, 0.0, heel, toe, ankle, foot, start, cell,
                                     table, vertex_cum, basis, influence, adjusted_clearance,
                                     swing_lift, max_swing_lift, max_foot_slope,
                                     max_adjustments, ctrl[b, q], summit, scratch)
            c = ctrl[b, q]
            worst = -np.inf
            prev_s, prev_z = 0.0, 0.0
            for i in range(T):
                ps = c[0, 0] * basis[0, i] + c[1, 0] * basis[1, i] + c[2, 0] * basis[2, i] \
                    + c[3, 0] * basis[3, i]
                pz = c[0, 1] * basis[0, i] + c[1, 1] * basis[1, i] + c[2, 1] * basis[2, i] \
                    + c[3, 1] * basis[3, i]
                if i > 0:
                    s_lo, s_hi = min(prev_s, ps), max(prev_s, ps)
                    if s_hi > zone and s_lo < end - zone:  # away from both footholds
                        worst = max(worst, clearance - (min(prev_z, pz) - ankle - 0.0))
                prev_s, prev_z = ps, pz
            slack[b, q] = -worst
