"""Step tables on the foothold lattice, evaluated in full or where the search reads them.

After k steps of lengths ``L_min + j*dL`` (j = 0..J-1) every foothold lies on the lattice
``k*L_min + m*dL`` (m = 0..(J-1)k). Legality and energy of step k depend only on the
stance foothold f_{k-1} and the step's own length (a *step* entry), except the swing
curve, which depends on the lift-off foothold f_{k-2} and the touch-down foothold f_k
(a *swing* entry). Each entry is evaluated once per agent, by
:mod:`planners.lattice_kernel`: all of them up front (``build_tables(..., lazy=False)``,
agents in parallel), or each when a search first reads it (``lazy=True``: the searches'
kernels read the tables through the kernel's accessors, and a value does not depend on
when it was evaluated).
"""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numba as nb
import numpy as np

from planners import stages
from planners.config import PlannerConfig
from planners.grids import leg_grids, swing_basis
from planners.lattice_kernel import (
    Lattice,
    build_agents,
    build_pending,
    build_pending_steps,
    complete_agents,
    prepare_agents,
)
from planners.legality import Reason
from planners.profile import RASTER_CELL
from planners.swing import TABLE_LEVELS

__all__ = ["Structure", "StepTables", "TableWork", "build_tables", "run_parts", "run_tasks",
           "structure"]


#: Largest number of configurations J**n whose step and swing indices are tabulated.
LOOKUP_CONFIGS = 65536
#: Batches of at least this many agents run their kernels on every core (smaller ones on
#: one: handing work to the threads costs more than it saves).
PARALLEL_AGENTS = 8
#: Threads the kernels run on (numba's thread count: NUMBA_NUM_THREADS, default the
#: cores).
THREADS = nb.config.NUMBA_NUM_THREADS
_POOL: list = []
_POOL_LOCK = threading.Lock()
#: ``serial`` True on a thread that runs its kernels on itself alone (a thread of
#: :func:`run_tasks`: the other threads run other tasks).
_LOCAL = threading.local()


def _pool() -> ThreadPoolExecutor:
    """The planners' THREADS - 1 worker threads (made on first use)."""
    with _POOL_LOCK:
        if not _POOL:
            _POOL.append(ThreadPoolExecutor(THREADS - 1, thread_name_prefix="planners"))
    return _POOL[0]


def run_parts(kernel, count: int, *args) -> None:
    """``kernel(*args, part, parts)`` for part = 0..parts-1 on ``parts`` threads (the
    kernels release the GIL and take every ``parts``-th of ``count`` independent agents
    or groups), or ``kernel(*args, 0, 1)`` below :data:`PARALLEL_AGENTS` (and on a
    thread of :func:`run_tasks`)."""
    parts = (min(THREADS, count) if count >= PARALLEL_AGENTS
             and not getattr(_LOCAL, "serial", False) else 1)
    if parts <= 1:
        kernel(*args, 0, 1)
        return
    futures = [_pool().submit(kernel, *args, part, parts) for part in range(1, parts)]
    kernel(*args, 0, parts)
    for future in futures:
        future.result()


def run_tasks(task, count: int) -> list:
    """``[task(0), ..., task(count - 1)]``, the tasks shared out on :data:`THREADS`
    threads (the calling one too), each thread taking the next task not yet taken; a
    task's kernels run on its own thread (:func:`run_parts` gives it one part). Once a
    task raises, no thread takes another, and the error is passed on. For
    independent tasks that each hold the GIL part of the time (a chunk of a batch:
    Python around compiled kernels that release it), so one thread's Python overlaps
    another's kernels. One thread below two tasks or with one thread."""
    if count < 2 or THREADS < 2 or getattr(_LOCAL, "serial", False):
        return [task(i) for i in range(count)]
    results: list = [None] * count
    taken = iter(range(count))
    lock = threading.Lock()
    failed: list = []  # a task raised (or the caller was interrupted): take no more

    def drain() -> None:
        _LOCAL.serial = True
        try:
            while True:
                with lock:
                    i = None if failed else next(taken, None)
                if i is None:
                    return
                results[i] = task(i)
        except BaseException:
            failed.append(True)
            raise
        finally:
            _LOCAL.serial = False

    futures = [_pool().submit(drain) for _ in range(min(THREADS, count) - 1)]
    try:
        drain()
    finally:
        for future in futures:
            future.result()
    return results
#: Evaluate only the steps whose stance foothold a legal sequence of steps from the start
#: reaches (the others get E = +inf and ``Reason.UNREACHED``) and the swing curves of
#: pairs a legal sequence can use (False: every step, and the swings of every pair of
#: supported footholds, up front; the plans are the same, only slower).
PRUNE = True
#: The planners whose plans evaluate the lattice lazily, where the search reads it: those
#: that read a small part of it. ``optimal`` and ``best_first_multistart`` (whose starts
#: include a DP over the whole lattice) read nearly every entry the pruned tables hold
#: (705 of 717 steps on random terrain) and get the tables up front, in one pass, which
#: is faster than entry by entry. Empty: every plan evaluates its tables up front (the
#: plans are the same).
LAZY = frozenset({"best_first", "fixed"})
#: The planners whose tables, evaluated up front, leave the swing curves that need the
#: §5.2 adjustment to be built where the search reads them (``build_tables(...,
#: defer_swings=True)``; :func:`planners.lattice_kernel.swing_at`): their DP reads a
#: step's predecessors in order of value up to the first legal swing, so about half of
#: the curves the pruned tables hold are never read. Empty: every curve up front (the
#: same plans).
DEFER_SWINGS = frozenset({"optimal", "best_first_multistart"})
#: The planners whose tables, evaluated up front, leave the steps that need key frames
#: (neither level nor hopeless) to be evaluated where the search reads them
#: (``build_tables(..., defer_steps=True)``; :func:`planners.lattice_kernel.step_at`):
#: their DP passes first evaluate only the steps that a lower bound of the cost cannot
#: rule out (:func:`planners.dp.settle`). Empty: every step up front (the same plans).
DEFER_STEPS = frozenset({"optimal"})


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


@dataclass(frozen=True, eq=False)
class TableWork:
    """What building the tables did, per agent (A,) each, counted where it was done.

    Attributes
    ----------
    steps : ndarray of int
        Lattice steps whose legality and energy were evaluated (those a legal sequence
        of steps from the start can take, see :data:`PRUNE`; with deferred steps, those
        that need no key frame and those a search read).
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
        Energy terms (Eq. 1 cal/kg, Eq. 2 unit, Eq. 3 J/kg) and the total E [J/kg]; E
        is +inf for a step that cannot be legal or was not evaluated (see :data:`PRUNE`).
    step_reason : ndarray of int, shape (A, Ns)
        :class:`~planners.legality.Reason` flags; 0 is legal.
    swing_ok : ndarray of bool, shape (A, Np)
    controls : ndarray, shape (A, Np, 4, 2)
        Swing-ankle Bezier control points (s relative to the stance foot, z) [m];
        undefined where no curve was built in lazy tables (0 in the others).
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
        What evaluating the tables did, per agent (so far, for lazy tables).
    lattice : Lattice
        The arrays above and the kernels' inputs (:mod:`planners.lattice_kernel`), for
        the searches' kernels.
    lazy : bool
        Entries are evaluated where a search reads them; an entry not evaluated
        (``evaluated`` False) is illegal, E = +inf, ``Reason.UNREACHED``, its other
        values undefined. :meth:`complete` evaluates what a search may read.
    pending : ndarray of bool, shape (A, Np)
        Swing curves not built yet, built where a search's kernel reads them through
        :attr:`swings` (deferred swings, ``build_tables(..., defer_swings=True)``; all
        False otherwise). ``swing_ok``, ``controls`` and ``rounds`` hold the curves built
        so far; :meth:`complete` builds the rest.
    step_pending : ndarray of bool, shape (A, Ns)
        Steps not evaluated yet, evaluated where a search's kernel reads them through
        :attr:`steps` (deferred steps, ``build_tables(..., defer_steps=True)``; all False
        otherwise): their ``Ej``, ``E``, ``cost`` and the knee's reach are not known yet
        (``E``, ``cost`` +inf, ``step_reason`` 0, ``legal`` False).
    legal : ndarray of bool, shape (A, Ns)
        Legal steps among those evaluated (``step_reason == 0`` and not pending; tables
        evaluated up front).
    cost_lb : ndarray, shape (A, Ns)
        With deferred steps: a lower bound of ``cost`` (the step's energy with Ej = 0;
        ``cost`` itself where evaluated; +inf where unused).
    defer_steps : bool
        The tables were built with deferred steps.
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
    lattice: Lattice
    lazy: bool
    pending: np.ndarray
    step_pending: np.ndarray
    legal: np.ndarray
    cost_lb: np.ndarray
    defer_steps: bool

    @property
    def deferred(self) -> bool:
        """Whether some swing curves or steps are still to be evaluated where a search
        reads them."""
        return bool(self.pending.any() or self.step_pending.any())

    @cached_property
    def steps(self) -> tuple:
        """What the searches' kernels read deferred steps through
        (:func:`~planners.lattice_kernel.step_at`; the arrays of
        :data:`~planners.lattice_kernel.STEP_CONTEXT`; one thread per agent, as
        :attr:`swings`)."""
        L = self.lattice
        return (self.step_pending, self.legal, self.cost_lb, L.prof_s, L.prof_z, L.bounds,
                L.slope, L.base, L.legs, L.consts, L.node_s, L.node_z, L.step_stance,
                L.step_front, L.step_depth, L.length, L.rise, L.terminal, L.fparams,
                L.iparams, L.weights, L.speeds, L.normal, L.Ej, L.E, L.reason, L.cost,
                L.work, self._leg_cache[0], self._leg_cache[1])

    @cached_property
    def _leg_cache(self) -> tuple:
        """The legs at K1 and K1' that deferred steps share (per agent and foothold:
        stance thigh, shank, reachable; next swing thigh, shank, reachable) and whether
        each is known (:func:`~planners.lattice_kernel.eval_pending_step`)."""
        shape = self.node_s.shape if self.defer_steps else (1, 1)
        return np.empty(shape + (6,)), np.zeros(shape + (2,), dtype=np.bool_)

    @cached_property
    def swings(self) -> tuple:
        """What the searches' kernels read swings through
        (:func:`~planners.lattice_kernel.swing_at`; the arrays of
        :data:`~planners.lattice_kernel.SWING_CONTEXT`). A read may build a pending
        curve of its agent, so the kernels give each agent to one thread at a time
        (:func:`run_parts` splits the agents; a search over repeated rows of one agent,
        as the vectorised compositions make, should not run on deferred tables)."""
        L = self.lattice
        return (self.pending, L.swing_ok, L.swing_done, L.swing_back, L.swing_front,
                L.node_s, L.node_z, L.base, L.legs, L.r_start, L.r_count, L.r_levels,
                L.r_table, L.r_vcum, L.basis, L.influence, L.fparams, L.iparams,
                L.controls, L.rounds, L.work, L.scratch, L.summit)

    def build_pending(self, agents: np.ndarray | None = None) -> None:
        """Build the pending swing curves of ``agents`` (default all)."""
        agents = (np.flatnonzero(self.pending.any(axis=1)) if agents is None
                  else np.asarray(agents, dtype=np.int64))
        if agents.size:
            run_parts(build_pending, agents.size, self.swings, agents)

    @property
    def work(self) -> TableWork:
        """What evaluating the tables did, per agent (counted in the kernels)."""
        w = self.lattice.work
        return TableWork(w[:, 4].copy(), w[:, 0].copy(), w[:, 1].copy(), w[:, 2].copy(),
                         w[:, 3].copy())

    @property
    def step_legal(self) -> np.ndarray:
        """Legal steps (A, Ns), bool (evaluated so far, for lazy tables and deferred
        steps; cached for tables evaluated up front)."""
        if self.lazy:
            return self.step_reason == 0
        return self.legal

    def prepare(self) -> None:
        """What the lazy kernels need of every agent before they evaluate an entry
        (``lattice_kernel.prepare``; tables evaluated up front leave it to the first
        search that reads them through those kernels)."""
        if not self.lattice.ready.all():
            run_parts(prepare_agents, self.neutral.size, self.lattice)

    def complete(self, agents: np.ndarray | None = None) -> None:
        """Evaluate every entry a search may read (:data:`PRUNE`) for ``agents``
        (default all); what a lazy search evaluated already is kept."""
        agents = (np.arange(self.neutral.size) if agents is None
                  else np.asarray(agents, dtype=np.int64))
        if agents.size and self.lazy:
            self.prepare()
            run_parts(complete_agents, agents.size, self.lattice, agents)
        elif agents.size:
            if self.defer_steps:
                run_parts(build_pending_steps, agents.size, self.steps, agents)
            self.build_pending(agents)

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


# (config, structure, PRUNE, constants) of the last configuration, replaced as one tuple so
# that a thread never reads one configuration's key with another's constants
_CONSTANTS: tuple = (None, None, None, None)


def _constants(config: PlannerConfig, st: Structure) -> tuple:
    """The kernels' inputs that depend on the configuration alone (kept for the last
    configuration: a plan's tables need them every time, a crowd uses one or two)."""
    global _CONSTANTS
    last_config, last_st, last_prune, last = _CONSTANTS
    if last_config is config and last_st is st and last_prune == PRUNE:
        return last
    w = config.weights
    first, second, valid = st.pair_steps
    basis, influence = swing_basis(config.bezier_samples)
    fparams = np.array([config.max_step_rise, config.max_foot_slope, config.support_tolerance,
                        config.edge_margin, config.swing_lift, config.pelvis_height_ratio,
                        float(np.cos(np.pi - config.knee_max_flexion)), config.min_step_ratio,
                        config.max_step_ratio, config.intervals, config.clearance,
                        config.max_swing_lift, RASTER_CELL])
    iparams = np.array([config.snap, config.terminal_cost, PRUNE,
                        config.max_adjustments, TABLE_LEVELS], dtype=np.int64)
    weights = np.array([w.alpha, w.beta, w.gamma, w.down_ratio, w.vertical == "linear",
                        w.frequency * w.alpha, w.c_thigh, w.c_calf], dtype=float)
    constants = (first, second, valid, basis, influence, fparams, iparams, weights,
                 np.asarray(st.step_offset, dtype=np.int64),
                 np.asarray(st.swing_offset, dtype=np.int64),
                 np.asarray(st.swing_strides, dtype=np.int64))
    _CONSTANTS = config, st, PRUNE, constants
    return constants


def build_tables(profiles, legs, speeds: np.ndarray, trailing: np.ndarray | None,
                 origins: np.ndarray, config: PlannerConfig, lazy: bool = False,
                 defer_swings: bool = False, defer_steps: bool = False) -> StepTables:
    """Step tables of every agent: evaluated up front, or (``lazy``) left for the
    searches to evaluate where they read them.

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
    lazy : bool
        Evaluate only the nodes (footholds, support, terminal energies) and leave every
        step and swing to the searches (else every entry :data:`PRUNE` allows, in one
        compiled pass per agent, agents in parallel).
    defer_swings : bool
        With the tables up front (not ``lazy``): leave the swing curves that need the
        §5.2 adjustment unbuilt (``pending``) for the searches to build where they read
        them (:data:`DEFER_SWINGS`); the values read are those built up front.
    defer_steps : bool
        With the tables up front (not ``lazy``): leave the steps that need key frames
        unevaluated (``step_pending``; ``legal`` False, ``cost_lb`` a lower bound of the
        cost) for the searches to evaluate where they read them (:data:`DEFER_STEPS`);
        the values read are those evaluated up front. Their stance-reachability
        (:data:`PRUNE`) takes a deferred step as legal.

    Notes
    -----
    The swing ankle at key frame K1 is lifted ``0.75 * swing_lift`` above the highest
    ground between the stance and the landing foothold (the summit of the initial §5.2
    curve), so stepping over a higher obstacle costs more joint rotation.
    """
    A = len(profiles)
    t0 = time.perf_counter()
    st = structure(config.n_steps, config.intervals + 1)
    g = leg_grids(legs, speeds, config)
    t0 = stages.add("grids", t0)
    if trailing is None:
        trailing = -(g.lo + g.delta * g.neutral)
    trailing = np.asarray(trailing, dtype=float)
    # each agent's own profile, shifted so that its stance foot lies on a raster cell
    # boundary (rasters then align with the agent's origin, whatever the batch)
    offsets = np.floor(origins / RASTER_CELL) * RASTER_CELL - origins
    base = origins + offsets
    sizes = np.array([p.s.size for p in profiles])
    bounds = np.concatenate([[0], np.cumsum(sizes)])
    prof_s = np.concatenate([p.s + o for p, o in zip(profiles, offsets.tolist(), strict=True)])
    prof_z = np.concatenate([p.z for p in profiles])
    (first, second, valid, basis, influence, fparams, iparams, weights, step_offset,
     swing_offset, swing_strides) = _constants(config, st)
    Nn, Ns, Np = st.node_depth.size, st.step_stance.size, st.swing_back.size
    # the swing raster of an agent spans its nodes (each within half an increment of the
    # grid) and two foot lengths either side
    reach_s = st.n * (g.lo + g.delta * st.J) - np.minimum(trailing, 0.0)
    cells = int(np.ceil(((reach_s + 4 * g.legs[:, 2]) / RASTER_CELL).max())) + 4
    empty, zeros = np.empty, np.zeros
    lattice = Lattice(
        st.node_depth, st.node_m, st.step_stance, st.step_front, st.step_j, st.step_depth,
        step_offset, st.swing_back, st.swing_front, st.swing_stride, swing_offset,
        swing_strides, first, second, valid,
        prof_s, prof_z, bounds, base,
        g.lo, g.delta, trailing, np.asarray(speeds, dtype=float), g.normal, g.per_metre,
        g.lo + g.delta * g.neutral, g.legs, g.flat_Ej, g.flat_reach, g.flat_ctrl,
        g.flat_ok, g.flat_slack, basis, influence, fparams, iparams, weights,
        zeros(A, dtype=np.bool_), empty(prof_s.size), empty(prof_s.size),
        zeros(A, dtype=np.int64), empty((A, 7)), empty((A, Nn), dtype=np.int64), empty(A),
        zeros(A, dtype=np.int64), zeros(A, dtype=np.int64), empty((A, TABLE_LEVELS * cells)),
        empty((A, cells + 1), dtype=np.int64), zeros(A, dtype=np.bool_),
        empty((A, Nn)), empty((A, Nn)), zeros((A, Nn)), empty(A),
        empty((A, Ns)), empty((A, Ns)), empty((A, Ns)), empty((A, Ns)), empty((A, Ns)),
        np.full((A, Ns), np.inf), np.full((A, Ns), int(Reason.UNREACHED), dtype=np.int64),
        np.full((A, Ns), np.inf), empty((A, Ns)), zeros((A, Ns), dtype=np.bool_),
        zeros((A, Np), dtype=np.bool_), (empty if lazy else zeros)((A, Np, 4, 2)),
        np.full((A, Np), -1),
        zeros((A, Np), dtype=np.bool_), zeros((A, 5), dtype=np.int64),
        empty((A, 3, basis.shape[1])), empty((A, 2)))
    L = lattice
    tables = StepTables(st, g.lo, g.delta, g.neutral, g.per_metre, L.node_s, L.node_z,
                        L.length, L.rise, L.En, L.Ev, L.Ej, L.E, L.reason, L.swing_ok,
                        L.controls, L.rounds, config, L.cost, L.progress, L.terminal, L.far,
                        lattice, lazy, zeros((A, Np), dtype=np.bool_),
                        zeros((A, Ns), dtype=np.bool_), zeros((A, Ns), dtype=np.bool_),
                        np.full((A, Ns), np.inf), bool(defer_steps and not lazy))
    t0 = stages.add("arrays", t0)
    if lazy:
        tables.prepare()
    else:  # the one-pass kernel (faster than entry by entry where most are read)
        L = lattice
        run_parts(build_agents, A, prof_s, prof_z, bounds, base, g.lo, g.delta, trailing,
                  L.speeds, g.normal, g.per_metre, L.neutral_len, g.legs, g.flat_Ej,
                  g.flat_reach, g.flat_ctrl, g.flat_ok, g.flat_slack, st.node_depth,
                  st.node_m, st.step_stance, st.step_front, st.step_j, st.step_depth,
                  L.step_offset, st.swing_back, st.swing_front, st.swing_stride, first,
                  second, valid, basis, influence, fparams, iparams, weights, L.node_s,
                  L.node_z, L.length, L.rise, L.En, L.Ev, L.Ej, L.E, L.reason, L.cost,
                  L.progress, L.terminal, L.far, L.swing_ok, L.controls, L.rounds, L.work,
                  bool(defer_swings), tables.pending, L.r_start, L.r_count, L.r_levels,
                  L.r_table, L.r_vcum, tables.defer_steps, tables.step_pending,
                  tables.legal, tables.cost_lb, L.slope, L.consts)
        if not tables.defer_steps:  # (deferred steps: the kernels keep it)
            np.equal(L.reason, 0, out=tables.legal)
        np.not_equal(L.reason, int(Reason.UNREACHED), out=L.step_done)
        np.greater_equal(L.rounds, 0, out=L.swing_done)
    stages.add("kernel", t0)
    return tables
