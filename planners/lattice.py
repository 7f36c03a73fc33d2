"""Precomputed step tables on the foothold lattice (one vectorised pass per batch).

After k steps of lengths ``L_min + j*dL`` (j = 0..J-1) every foothold lies on the lattice
``k*L_min + m*dL`` (m = 0..(J-1)k). Legality and energy of step k depend only on the
stance foothold f_{k-1} and the step's own length (a *step* entry), except the swing
curve, which depends on the lift-off foothold f_{k-2} and the touch-down foothold f_k
(a *swing* entry). Every node, step and swing of the horizon is evaluated once for all
agents together; the searches then only look tables up.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from functools import cached_property, lru_cache

import numpy as np

from planners.config import PlannerConfig
from planners.energy import (
    frequency_energy,
    normal_step,
    step_energy,
    terminal_energy,
    total_energy,
    vertical_energy,
    walking_energy,
)
from planners.leg import Leg
from planners.legality import Reason, foot_support, snap_to_support
from planners.profile import _VERTICAL, RASTER_CELL, GroundProfile
from planners.swing import adjust_swings, bezier_points, sole_clearance

__all__ = ["Structure", "StepTables", "TableWork", "structure", "build_tables",
           "combine_profiles", "grid", "neutral_index"]


#: Extra clearance of the reusable curves for straight sloped spans [m].
SLOPE_EXTRA = 0.03
#: Largest number of configurations J**n whose step and swing indices are tabulated.
LOOKUP_CONFIGS = 65536
#: Compute swing curves only for pairs a legal sequence of steps can use (False: for
#: every pair of supported footholds; the results are the same, only slower).
PRUNE_SWINGS = True


@dataclass(frozen=True, eq=False)
class Structure:
    """Index structure of the lattice for horizon ``n`` and ``J`` step lengths.

    Nodes: 0 is the trailing foot, 1 the stance foot, then depth k's footholds
    ``node_offset[k] + m``. Steps of depth k: ``step_offset[k-1] + m_{k-1}*J + j_k``.
    Swings of depth k: ``swing_offset[k-1] + m_{k-2}*S_k + stride`` where the stride index
    is ``j_{k-1} + j_k`` (``j_1`` at depth 1) and ``S_1 = J``, ``S_k = 2J - 1``.
    """

    n: int
    J: int
    node_depth: np.ndarray  # (Nn,) -1 trailing, 0 stance, 1..n
    node_m: np.ndarray  # (Nn,)
    node_offset: tuple[int, ...]  # by depth 0..n
    step_depth: np.ndarray  # (Ns,)
    step_stance: np.ndarray  # (Ns,) node index
    step_front: np.ndarray  # (Ns,) node index
    step_j: np.ndarray  # (Ns,)
    step_offset: tuple[int, ...]
    swing_back: np.ndarray  # (Np,) node index
    swing_front: np.ndarray  # (Np,) node index
    swing_offset: tuple[int, ...]
    swing_strides: tuple[int, ...]
    swing_stride: np.ndarray  # (Np,) stride index j_{k-1} + j_k; -1 at depth 1

    def indices(self, configs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Step and swing indices (..., n) of configurations (..., n) of j's (each in
        0..J-1); looked up in a table of every configuration when there are at most
        ``LOOKUP_CONFIGS`` of them."""
        configs = np.asarray(configs, dtype=np.int64)
        table = self._lookup
        if table is None:
            return self._indices(configs)
        code = configs @ self._codes  # the configuration's row in all_configs
        return table[0][code], table[1][code]

    @cached_property
    def _codes(self) -> np.ndarray:
        return self.J ** np.arange(self.n - 1, -1, -1, dtype=np.int64)

    @cached_property
    def _lookup(self) -> tuple[np.ndarray, np.ndarray] | None:
        if self.J**self.n > LOOKUP_CONFIGS:
            return None
        return self._indices(self.all_configs.astype(np.int64))

    def _indices(self, configs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lead = configs.shape[:-1]
        zero = np.zeros(lead + (1,), dtype=np.int64)
        total = np.cumsum(configs, axis=-1)
        m_prev = np.concatenate([zero, total[..., :-1]], axis=-1)  # m_{k-1}
        m_prev2 = np.concatenate([zero, zero, total[..., :-2]], axis=-1)[..., :self.n]
        stride = configs + np.concatenate([zero, configs[..., :-1]], axis=-1)
        steps = self._step_offsets + m_prev * self.J + configs
        swings = self._swing_offsets + m_prev2 * self._swing_strides + stride
        return steps, swings

    @cached_property
    def _step_offsets(self) -> np.ndarray:
        return np.array(self.step_offset, dtype=np.int64)

    @cached_property
    def _swing_offsets(self) -> np.ndarray:
        return np.array(self.swing_offset, dtype=np.int64)

    @cached_property
    def _swing_strides(self) -> np.ndarray:
        return np.array(self.swing_strides, dtype=np.int64)

    @cached_property
    def pair_steps(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per swing pair and middle step length j_{k-1}: the two step indices (Np, J)
        (lift-off -> stance, stance -> touch-down) and whether they exist. Depth 1 pairs
        have one step (the second), the first is a copy of it."""
        J = self.J
        first = np.zeros((self.swing_back.size, J), dtype=np.int64)
        second = np.zeros_like(first)
        valid = np.zeros(first.shape, dtype=bool)
        depth = self.node_depth[self.swing_front]
        jp = np.arange(J)[None, :]
        for k in range(1, self.n + 1):
            rows = np.flatnonzero(depth == k)
            if k == 1:
                j = self.node_m[self.swing_front[rows]]
                second[rows] = (self.step_offset[0] + j)[:, None]
                first[rows] = second[rows]
                valid[rows, 0] = True
                continue
            m2 = self.node_m[self.swing_back[rows]][:, None]
            stride = self.swing_stride[rows][:, None]
            jc = stride - jp
            ok = (jc >= 0) & (jc < J)
            first_k = (self.step_offset[k - 2] + (m2 if k > 2 else 0) * J + jp)
            second[rows] = self.step_offset[k - 1] + (m2 + jp) * J + np.clip(jc, 0, J - 1)
            first[rows] = np.broadcast_to(first_k, ok.shape)
            valid[rows] = ok
        return first, second, valid

    @cached_property
    def all_configs(self) -> np.ndarray:
        """Every configuration (J**n, n) of step-length indices."""
        grids = np.indices((self.J,) * self.n, dtype=np.int16)
        return grids.reshape(self.n, -1).T

    @cached_property
    def all_indices(self) -> tuple[np.ndarray, np.ndarray]:
        """Step and swing indices (J**n, n) of every configuration."""
        steps, swings = self._indices(self.all_configs.astype(np.int64))
        return steps.astype(np.int32), swings.astype(np.int32)


@lru_cache(maxsize=16)
def structure(n: int, J: int) -> Structure:
    """The (cached) lattice structure for horizon ``n`` and ``J`` step lengths."""
    node_depth, node_m, node_offset = [-1, 0], [0, 0], [1]
    for k in range(1, n + 1):
        node_offset.append(len(node_depth))
        count = (J - 1) * k + 1
        node_depth += [k] * count
        node_m += list(range(count))

    def node(k, m):
        return node_offset[k] + m

    step_depth, step_stance, step_front, step_j, step_offset = [], [], [], [], []
    swing_back, swing_front, swing_offset, swing_strides = [], [], [], []
    swing_stride = []
    for k in range(1, n + 1):
        step_offset.append(len(step_depth))
        m_prev = np.repeat(np.arange((J - 1) * (k - 1) + 1), J)
        j = np.tile(np.arange(J), m_prev.size // J)
        step_depth += [k] * j.size
        step_stance += list(node(k - 1, m_prev))
        step_front += list(node(k, m_prev + j))
        step_j += list(j)
        swing_offset.append(len(swing_back))
        if k == 1:
            swing_strides.append(J)
            swing_back += [0] * J
            swing_front += list(node(1, np.arange(J)))
            swing_stride += [-1] * J
        else:
            S = 2 * J - 1
            swing_strides.append(S)
            m2 = np.repeat(np.arange((J - 1) * (k - 2) + 1), S)
            stride = np.tile(np.arange(S), m2.size // S)
            swing_back += list(node(k - 2, m2))
            swing_front += list(node(k, m2 + stride))
            swing_stride += list(stride)
    a = np.asarray
    return Structure(n, J, a(node_depth), a(node_m), tuple(node_offset), a(step_depth),
                     a(step_stance), a(step_front), a(step_j), tuple(step_offset),
                     a(swing_back), a(swing_front), tuple(swing_offset), tuple(swing_strides),
                     a(swing_stride))


def combine_profiles(profiles, lo: np.ndarray, hi: np.ndarray, origins: np.ndarray,
                     cell: float):
    """One profile holding every agent's profile side by side.

    Agent a's profile, cropped (or padded flat) to ``[lo[a] - 1, hi[a] + 1]`` [m], is
    shifted by ``offset[a]`` so that queries of different agents never meet and every
    stance foot ``origins[a] + offset[a]`` lies on a multiple of ``cell`` [m] (rasters
    then align with each agent's origin, whatever the batch or a translation). Returns the
    combined :class:`GroundProfile` and the offsets (A,) [m].
    """
    if len(profiles) == 1:
        offset = np.floor(origins[0] / cell) * cell - origins[0]
        p = profiles[0]
        return (p if offset == 0 else GroundProfile(p.s + offset, p.z)), np.array([offset])
    start, end = lo - 1.0, hi + 1.0  # (A,): cropped to the part that can be queried
    offsets = np.empty(len(profiles))
    cursor = 0.0
    for a in range(offsets.size):  # each agent's offset follows the previous one's end
        offsets[a] = np.ceil((cursor - start[a] + origins[a]) / cell) * cell - origins[a]
        cursor = end[a] + offsets[a] + 1.0
    sizes = np.array([p.s.size for p in profiles])
    bounds = np.concatenate([[0], np.cumsum(sizes)])
    agent = np.repeat(np.arange(sizes.size), sizes)
    s, z = np.concatenate([p.s for p in profiles]), np.concatenate([p.z for p in profiles])
    # every profile's own slopes (GroundProfile._slopes, side by side)
    ds, dz = np.diff(s), np.diff(z)
    slope = np.zeros(s.size)
    np.divide(dz, ds, out=slope[:-1], where=(ds > _VERTICAL) & (agent[1:] == agent[:-1]))

    def heights(q):  # GroundProfile.height of each agent's own profile at q (A,)
        q = np.maximum(q, s[bounds[:-1]])
        at_or_below = np.add.reduceat((s <= q[agent]).astype(np.intp), bounds[:-1])
        i = bounds[:-1] + at_or_below - 1
        return z[i] + slope[i] * (q - s[i])

    inside = np.flatnonzero((s > start[agent]) & (s < end[agent]))
    rows = np.concatenate([np.arange(sizes.size), agent[inside], np.arange(sizes.size)])
    rank = np.concatenate([np.full(sizes.size, -1), inside, np.full(sizes.size, s.size)])
    order = np.lexsort((rank, rows))  # per agent: start, the vertices inside, end
    out_s = np.concatenate([start, s[inside], end]) + offsets[rows]
    out_z = np.concatenate([heights(start), z[inside], heights(end)])
    return GroundProfile(out_s[order], out_z[order]), offsets


class _LegArrays:
    """Legs as column arrays (A, 1) that broadcast against (A, N) step arrays."""

    names = ("thigh", "shank", "foot_length", "heel_offset", "toe_offset", "ankle_height")

    def __init__(self, legs):
        for name in self.names:
            setattr(self, name, np.array([getattr(leg, name) for leg in legs])[:, None])
        self.length = self.thigh + self.shank

    def take(self, rows: np.ndarray) -> _LegArrays:
        """Per-row legs (C,) for the agents ``rows`` (C,)."""
        new = object.__new__(_LegArrays)
        for name, value in vars(self).items():
            setattr(new, name, value[:, 0][rows])
        return new


@dataclass(frozen=True, eq=False)
class TableWork:
    """What building the tables did, per agent (A,) each, counted where it was done.

    Attributes
    ----------
    steps : ndarray of int
        Lattice steps whose legality and energy were evaluated.
    key_frames : ndarray of int
        Steps whose key frames were solved by inverse kinematics (the others are level
        steps on level ground, looked up in the per-leg cache).
    swing_curves : ndarray of int
        Swing curves built and checked by the §5.2 adjustment.
    swing_curves_reused : ndarray of int
        Swing curves taken from the per-leg flat-ground cache (sheared to a slope) and
        checked against the slack the cache recorded.
    swing_adjustments : ndarray of int
        §5.2 adjustment rounds of the curves built.
    """

    steps: np.ndarray
    key_frames: np.ndarray
    swing_curves: np.ndarray
    swing_curves_reused: np.ndarray
    swing_adjustments: np.ndarray


@dataclass(frozen=True, eq=False)
class StepTables:
    """Per-agent tables (A agents, Nn nodes, Ns steps, Np swings).

    Attributes
    ----------
    struct : Structure
    step_min, step_delta : ndarray, shape (A,)
        Shortest grid step and grid increment [m].
    neutral : ndarray of int, shape (A,)
        Index of the neutral step length (best flat-ground efficiency, s_init of §4.2).
    neutral_cost : ndarray, shape (A,)
        Energy per metre of neutral steps on flat ground [J/(kg m)].
    node_s, node_z : ndarray, shape (A, Nn)
        Foothold arc lengths relative to the stance foot and ground heights [m].
    length, rise : ndarray, shape (A, Ns)
        Step length and height change [m].
    En, Ev, Ej, E : ndarray, shape (A, Ns)
        Energy terms (Eq. 1 cal/kg, Eq. 2 unit, Eq. 3 J/kg) and the total E [J/kg].
    step_reason : ndarray of int, shape (A, Ns)
        :class:`~planners.legality.Reason` flags; 0 is legal.
    swing_ok : ndarray of bool, shape (A, Np)
    controls : ndarray, shape (A, Np, 4, 2)
        Swing-ankle Bezier control points (s relative to the stance foot, z) [m].
    rounds : ndarray of int, shape (A, Np)
        §5.2 adjustment rounds (-1 where no curve was computed).
    cost, progress : ndarray, shape (A, Ns)
        What the searches score (efficiency = sum of progress / sum of cost): ``E`` and
        ``length``, except that with ``config.terminal_cost`` a last step (depth n) also
        costs the terminal energy of its landing node and progresses to ``reach``, so
        that every configuration is scored for the same progress [J/kg], [m].
    terminal : ndarray, shape (A, Nn)
        Estimated energy from a node to ``reach`` (:func:`planners.energy.terminal_energy`;
        0 where unused) [J/kg].
    reach : ndarray, shape (A,)
        Farthest last foothold of the lattice, relative to the stance foot [m].
    work : TableWork
        What building the tables did, per agent.
    """

    struct: Structure
    step_min: np.ndarray
    step_delta: np.ndarray
    neutral: np.ndarray
    neutral_cost: np.ndarray
    node_s: np.ndarray
    node_z: np.ndarray
    length: np.ndarray
    rise: np.ndarray
    En: np.ndarray
    Ev: np.ndarray
    Ej: np.ndarray
    E: np.ndarray
    step_reason: np.ndarray
    swing_ok: np.ndarray
    controls: np.ndarray
    rounds: np.ndarray
    config: PlannerConfig
    cost: np.ndarray
    progress: np.ndarray
    terminal: np.ndarray
    reach: np.ndarray
    work: TableWork

    @cached_property
    def step_legal(self) -> np.ndarray:
        """Legal steps (A, Ns), bool."""
        return self.step_reason == 0

    def evaluate(self, agents: np.ndarray, configs: np.ndarray):
        """Legality and efficiency of configurations.

        Parameters
        ----------
        agents : ndarray of int, shape (B,)
        configs : ndarray of int, shape (B, ..., n)

        Returns
        -------
        legal : ndarray of bool, shape (B, ...)
        efficiency : ndarray, shape (B, ...)
            Sum of ``progress`` over sum of ``cost`` [m kg/J] (Eq. 5 over the steps, for
            the same progress with ``terminal_cost``).
        """
        steps, swings = self.struct.indices(configs)
        rows = agents.reshape((-1,) + (1,) * (configs.ndim - 1))
        # gathers through flat indices (faster than indexing with broadcast row arrays)
        at_step = rows * self.E.shape[1] + steps
        at_swing = rows * self.swing_ok.shape[1] + swings
        legal = (self.step_legal.ravel().take(at_step).all(axis=-1)
                 & self.swing_ok.ravel().take(at_swing).all(axis=-1))
        energy = self.cost.ravel().take(at_step).sum(axis=-1)
        length = self.progress.ravel().take(at_step).sum(axis=-1)
        # Rounded to 1e-12 so that ties (mirror-image plans on level ground) are broken
        # the same way whatever the profile's offsets.
        return legal, np.round(length / energy, 12)


_FLAT_CACHE: dict = {}


def flat_swings(legs, config: PlannerConfig, extra: float = 0.0):
    """Swing curves over flat ground for every stride ``2 L_min + s dL`` (s = 0..2J-2).

    Returns control points (A, 2J-1, 4, 2) relative to the lift-off foothold [m], ok
    flags (A, 2J-1) and the sole's clearance slack (A, 2J-1) [m] (how much more than
    the required clearance the curve keeps away from the footholds' zones). Curves are
    computed once per distinct (leg, config, extra), all missing legs in one vectorised
    call. ``extra`` [m] is added to the clearance the curves are adjusted for, so that
    their slack covers sloped ground; the slack is reported against the real clearance.
    """
    S = 2 * config.intervals + 1
    key = (config, extra)
    missing = list({leg: None for leg in legs if (leg, key) not in _FLAT_CACHE})
    if missing:
        lo, delta = grid(missing, config)
        strides = (2 * lo[:, None] + delta[:, None] * np.arange(S)).ravel()
        span = float(strides.max()) + 2 * max(leg.foot_length for leg in missing)
        flat = GroundProfile.flat(2 * span, 0.0, -span / 2)
        zero = np.zeros_like(strides)
        feet = _LegArrays(missing).take(np.repeat(np.arange(len(missing)), S))
        lifted = replace(config, clearance=config.clearance + extra)
        swing = adjust_swings(zero, zero, strides, zero, flat, feet, lifted)
        pts = bezier_points(swing.controls, config.bezier_samples)
        deficit = sole_clearance(pts, zero, strides, flat, feet, config)
        zone = 0.5 * feet.foot_length[:, None]
        s_lo = np.minimum(pts[:, :-1, 0], pts[:, 1:, 0])
        s_hi = np.maximum(pts[:, :-1, 0], pts[:, 1:, 0])
        away = (s_hi > zone) & (s_lo < strides[:, None] - zone)
        slack = -np.max(np.where(away, deficit, -np.inf), axis=1)
        if len(_FLAT_CACHE) > 4096:
            _FLAT_CACHE.clear()
        for i, leg in enumerate(missing):
            rows = slice(i * S, (i + 1) * S)
            _FLAT_CACHE[(leg, key)] = (swing.controls[rows], swing.ok[rows], slack[rows])
    entries = [_FLAT_CACHE[(leg, key)] for leg in legs]
    return tuple(np.stack([e[i] for e in entries]) for i in range(3))


def grid(legs, config: PlannerConfig) -> tuple[np.ndarray, np.ndarray]:
    """Shortest step and increment (A,) [m] of each leg's step-length grid (shifted by
    ``grid_shift`` increments for an :class:`AnchoredLeg`)."""
    length = np.array([leg.length for leg in legs])
    lo = config.min_step_ratio * length
    delta = (config.max_step_ratio * length - lo) / config.intervals
    shift = np.array([getattr(leg, "grid_shift", 0.0) for leg in legs])
    return lo + shift * delta, delta


#: Grid shifts are multiples of 1/GRID_SHIFTS increment (so the per-leg caches stay small).
GRID_SHIFTS = 16


@dataclass(frozen=True)
class AnchoredLeg(Leg):
    """A leg whose step-length grid is anchored on its normal-mode step for one speed
    (``PlannerConfig.step_model = "normal_mode"``): the grid is shifted by ``grid_shift``
    increments (|shift| <= 1/2) so that grid node ``neutral`` is that step."""

    grid_shift: float = 0.0
    neutral: int = 0


def anchored_legs(legs, speeds: np.ndarray, config: PlannerConfig) -> list[AnchoredLeg]:
    """Each leg anchored on its normal-mode step at its speed [m/s] (to 1/32 increment)."""
    lo, delta = grid(legs, config)
    u = (normal_step(_LegArrays(legs), np.asarray(speeds, float)[:, None])[:, 0] - lo) / delta
    k = np.clip(np.floor(u + 0.5), 0, config.intervals).astype(int)
    shift = np.round(np.clip(u - k, -0.5, 0.5) * GRID_SHIFTS) / GRID_SHIFTS
    names = [f.name for f in fields(Leg)]
    return [AnchoredLeg(**{n: getattr(leg, n) for n in names}, grid_shift=float(q),
                        neutral=int(j)) for leg, q, j in zip(legs, shift, k, strict=True)]


_NEUTRAL_CACHE: dict = {}


def neutral_index(legs, config: PlannerConfig) -> np.ndarray:
    """Grid index (A,) of the most efficient step on flat ground (s_init of §4.2).

    With En proportional to the step length at a given speed (Eq. 1 with cadence
    v / L), the best flat step minimises Ej / L and does not depend on the speed; it is
    cached per (leg, config).
    """
    _neutral(legs, config)
    return np.array([_NEUTRAL_CACHE[(leg, config)][0] for leg in legs])


def neutral_energy_per_metre(legs, speeds: np.ndarray, config: PlannerConfig) -> np.ndarray:
    """Energy per metre (A,) [J/(kg m)] of neutral steps on flat ground at ``speeds``."""
    _neutral(legs, config)
    entries = [_NEUTRAL_CACHE[(leg, config)] for leg in legs]
    v = 60.0 * np.asarray(speeds, dtype=float)
    # En per metre is (32 + 0.005 v^2) / v [cal/(kg m)]; the rest does not depend on v.
    w = config.weights
    walking = w.alpha * (32.0 + 0.005 * v**2) / v
    if config.step_model == "normal_mode":
        lo, delta = grid(legs, config)
        L = lo + delta * np.array([e[0] for e in entries])
        normal = normal_step(_LegArrays(legs), np.asarray(speeds, float)[:, None])[:, 0]
        walking = walking * (1.0 + w.frequency * (normal / L - 1.0) ** 2)
    return walking + np.array([e[1] for e in entries])


def _neutral(legs, config: PlannerConfig) -> None:
    missing = list({leg: None for leg in legs if (leg, config) not in _NEUTRAL_CACHE})
    if not missing:
        return
    lo, delta = grid(missing, config)
    L = lo[:, None] + delta[:, None] * np.arange(config.intervals + 1)
    leg = _LegArrays(missing)
    zero = np.zeros_like(L)
    summit = leg.ankle_height + 0.75 * config.swing_lift + zero
    # Eqs. 1-4 alone: the speed-dependent frequency term is added per speed by the callers
    paper = replace(config, step_model="paper")
    En, _, Ej, E, reachable = step_energy(zero, zero, L, zero, summit, leg, 1.0, paper)
    if len(_NEUTRAL_CACHE) > 4096:
        _NEUTRAL_CACHE.clear()
    best = np.argmax(L / E, axis=1)
    anchored = np.array([isinstance(m, AnchoredLeg) for m in missing])
    if anchored.any():
        best = np.where(anchored, [getattr(m, "neutral", 0) for m in missing], best)
    rows = np.arange(len(missing))
    rest = (E - config.weights.alpha * En)[rows, best] / L[rows, best]  # [J/(kg m)]
    for i, leg_i in enumerate(missing):
        _NEUTRAL_CACHE[(leg_i, config)] = (int(best[i]), float(rest[i]), Ej[i], reachable[i])


def flat_joint_energy(legs, config: PlannerConfig) -> tuple[np.ndarray, np.ndarray]:
    """Ej [J/kg] and knee reach of level steps of every grid length, (A, J) each (cached)."""
    _neutral(legs, config)
    entries = [_NEUTRAL_CACHE[(leg, config)] for leg in legs]
    return np.stack([e[2] for e in entries]), np.stack([e[3] for e in entries])


def build_tables(profiles, legs, speeds: np.ndarray, trailing: np.ndarray | None,
                 origins: np.ndarray, config: PlannerConfig) -> StepTables:
    """Evaluate legality and energy of every node, step and swing for every agent.

    Parameters
    ----------
    profiles : list of GroundProfile, length A
    legs : list of Leg, length A
    speeds : ndarray, shape (A,)
        Target walking speeds [m/s].
    trailing : ndarray, shape (A,) or None
        Arc length of the trailing foot (the next swing foot) relative to the stance
        foot [m], < 0; None puts it one neutral step behind.
    origins : ndarray, shape (A,)
        Arc length of the stance foot on each profile [m].
    config : PlannerConfig

    Notes
    -----
    The swing ankle at key frame K1 is lifted ``0.75 * swing_lift`` above the highest
    ground between the stance and the landing foothold (the summit of the initial §5.2
    curve), so stepping over a higher obstacle costs more joint rotation.
    """
    A = len(profiles)
    st = structure(config.n_steps, config.intervals + 1)
    if config.step_model == "normal_mode":
        legs = anchored_legs(legs, speeds, config)
    lo, delta = grid(legs, config)
    neutral = neutral_index(legs, config)
    if trailing is None:
        trailing = -(lo + delta * neutral)
    reach = config.n_steps * (lo + delta * config.intervals)
    profile, shift = combine_profiles(profiles, origins + trailing - 1.0, origins + reach + 1.0,
                                      origins, RASTER_CELL)
    base = (origins + shift)[:, None]  # (A, 1) absolute s of each stance foot
    legs_col = _LegArrays(legs)

    # Nodes: footholds relative to the stance foot, their heights and support.
    depth = st.node_depth[None, :]
    node_s = np.where(depth == -1, trailing[:, None],
                      np.maximum(depth, 0) * lo[:, None] + st.node_m * delta[:, None])
    if config.snap:
        moved = snap_to_support(base + node_s[:, 2:], 0.5 * delta[:, None], profile,
                                legs_col.heel_offset, legs_col.toe_offset, config) - base
        node_s = np.concatenate([node_s[:, :2], moved], axis=1)
    node_z = profile.height(base + node_s)
    support = foot_support(base + node_s, profile, legs_col.heel_offset, legs_col.toe_offset,
                           config)
    support[:, :2] = 0  # the feet already standing are where they are

    # Steps: stance node -> front node.
    stance_s, front_s = node_s[:, st.step_stance], node_s[:, st.step_front]
    stance_z, front_z = node_z[:, st.step_stance], node_z[:, st.step_front]
    rise = front_z - stance_z
    highest = profile.max_height(base + stance_s, base + front_s)
    # Key frames of level steps on level ground depend only on the length: cached.
    length = front_s - stance_s
    nominal = lo[:, None] + delta[:, None] * st.step_j
    level = (rise == 0) & (highest == stance_z) & (np.abs(length - nominal) <= 1e-12)
    flat_Ej, flat_reach = flat_joint_energy(legs, config)
    Ej = np.take_along_axis(flat_Ej, np.broadcast_to(st.step_j, rise.shape), axis=1)
    reachable = np.take_along_axis(flat_reach, np.broadcast_to(st.step_j, rise.shape), axis=1)
    # Key frames are solved for the non-level steps that can be legal: a landing across
    # an edge or a rise beyond the limit is illegal whatever the knee does, and its
    # energy is never used (it is set to +inf below).
    hopeless = (support[:, st.step_front] != 0) | (np.abs(rise) > config.max_step_rise)
    other = np.nonzero(~level & ~hopeless)
    key_frames = np.bincount(other[0], minlength=A)
    if other[0].size:
        sub = legs_col.take(other[0])
        summit_z = highest[other] + sub.ankle_height + 0.75 * config.swing_lift
        _, _, Ej[other], _, reachable[other] = step_energy(
            stance_s[other], stance_z[other], front_s[other], front_z[other], summit_z, sub,
            speeds[other[0]], config)
    w = config.weights
    En = walking_energy(length, speeds[:, None])
    Ev = vertical_energy(rise, w.down_ratio, w.vertical)
    E = total_energy(En, Ev, Ej, w)
    if config.step_model == "normal_mode":
        E = E + frequency_energy(En, length, normal_step(legs_col, speeds[:, None]), w)
    E = np.where(hopeless & ~level, np.inf, E)
    per_metre = neutral_energy_per_metre(legs, speeds, config)
    last = slice(st.node_offset[st.n], None)  # the nodes of depth n
    far = node_s[:, last].max(axis=1)  # (A,) every plan's common end
    terminal = np.zeros(node_s.shape)
    cost, progress = E, length
    if config.terminal_cost:
        terminal[:, last] = terminal_energy(profile, base + node_s[:, last], base[:, 0] + far,
                                            base[:, 0] + trailing - 2.0, legs_col, speeds,
                                            per_metre, lo + delta * neutral, config)
        final = st.step_depth == st.n
        cost = E + np.where(final, terminal[:, st.step_front], 0.0)
        progress = np.where(final, far[:, None] - stance_s, length)
    reason = support[:, st.step_front].copy()
    reason |= np.where(np.abs(rise) > config.max_step_rise, int(Reason.STEP_HEIGHT), 0)
    reason |= np.where(reachable, 0, int(Reason.KNEE_REACH))

    # Swings: lift-off node -> touch-down node, only for pairs some legal sequence of
    # steps (from the start, through a stance foothold between them) can use.
    back, front = st.swing_back, st.swing_front
    step_ok = reason == 0
    reach = np.zeros(node_s.shape, dtype=bool)
    reach[:, :2] = True
    for k in range(1, st.n + 1):
        sl = slice(st.step_offset[k - 1], st.step_offset[k] if k < st.n else None)
        arrive = step_ok[:, sl] & reach[:, st.step_stance[sl]]
        np.logical_or.at(reach, (slice(None), st.step_front[sl]), arrive)
    first, second, valid = st.pair_steps
    through = (valid & step_ok[:, first] & step_ok[:, second]).any(axis=-1)
    needed = through & reach[:, back] if PRUNE_SWINGS else (
        (support[:, front] == 0) & (support[:, back] == 0))
    P = back.size
    controls = np.zeros((A, P, 4, 2))
    rounds = np.full((A, P), -1)
    swing_ok = np.zeros((A, P), dtype=bool)
    built, reused, adjustments = (np.zeros(A, dtype=np.int64) for _ in range(3))
    agent_of, which = np.nonzero(needed)
    if agent_of.size:
        b_node, f_node = back[which], front[which]
        start = base[agent_of, 0] + node_s[agent_of, b_node]
        end = base[agent_of, 0] + node_s[agent_of, f_node]
        z_start, z_end = node_z[agent_of, b_node], node_z[agent_of, f_node]
        # Spans where the ground is one straight segment reuse the flat curve, sheared to
        # the slope: the sole then keeps the flat clearance minus |grade| x foot offset.
        stride = st.swing_stride[which].copy()
        # Depth 1 swings start at the trailing foot; when it stands a grid step behind
        # (the default), their strides are on the grid too.
        behind = (-trailing - lo) / delta
        on_grid = ((np.abs(behind - np.round(behind)) < 1e-9) & (behind > -0.5)
                   & (behind < config.intervals + 0.5))
        depth_one = (stride < 0) & on_grid[agent_of]
        stride[depth_one] = (np.round(behind[agent_of[depth_one]]).astype(np.int64)
                             + st.node_m[f_node[depth_one]])
        heel = legs_col.heel_offset[agent_of, 0]
        toe = legs_col.toe_offset[agent_of, 0]
        vertices = (np.searchsorted(profile.s, end + toe, side="left")
                    - np.searchsorted(profile.s, start - heel, side="right"))
        grade = (z_end - z_start) / (end - start)
        nominal = 2 * lo[agent_of] + np.maximum(stride, 0) * delta[agent_of]
        flat = ((stride >= 0) & (vertices == 0) & (np.abs(grade) <= config.max_foot_slope)
                & (np.abs(end - start - nominal) <= 1e-9))  # snapped footholds differ
        # Level spans use the flat curves; sloped ones the curves with SLOPE_EXTRA more
        # clearance (enough for grades up to about 15 %).
        for extra, subset in ((0.0, flat & (grade == 0)), (SLOPE_EXTRA, flat & (grade != 0))):
            if not subset.any():
                continue
            flat_ctrl, flat_ok, flat_slack = flat_swings(legs, config, extra)
            ag, rows = agent_of[subset], np.flatnonzero(subset)
            fits = flat_ok[ag, stride[rows]] & (
                np.abs(grade[rows]) * np.maximum(heel[rows], toe[rows])
                <= flat_slack[ag, stride[rows]])
            flat[rows[~fits]] = False
            ag, rows = ag[fits], rows[fits]
            ctrl = flat_ctrl[ag, stride[rows]].copy()
            ctrl[..., 1] += z_start[rows, None] + grade[rows, None] * ctrl[..., 0]
            ctrl[..., 0] += node_s[ag, b_node[rows], None]
            controls[ag, which[rows]] = ctrl
            rounds[ag, which[rows]] = 0
            swing_ok[ag, which[rows]] = True
            reused += np.bincount(ag, minlength=A)
        rest = ~flat
        if rest.any():
            margin = 2 * float(legs_col.foot_length.max())
            lo_s = np.floor((float(start[rest].min()) - margin) / RASTER_CELL) * RASTER_CELL
            ground = profile.raster(lo_s, float(end[rest].max()) + margin, RASTER_CELL)
            ag = agent_of[rest]
            swing = adjust_swings(start[rest], z_start[rest], end[rest], z_end[rest], ground,
                                  legs_col.take(ag), config)
            ctrl = swing.controls
            ctrl[..., 0] -= base[ag]
            controls[ag, which[rest]] = ctrl
            rounds[ag, which[rest]] = swing.rounds
            swing_ok[ag, which[rest]] = swing.ok
            built += np.bincount(ag, minlength=A)
            adjustments += np.bincount(ag, weights=swing.rounds, minlength=A).astype(np.int64)
    return StepTables(st, lo, delta, neutral, per_metre,
                      node_s, node_z, length, rise, En, Ev, Ej, E, reason,
                      swing_ok, controls, rounds, config, cost, progress, terminal, far,
                      TableWork(np.full(A, rise.shape[1]), key_frames, built, reused,
                                adjustments))
