"""The exact optimum over the same grid and horizon (Dinkelbach + dynamic programming)."""

from __future__ import annotations

import numba as nb
import numpy as np

from planners.dp import dp_one, dp_scratch, settle, settle_scratch
from planners.lattice import StepTables, run_parts
from planners.lattice_kernel import step_at, swing_at
from planners.multistart import nearest_legal
from planners.search import SearchResult, efficiency_one

__all__ = ["optimal"]

#: Most Dinkelbach iterations (it converges superlinearly; 2-4 are typical).
MAX_ITERATIONS = 30


def optimal(tables: StepTables) -> SearchResult:
    """The legal configuration of highest efficiency (sum of lengths / sum of energies).

    The objective is a ratio, so it is not additive over steps. Dinkelbach's method
    solves it exactly: with ``lam`` the energy per metre (1 / efficiency) of the best
    configuration so far, dynamic programming finds the legal configuration minimising
    ``sum(E - lam * L)``; if that sum is negative the new configuration is more efficient
    and ``lam`` moves to it, otherwise ``lam`` is optimal. ``nodes_expanded`` counts the
    reachable DP states and ``legality_checks`` their transitions in every pass
    (:class:`~planners.dp.DPWork`; plus those of the start, the nearest legal
    configuration by DP). On tables with deferred steps
    (:data:`~planners.lattice.DEFER_STEPS`) every DP pass is bounded first
    (:func:`~planners.dp.settle`: the steps a lower bound of their cost cannot rule out
    are evaluated) and runs over the evaluated steps: the same configurations; the
    counters count the states and transitions of those passes (the bound's passes over
    the footholds are not counted there; the steps they evaluate are, in
    ``lattice_steps`` and ``key_frame_solves``). E and L are the tables' ``cost`` and
    ``progress``: with ``PlannerConfig.terminal_cost`` every configuration progresses
    equally and the optimum is the least energy for it. Each agent iterates on its own,
    with its start in one compiled kernel (:func:`_optimal`), agents on every core
    (:func:`~planners.lattice.run_parts`).
    """
    st = tables.struct
    A = tables.neutral.size
    out = SearchResult.empty(A, st.n)
    run_parts(_optimal, A, tables.steps, tables.swings,
              np.ascontiguousarray(tables.cost), np.ascontiguousarray(tables.progress),
              tables.neutral.astype(np.int64), st.step_j, st.J, st._step_offsets,
              st._swing_offsets, st._swing_strides, out.configs, out.found, out.expanded,
              out.checks, MAX_ITERATIONS)
    return out


def _composed(tables: StepTables) -> SearchResult:
    """:func:`optimal` from :func:`~planners.multistart.nearest_legal` (vectorised over
    the agents) and :func:`_dinkelbach`: what the compiled :func:`_optimal` does agent by
    agent (a test compares the two)."""
    st = tables.struct
    init = nearest_legal(tables)
    configs = init.configs.copy()
    expanded, checks = init.expanded.copy(), init.checks.copy()
    agents = np.flatnonzero(init.found)
    run_parts(_dinkelbach, agents.size, tables.steps, tables.swings,
              np.ascontiguousarray(tables.cost), np.ascontiguousarray(tables.progress),
              st.step_j, st.J, st._step_offsets, st._swing_offsets, st._swing_strides,
              agents, configs, expanded, checks, MAX_ITERATIONS)
    return SearchResult(configs, init.found.copy(), expanded, checks)


@nb.njit(cache=True, nogil=True)
def _optimal(sp, sw, cost, progress, neutral, step_j, J, step_off, swing_off,
             strides, configs, found, expanded, checks, iterations, part, parts):
    """:func:`optimal` of every ``parts``-th agent from ``part``
    (:func:`planners.lattice.run_parts`): the start
    (:func:`~planners.multistart._nearest_one` from the neutral step), then, where one
    is found, :func:`_dinkelbach`'s iterations from it."""
    A, n = configs.shape
    value, new, choice = dp_scratch(J, n)
    bounds = settle_scratch(sp[10].shape[1], n)
    row = np.empty(cost.shape[1])
    best = np.empty(n, dtype=np.int64)
    for a in range(part, A, parts):
        ok, expanded[a], checks[a] = _nearest(sp, sw, cost, progress, step_j, J,
                                              step_off, swing_off, strides, a, neutral[a],
                                              row, value, new, choice, bounds, configs[a])
        found[a] = ok
        if ok:
            _iterate(sp, sw, cost, progress, step_j, J, step_off, swing_off, strides,
                     a, configs[a], expanded, checks, iterations, value, new, choice, row,
                     best, bounds)


@nb.njit(cache=True, nogil=True)
def _nearest(sp, sw, cost, progress, step_j, J, step_off, swing_off, strides, a, centre,
             row, value, new, choice, bounds, config):
    """:func:`~planners.multistart._nearest_one` (the legal configuration nearest
    ``(centre, ..., centre)``) with its steps read through ``sp``
    (:func:`~planners.lattice_kernel.step_at`) and its DP pass bounded
    (:func:`~planners.dp.settle`). Returns (found, expanded, checks)."""
    n = config.size
    config[:] = centre
    m_prev, m_prev2, j_prev = 0, 0, 0
    legal = True
    for k in range(n):  # _legal_one: steps and swings in order up to the first illegal
        step = step_off[k] + m_prev * J + config[k]
        swing = swing_off[k] + m_prev2 * strides[k] + config[k] + (j_prev if k > 0 else 0)
        if legal and not (step_at(sp, a, step) and swing_at(sw, a, swing)):
            legal = False
        if k > 0:
            m_prev2 += j_prev
        m_prev += config[k]
        j_prev = config[k]
    if legal:
        return True, 0, 1
    for t in range(row.size):  # np.round(dist + 1e-7 * cost, 10), as cheapest
        row[t] = np.rint((abs(step_j[t] - centre) + 1e-7 * cost[a, t]) * 1e10) / 1e10
    F, H, pred, q, path = bounds
    settle(sp, sw, a, row, 0, centre, 0.0, step_j, progress, J, step_off, swing_off,
           strides, np.inf, F, H, pred, q, path)
    best = np.empty(n, dtype=np.int64)
    ok, states, transitions = dp_one(sp[1], sw, row, a, J, step_off, swing_off,
                                     strides, value, new, choice, best)
    if ok:
        config[:] = best
    return ok, states, 1 + transitions


@nb.njit(cache=True, nogil=True)
def _dinkelbach(sp, sw, cost, progress, step_j, J, step_off, swing_off, strides,
                agents, configs, expanded, checks, iterations, part, parts):
    """Dinkelbach's iterations of :func:`optimal` from the legal ``configs[a]`` of every
    ``parts``-th agent ``a`` in ``agents`` from ``part``
    (:func:`planners.lattice.run_parts`), each until a DP pass no longer improves the
    efficiency or ``iterations`` passes. The arithmetic of the vectorised iteration it
    replaced: efficiencies rounded to 1e-12 (:func:`~planners.search.efficiency_one`, as
    :meth:`~planners.lattice.StepTables.evaluate`), step costs ``E - lam * L`` rounded to
    1e-10 (as :func:`~planners.dp.cheapest`)."""
    n = configs.shape[1]
    value, new, choice = dp_scratch(J, n)
    bounds = settle_scratch(sp[10].shape[1], n)
    row = np.empty(cost.shape[1])
    best = np.empty(n, dtype=np.int64)
    for i in range(part, agents.size, parts):
        _iterate(sp, sw, cost, progress, step_j, J, step_off, swing_off, strides,
                 agents[i], configs[agents[i]], expanded, checks, iterations, value, new,
                 choice, row, best, bounds)


@nb.njit(cache=True, nogil=True)
def _iterate(sp, sw, cost, progress, step_j, J, step_off, swing_off, strides, a,
             config, expanded, checks, iterations, value, new, choice, row, best, bounds):
    """:func:`_dinkelbach`'s iterations for table row ``a`` from its legal ``config``
    (n,), in place (``value``, ``new``, ``choice``: :func:`~planners.dp.dp_scratch`;
    ``bounds``: :func:`~planners.dp.settle_scratch`; ``row`` (Ns,), ``best`` (n,):
    scratch). Each DP pass is bounded (:func:`~planners.dp.settle`) by the sum of the
    configuration so far."""
    Ns = cost.shape[1]
    n = config.size
    F, H, pred, q, path = bounds
    eff = efficiency_one(a, config, cost, progress, J, step_off)
    for _ in range(iterations):
        lam = 1.0 / eff
        for t in range(Ns):
            row[t] = np.rint((cost[a, t] - lam * progress[a, t]) * 1e10) / 1e10
        ub = 0.0  # the configuration's sum in the DP's order
        m = 0
        for k in range(n):
            ub = ub + row[step_off[k] + m * J + config[k]]
            m += config[k]
        settle(sp, sw, a, row, 1, 0, lam, step_j, progress, J, step_off, swing_off,
               strides, ub, F, H, pred, q, path)
        ok, states, transitions = dp_one(sp[1], sw, row, a, J, step_off,
                                         swing_off, strides, value, new, choice, best)
        expanded[a] += states
        checks[a] += transitions
        moved = efficiency_one(a, best, cost, progress, J, step_off)
        if not (ok and moved > eff * (1 + 1e-12)):
            break
        config[:] = best
        eff = moved
