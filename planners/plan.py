"""The planners' entry points: :func:`plan` for one walker, :func:`plan_batch` for many."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from planners import lattice, stages
from planners.best_first import best_first
from planners.config import PlannerConfig
from planners.errors import invalid
from planners.fixed import fixed
from planners.lattice import StepTables, build_tables
from planners.leg import Leg
from planners.legality import Reason, describe
from planners.multistart import best_first_multistart
from planners.optimal import optimal
from planners.profile import GroundProfile
from planners.search import SearchResult
from planners.timing import phase_durations
from planners.turning import split_turn

__all__ = ["Plan", "PLANNERS", "plan", "plan_batch"]

_SEARCHES = {"best_first": best_first, "best_first_multistart": best_first_multistart,
             "fixed": fixed, "optimal": optimal}
#: Names of the planners: Chen & Li's ``best_first`` (FIND_INIT + BFP as written), the
#: improved ``best_first_multistart`` (several starts, a wider neighbourhood), the
#: unplanned ``fixed`` walker and the exact ``optimal`` over the same grid and horizon.
PLANNERS = frozenset(_SEARCHES)
#: Agents planned together in one vectorised pass (bounds memory).
BATCH_CHUNK = 64
#: A batch of several chunks shares its chunks out on the threads
#: (:func:`~planners.lattice.run_tasks`: each chunk's kernels on one thread) instead of
#: running each chunk's kernels on every thread in turn (False; the same plans).
CHUNK_THREADS = True
OK = "ok"
NO_FOOTHOLD = "no legal foothold"
#: The message of a failed plan that was not diagnosed (``plan_batch(diagnose=...)``).
NOT_DIAGNOSED = "no legal configuration (not diagnosed)"


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
        Counted work: the search's ``nodes_expanded`` and ``legality_checks`` (see each
        search), and the tables' ``lattice_steps`` (evaluated), ``key_frame_solves``,
        ``swing_curves`` (built by §5.2), ``swing_curves_reused`` (from the flat-ground
        cache), ``swing_adjustments`` (see :class:`~planners.lattice.TableWork`);
        ``time_s`` (per plan, amortised over a batch); the grid (``step_min``,
        ``step_increment``, ``neutral_step`` [m]); ``reach`` and ``terminal_energy``.
    speed : float
        Target speed [m/s].
    trailing_s : float
        Arc length of the trailing foot at the start [m].
    foot_rotations : ndarray, shape (k,)
        Heading increment of each new foothold on a curved path (§5.4,
        :func:`~planners.turning.split_turn` of the path's heading change over the plan
        with ``PlannerConfig.turn_threshold``; the inside foot turns first) [rad]; a turn
        needing more placements than the plan has continues in the next plan. Zeros on a
        straight path.
    feet : tuple of str, length k
        ``"left"`` or ``"right"``: the foot making each step (the first is the trailing
        foot, alternating); empty strings when the caller did not say which foot.
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
    foot_rotations: np.ndarray = field(default_factory=lambda: np.zeros(0))
    feet: tuple[str, ...] = ()

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
            "foot_rotations": self.foot_rotations.tolist(),
            "feet": list(self.feet),
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
    planner : {"best_first", "best_first_multistart", "fixed", "optimal"}
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
               trailing=None, origins=None, heading_change=None,
               first_foot=None, diagnose=True) -> list[Plan]:
    """Plan for many walkers in one vectorised pass per chunk of agents.

    Parameters
    ----------
    profiles : sequence of GroundProfile, length A
    legs : Leg or sequence of Leg (length A)
    speeds : float or array_like (A,)
        Target speeds [m/s].
    planner : {"best_first", "best_first_multistart", "fixed", "optimal"}
    config : PlannerConfig, optional
    trailing : array_like (A,), optional
        Trailing-foot arc lengths relative to each stance foot [m], < 0.
    origins : array_like (A,), optional
        Stance-foot arc lengths on each profile [m]; default 0.
    heading_change : array_like (A,), optional
        Change of walking direction along each path over the plan [rad], positive left;
        gives :attr:`Plan.foot_rotations` (default straight paths).
    first_foot : sequence of str (A,), optional
        ``"left"`` or ``"right"``: the foot making each agent's next step (which foot
        turns first, :attr:`Plan.feet`); default ``"left"`` where ``heading_change`` is
        given.
    diagnose : bool or array_like of bool (A,), optional
        Diagnose the failed plans of these agents (default all): the message naming
        where the walker is stopped and the longest legal prefix, which evaluates the
        agent's whole table (:meth:`~planners.lattice.StepTables.complete`). A failed plan
        not diagnosed has no steps and the message ``NOT_DIAGNOSED`` (for a caller that
        plans it again); every other plan is the same.

    Returns
    -------
    list of Plan, length A
    """
    config = _default_config() if config is None else config
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
    turns = None if heading_change is None else _vector(heading_change, A, "heading_change")
    if first_foot is None:
        first_foot = ["left" if turns is not None else ""] * A
    first_foot = list(first_foot)
    if len(first_foot) != A or not set(first_foot) <= {"left", "right", ""}:
        raise invalid("plan", "first_foot", f"{A} of 'left' or 'right'", first_foot)
    diagnose = np.broadcast_to(np.asarray(diagnose, dtype=bool), (A,))
    if trailing is not None:
        trailing = _vector(trailing, A, "trailing")
        bad = np.flatnonzero(~((trailing < 0) & (trailing > -3.0)))
        if bad.size:
            raise invalid("plan", "trailing", "in (-3, 0) [m]", float(trailing[bad[0]]))

    def chunk(i: int) -> list[Plan]:
        sl = slice(i * BATCH_CHUNK, (i + 1) * BATCH_CHUNK)
        t0 = time.perf_counter()
        tables = build_tables(profiles[sl], legs[sl], speeds[sl],
                              None if trailing is None else trailing[sl], origins[sl], config,
                              lazy=lattice.PRUNE and planner in lattice.LAZY,
                              defer_swings=planner in lattice.DEFER_SWINGS,
                              defer_steps=planner in lattice.DEFER_STEPS)
        t1 = time.perf_counter()
        result = _SEARCHES[planner](tables)
        t2 = stages.add("search", t1)
        elapsed = (t2 - t0) / len(profiles[sl])
        done = _assemble(tables, result, planner, profiles[sl], legs[sl], speeds[sl],
                         origins[sl], elapsed, diagnose[sl])
        stages.add("assemble", t2)
        return done

    # chunks on every core (each chunk's kernels on its thread alone), so that one
    # thread's Python (grids, arrays, assembly) overlaps another's kernels
    chunks = -(-A // BATCH_CHUNK)
    plans = [p for done in (lattice.run_tasks(chunk, chunks) if CHUNK_THREADS
                            else [chunk(i) for i in range(chunks)]) for p in done]
    if turns is None and not any(first_foot):
        return plans
    return [_turned(p, None if turns is None else float(turns[a]), first_foot[a], config)
            for a, p in enumerate(plans)]


@lru_cache(maxsize=1)
def _default_config() -> PlannerConfig:
    """``PlannerConfig()``, built once (its validation is a large part of a single plan)."""
    return PlannerConfig()


def _turned(p: Plan, change: float | None, foot: str, config: PlannerConfig) -> Plan:
    """``p`` with the §5.4 foot rotations of a heading change ``change`` [rad] and the
    stepping feet (``foot`` first)."""
    k = p.step_lengths.size
    rotations = np.zeros(k)
    if change is not None:
        split, _ = split_turn(change, config.turn_threshold, foot or "left")
        rotations[:min(k, split.size)] = split[:k]
    other = {"left": "right", "right": "left", "": ""}[foot]
    feet = tuple(foot if i % 2 == 0 else other for i in range(k))
    return replace(p, foot_rotations=rotations, feet=feet)


def _vector(values, count: int, name: str) -> np.ndarray:
    if type(values) is list and len(values) == 1 and isinstance(values[0], float | int):
        values = values[0]  # plan(): one walker
    if isinstance(values, float | int):  # a number for every walker (no broadcasting)
        number = float(values)
        if not math.isfinite(number):
            raise invalid("plan", name, "finite", number)
        return np.full(count, number)
    try:
        arr = np.broadcast_to(np.asarray(values, dtype=float), (count,)).copy()
    except (TypeError, ValueError):
        raise invalid("plan", name, f"a number or {count} numbers", values) from None
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise invalid("plan", name, "finite", float(arr[bad[0]]))
    return arr


def _assemble(tables: StepTables, result: SearchResult, planner: str, profiles, legs,
              speeds, origins, elapsed: float, diagnose: np.ndarray) -> list[Plan]:
    """Turn search results into :class:`Plan` objects (gathers, no numerics per agent);
    the failed plans of agents ``diagnose`` (A,) bool get their diagnosis, the others no
    steps."""
    st = tables.struct
    A = speeds.size
    rows = np.arange(A)[:, None]
    messages = {}
    undiagnosed = ~result.found & ~diagnose
    for a in np.flatnonzero(undiagnosed).tolist():
        messages[a] = NOT_DIAGNOSED, 0  # no steps: its configuration is not read
    if not result.found.all() and diagnose.any():
        failed = np.flatnonzero(~result.found & diagnose)
        if tables.lazy or tables.deferred:
            tables.complete(failed)  # the diagnosis reads every legal prefix
        for a, (message, prefix, depth) in zip(failed.tolist(),
                                               _diagnose(tables, failed, profiles, origins),
                                               strict=True):
            messages[a] = message, depth
            result.configs[a] = prefix  # a failed agent keeps its longest legal prefix
    steps, swings = st.indices(result.configs)
    Np = tables.controls.shape[1]
    if tables.deferred:  # (a search reads every swing of the configuration it returns)
        unbuilt = tables.pending.take(rows * Np + swings).any(axis=1) & ~undiagnosed
        if unbuilt.any():
            tables.build_pending(np.flatnonzero(unbuilt))
    foot_nodes = np.empty((A, st.n + 1), dtype=np.int64)
    foot_nodes[:, 0] = 1
    foot_nodes[:, 1:] = st.step_front[steps]
    # gathers through flat indices (faster than indexing with broadcast row arrays)
    at_node = rows * tables.node_s.shape[1] + foot_nodes
    at_step = rows * tables.length.shape[1] + steps
    foot_s = tables.node_s.take(at_node) + origins[:, None]
    foot_z = tables.node_z.take(at_node)
    lengths = tables.length.take(at_step)
    rises = tables.rise.take(at_step)
    controls = tables.controls.reshape(A * Np, 4, 2).take(rows * Np + swings, axis=0)
    leg_length = np.array([leg.length for leg in legs])[:, None]
    terms = {name: getattr(tables, name).take(at_step) for name in ("En", "Ev", "Ej", "E")}
    # a failed plan's steps (and swings) beyond its legal prefix may be unevaluated (lazy
    # tables): their values are garbage and dropped below
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        controls[..., 0] += origins[:, None, None]
        durations = phase_durations(lengths, speeds[:, None], rises, leg_length)
        efficiency = lengths.sum(axis=1) / terms["E"].sum(axis=1)
    work = tables.lattice.work.tolist()  # TableWork's counters, in the kernels' order
    expanded, checks = result.expanded.tolist(), result.checks.tolist()
    # per-agent numbers and rows taken out in whole-array passes (Python floats and row
    # views, as indexing agent by agent gave them)
    step_min, step_delta = tables.step_min.tolist(), tables.step_delta.tolist()
    neutral_step = (tables.step_min + tables.step_delta * tables.neutral).tolist()
    reach = (tables.reach + origins).tolist()
    terminal = tables.terminal.take(rows[:, 0] * tables.terminal.shape[1]
                                    + foot_nodes[:, -1]).tolist()
    trailing = (tables.node_s[:, 0] + origins).tolist()
    efficiencies, speed = efficiency.tolist(), speeds.tolist()
    agent_rows = zip(foot_s, foot_z, lengths, rises, controls, durations, terms["En"],
                  terms["Ev"], terms["Ej"], terms["E"], np.zeros((A, st.n)), strict=True)
    plans = []
    for a, row in enumerate(agent_rows):
        key_frames, built, reused, adjustments, steps_done = work[a]
        stats = {
            "nodes_expanded": expanded[a],
            "legality_checks": checks[a],
            "lattice_steps": steps_done,
            "key_frame_solves": key_frames,
            "swing_curves": built,
            "swing_curves_reused": reused,
            "swing_adjustments": adjustments,
            "time_s": elapsed,
            "step_min": step_min[a],
            "step_increment": step_delta[a],
            "neutral_step": neutral_step[a],
            # the horizon's common end and the estimated energy of walking on to it from
            # the last foothold (PlannerConfig.terminal_cost; 0 without it)
            "reach": reach[a],
            "terminal_energy": terminal[a],
        }
        trailing_s = trailing[a]
        if a in messages:
            message, k = messages[a]
            e = terms["E"][a, :k]
            eff = float(lengths[a, :k].sum() / e.sum()) if k else 0.0
            plans.append(Plan(NO_FOOTHOLD, message, planner, foot_s[a, :k + 1],
                              foot_z[a, :k + 1], lengths[a, :k], rises[a, :k],
                              controls[a, :k], durations[a, :k], terms["En"][a, :k],
                              terms["Ev"][a, :k], terms["Ej"][a, :k], e, eff, stats,
                              speed[a], trailing_s, np.zeros(k)))
            continue
        s, z, length, rise, control, duration, En, Ev, Ej, E, rotations = row
        plans.append(Plan(OK, "", planner, s, z, length, rise, control, duration, En, Ev,
                          Ej, E, efficiencies[a], stats, speed[a], trailing_s, rotations))
    return plans


def _diagnose(tables: StepTables, agents: np.ndarray, profiles, origins: np.ndarray) -> list:
    """Where and why no legal configuration exists, for each agent in ``agents``.

    Returns (message, configuration, depth) per agent: the configuration nearest to the
    neutral one among those whose first ``depth`` steps are legal, ``depth`` being the
    most steps any configuration can make. The message names where the walker is stopped:
    for a rise beyond ``max_step_rise`` the first profile vertex past the stance foot
    that is too high or too low, otherwise the failing landing nearest the neutral one.
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
        at, why = landing, describe(reason)
        if reason & Reason.STEP_HEIGHT:
            limit = tables.config.max_step_rise
            p = profiles[a]
            z0 = tables.node_z[a, st.step_stance[s_idx]]
            beyond = np.flatnonzero((p.s > stance) & (p.s <= hi)
                                    & (np.abs(p.z - z0) > limit))
            rise = float(tables.rise[a, s_idx])
            if beyond.size:
                at, rise = float(p.s[beyond[0]]), float(p.z[beyond[0]] - z0)
            why = f"rise {rise:+.2f} m exceeds the largest step rise {limit:.2f} m"
        messages.append((
            f"no legal foothold at s = {at:.2f} m: {why} (step {depth + 1} from "
            f"s = {stance:.2f} m, landings s = {lo:.2f}..{hi:.2f} m tried)", grid[pick], depth))
    return messages
