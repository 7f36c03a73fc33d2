"""The planners' entry points: :func:`plan` for one walker, :func:`plan_batch` for many."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from planners.best_first import best_first
from planners.config import PlannerConfig
from planners.errors import invalid
from planners.fixed import fixed
from planners.lattice import StepTables, build_tables
from planners.leg import Leg
from planners.legality import Reason, describe
from planners.optimal import optimal
from planners.profile import GroundProfile
from planners.search import SearchResult
from planners.timing import phase_durations

__all__ = ["Plan", "PLANNERS", "plan", "plan_batch"]

_SEARCHES = {"best_first": best_first, "fixed": fixed, "optimal": optimal}
#: Names of the planners: Chen & Li's ``best_first``, the unplanned ``fixed`` walker and
#: the exact ``optimal`` over the same grid and horizon.
PLANNERS = frozenset(_SEARCHES)
#: Agents planned together in one vectorised pass (bounds memory).
BATCH_CHUNK = 64
OK = "ok"
NO_FOOTHOLD = "no legal foothold"


@dataclass(frozen=True, eq=False)
class Plan:
    """A footstep plan for the next ``k`` steps.

    ``k = n_steps`` when ok; without a legal configuration the plan holds the longest
    legal prefix (``k < n_steps``, possibly 0) and the status says where and why.

    Attributes
    ----------
    status : str
        ``"ok"`` or ``"no legal foothold"``.
    message : str
        Empty when ok; otherwise where and why no legal step exists.
    planner : str
    footholds_s, footholds_z : ndarray, shape (k+1,)
        Arc length and ground height of the ankle footholds, starting with the stance
        foot [m].
    step_lengths, step_heights : ndarray, shape (k,)
        Length and signed height change of each step [m].
    swing_controls : ndarray, shape (k, 4, 2)
        Bezier control points of each step's swing ankle in (s, z) [m]; the curve runs
        from the foot two placements back to the new foothold.
    phase_durations : ndarray, shape (k, 3)
        Durations of the phases T1, T2, T3 of each step (Table 1) [s].
    En, Ev, Ej, E : ndarray, shape (k,)
        Energy per step: Eq. 1 [cal/kg], Eq. 2 [its unit], Eq. 3 [J/kg], Eq. 4 [J/kg].
    efficiency : float
        Eq. 5 over the plan: total length / total energy [m kg/J].
    stats : dict
        ``nodes_expanded``, ``legality_checks``, ``swing_curves``,
        ``swing_adjustments``, ``time_s`` (per plan, amortised over a batch) and the grid
        (``step_min``, ``step_increment`` [m], ``neutral_step`` [m]).
    speed : float
        Target speed [m/s].
    trailing_s : float
        Arc length of the trailing foot at the start [m].
    """

    status: str
    message: str
    planner: str
    footholds_s: np.ndarray
    footholds_z: np.ndarray
    step_lengths: np.ndarray
    step_heights: np.ndarray
    swing_controls: np.ndarray
    phase_durations: np.ndarray
    En: np.ndarray
    Ev: np.ndarray
    Ej: np.ndarray
    E: np.ndarray
    efficiency: float
    stats: dict = field(default_factory=dict)
    speed: float = float("nan")
    trailing_s: float = float("nan")

    @property
    def ok(self) -> bool:
        """Whether a legal plan was found."""
        return self.status == OK

    @property
    def distance(self) -> float:
        """Distance covered along the path [m]."""
        return float(self.step_lengths.sum())

    @property
    def energy_total(self) -> float:
        """Total energy of the plan [J/kg]."""
        return float(self.E.sum())

    @property
    def energy_per_metre(self) -> float:
        """Energy per metre walked [J/(kg m)]; nan without steps."""
        return self.energy_total / self.distance if self.distance > 0 else float("nan")

    def to_dict(self) -> dict:
        """A JSON-ready dictionary (SI units; see the attribute docs)."""
        def clean(x):
            return None if isinstance(x, float) and not math.isfinite(x) else x

        return {
            "status": self.status,
            "message": self.message,
            "planner": self.planner,
            "speed": self.speed,
            "footholds": [{"s": float(s), "z": float(z)}
                          for s, z in zip(self.footholds_s, self.footholds_z, strict=True)],
            "step_lengths": self.step_lengths.tolist(),
            "step_heights": self.step_heights.tolist(),
            "swing_controls": self.swing_controls.tolist(),
            "phase_durations": self.phase_durations.tolist(),
            "energy": {"En": self.En.tolist(), "Ev": self.Ev.tolist(),
                       "Ej": self.Ej.tolist(), "E": self.E.tolist()},
            "energy_total": self.energy_total,
            "energy_per_metre": clean(self.energy_per_metre),
            "efficiency": self.efficiency,
            "stats": {k: (v.item() if isinstance(v, np.generic) else v)
                      for k, v in self.stats.items()},
        }


def plan(profile: GroundProfile, leg: Leg, speed: float, planner: str = "best_first",
         config: PlannerConfig | None = None, *, trailing: float | None = None,
         origin: float = 0.0) -> Plan:
    """Plan the next ``config.n_steps`` footsteps of one walker.

    Parameters
    ----------
    profile : GroundProfile
        Ground along the path [m].
    leg : Leg
        Leg geometry [m].
    speed : float
        Target walking speed along the path [m/s], in (0, 3].
    planner : {"best_first", "fixed", "optimal"}
    config : PlannerConfig, optional
    trailing : float, optional
        Arc length of the trailing foot (the one that swings next) relative to the stance
        foot [m], < 0; default one neutral step behind.
    origin : float
        Arc length of the stance foot on ``profile`` [m]; 0 by the contract.

    Returns
    -------
    Plan
        Status ``"no legal foothold"`` (with where and why) when nothing is legal.
    """
    return plan_batch([profile], leg, speed, planner, config,
                      trailing=None if trailing is None else [trailing], origins=[origin])[0]


def plan_batch(profiles: Sequence[GroundProfile], legs: Leg | Sequence[Leg], speeds,
               planner: str = "best_first", config: PlannerConfig | None = None, *,
               trailing=None, origins=None) -> list[Plan]:
    """Plan for many walkers in one vectorised pass per chunk of agents.

    Parameters
    ----------
    profiles : sequence of GroundProfile, length A
    legs : Leg or sequence of Leg (length A)
    speeds : float or array_like (A,)
        Target speeds [m/s].
    planner : {"best_first", "fixed", "optimal"}
    config : PlannerConfig, optional
    trailing : array_like (A,), optional
        Trailing-foot arc lengths relative to each stance foot [m], < 0.
    origins : array_like (A,), optional
        Stance-foot arc lengths on each profile [m]; default 0.

    Returns
    -------
    list of Plan, length A
    """
    config = PlannerConfig() if config is None else config
    if not isinstance(config, PlannerConfig):
        raise invalid("plan", "config", "a PlannerConfig", config)
    if planner not in PLANNERS:
        raise invalid("plan", "planner", f"one of {sorted(PLANNERS)}", planner)
    profiles = list(profiles)
    A = len(profiles)
    for i, p in enumerate(profiles):
        if not isinstance(p, GroundProfile):
            raise invalid("plan", f"profiles[{i}]", "a GroundProfile", type(p).__name__)
    legs = [legs] * A if isinstance(legs, Leg) else list(legs)
    if len(legs) != A or not all(isinstance(leg, Leg) for leg in legs):
        raise invalid("plan", "legs", f"a Leg or {A} Legs", legs)
    speeds = _vector(speeds, A, "speeds")
    bad = np.flatnonzero(~((speeds > 0) & (speeds <= 3.0)))
    if bad.size:
        raise invalid("plan", "speed", "finite and in (0, 3] [m/s]", float(speeds[bad[0]]))
    origins = np.zeros(A) if origins is None else _vector(origins, A, "origins")
    if trailing is not None:
        trailing = _vector(trailing, A, "trailing")
        bad = np.flatnonzero(~((trailing < 0) & (trailing > -3.0)))
        if bad.size:
            raise invalid("plan", "trailing", "in (-3, 0) [m]", float(trailing[bad[0]]))
    plans: list[Plan] = []
    for start in range(0, A, BATCH_CHUNK):
        sl = slice(start, start + BATCH_CHUNK)
        t0 = time.perf_counter()
        tables = build_tables(profiles[sl], legs[sl], speeds[sl],
                              None if trailing is None else trailing[sl], origins[sl], config)
        result = _SEARCHES[planner](tables)
        elapsed = (time.perf_counter() - t0) / len(profiles[sl])
        plans += _assemble(tables, result, planner, legs[sl], speeds[sl], origins[sl],
                           elapsed)
    return plans


def _vector(values, count: int, name: str) -> np.ndarray:
    try:
        arr = np.broadcast_to(np.asarray(values, dtype=float), (count,)).copy()
    except (TypeError, ValueError):
        raise invalid("plan", name, f"a number or {count} numbers", values) from None
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise invalid("plan", name, "finite", float(arr[bad[0]]))
    return arr


def _assemble(tables: StepTables, result: SearchResult, planner: str, legs, speeds,
              origins, elapsed: float) -> list[Plan]:
    """Turn search results into :class:`Plan` objects (gathers, no numerics per agent)."""
    st = tables.struct
    A = speeds.size
    rows = np.arange(A)[:, None]
    failed = np.flatnonzero(~result.found)
    messages = {}
    for a, (message, prefix, depth) in zip(failed.tolist(),
                                           _diagnose(tables, failed, origins), strict=True):
        messages[a] = message, depth
        result.configs[a] = prefix  # a failed agent keeps its longest legal prefix
    steps, swings = st.indices(result.configs)
    front = st.step_front[steps]
    foot_nodes = np.concatenate([np.ones((A, 1), dtype=np.int64), front], axis=1)
    foot_s = tables.node_s[rows, foot_nodes] + origins[:, None]
    foot_z = tables.node_z[rows, foot_nodes]
    lengths = tables.length[rows, steps]
    rises = tables.rise[rows, steps]
    controls = tables.controls[rows, swings].copy()
    controls[..., 0] += origins[:, None, None]
    leg_length = np.array([leg.length for leg in legs])[:, None]
    durations = phase_durations(lengths, speeds[:, None], rises, leg_length)
    terms = {name: getattr(tables, name)[rows, steps] for name in ("En", "Ev", "Ej", "E")}
    efficiency = lengths.sum(axis=1) / terms["E"].sum(axis=1)
    used_rounds = np.clip(tables.rounds, 0, None).sum(axis=1)
    curves = (tables.rounds >= 0).sum(axis=1)
    plans = []
    for a in range(A):
        stats = {
            "nodes_expanded": int(result.expanded[a]),
            "legality_checks": int(result.checks[a]),
            "swing_curves": int(curves[a]),
            "swing_adjustments": int(used_rounds[a]),
            "time_s": elapsed,
            "step_min": float(tables.step_min[a]),
            "step_increment": float(tables.step_delta[a]),
            "neutral_step": float(tables.step_min[a]
                                  + tables.step_delta[a] * tables.neutral[a]),
            # the horizon's common end and the estimated energy of walking on to it from
            # the last foothold (PlannerConfig.terminal_cost; 0 without it)
            "reach": float(tables.reach[a] + origins[a]),
            "terminal_energy": float(tables.terminal[a, foot_nodes[a, -1]]),
        }
        trailing_s = float(tables.node_s[a, 0] + origins[a])
        if a in messages:
            message, k = messages[a]
            e = terms["E"][a, :k]
            eff = float(lengths[a, :k].sum() / e.sum()) if k else 0.0
            plans.append(Plan(NO_FOOTHOLD, message, planner, foot_s[a, :k + 1],
                              foot_z[a, :k + 1], lengths[a, :k], rises[a, :k],
                              controls[a, :k], durations[a, :k], terms["En"][a, :k],
                              terms["Ev"][a, :k], terms["Ej"][a, :k], e, eff, stats,
                              float(speeds[a]), trailing_s))
            continue
        plans.append(Plan(OK, "", planner, foot_s[a], foot_z[a], lengths[a], rises[a],
                          controls[a], durations[a], terms["En"][a], terms["Ev"][a],
                          terms["Ej"][a], terms["E"][a], float(efficiency[a]), stats,
                          float(speeds[a]), trailing_s))
    return plans


def _diagnose(tables: StepTables, agents: np.ndarray, origins: np.ndarray) -> list:
    """Where and why no legal configuration exists, for each agent in ``agents``.

    Returns (message, configuration, depth) per agent: the configuration nearest to the
    neutral one among those whose first ``depth`` steps are legal, ``depth`` being the
    most steps any configuration can make.
    """
    if agents.size == 0:
        return []
    st = tables.struct
    grid = st.all_configs.astype(np.int64)
    steps, swings = st.all_indices
    messages = []
    for a in agents:
        ok = tables.step_legal[a, steps] & tables.swing_ok[a, swings]  # (J**n, n)
        leading = np.cumprod(ok, axis=1).sum(axis=1)  # legal steps before the first bad
        depth = int(leading.max())  # steps that can be made; step depth+1 fails
        reach = leading == depth
        dist = np.abs(grid - tables.neutral[a]).sum(axis=1)
        pick = np.flatnonzero(reach)[np.argmin(dist[reach])]
        s_idx, w_idx = steps[pick, depth], swings[pick, depth]
        reason = int(tables.step_reason[a, s_idx])
        if reason == 0 and not tables.swing_ok[a, w_idx]:
            reason = int(Reason.SWING)
        stance = tables.node_s[a, st.step_stance[s_idx]] + origins[a]
        landing = tables.node_s[a, st.step_front[s_idx]] + origins[a]
        lo = stance + tables.step_min[a]
        hi = lo + tables.step_delta[a] * (st.J - 1)
        rise = float(tables.rise[a, s_idx])
        detail = f", rise {rise:+.2f} m" if reason & Reason.STEP_HEIGHT else ""
        messages.append((
            f"no legal foothold for step {depth + 1} from s = {stance:.2f} m (landings "
            f"s = {lo:.2f}..{hi:.2f} m tried): {describe(reason)} (e.g. landing at "
            f"s = {landing:.2f} m{detail})", grid[pick], depth))
    return messages
