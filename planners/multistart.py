"""The improved best-first search: several starts and a wider neighbourhood.

``best_first_multistart`` climbs Chen & Li's best-first search (Fig. 4, as steepest
ascent) from several initial configurations over a neighbourhood that also moves single
footholds, and keeps the best local optimum. :mod:`planners.best_first` is the paper's
search as written; this is the improvement, measured in ``benchmarks/bench_planners.py``.
"""

from __future__ import annotations

from functools import lru_cache

import numba as nb
import numpy as np

from planners.dp import cheapest, dp_one, dp_scratch
from planners.lattice import StepTables, run_parts
from planners.lattice_kernel import swing_at
from planners.search import SearchResult, efficiency_one, neighbour_deltas

__all__ = ["nearest_legal", "budget", "greedy", "hill_climb", "best_first_multistart"]


#: Local optima within this relative efficiency of each other count as the same.
AGREE = 1e-3


def nearest_legal(tables: StepTables, centres: np.ndarray | None = None,
              agents: np.ndarray | None = None) -> SearchResult:
    """A legal configuration at the least grid (L1) distance from (c, ..., c).

    What FIND_INIT (Fig. 3) returns, found by dynamic programming over the lattice where
    ``(c, ..., c)`` itself is illegal (distance is a sum over steps; ties go to the lower
    energy, where the breadth-first search of :mod:`planners.best_first` takes the first
    in its queue order). ``checks`` counts the legality look-ups (1, plus the DP
    transitions), ``expanded`` the configurations expanded (0, or the DP states).

    Parameters
    ----------
    tables : StepTables
    centres : ndarray of int, shape (B,), optional
        Step-length index of ``q_init`` per search; default the neutral step.
    agents : ndarray of int, shape (B,), optional
        Table row of each search (rows may repeat); default every agent once.

    Returns
    -------
    SearchResult
        One entry per search (B).
    """
    st = tables.struct
    n = st.n
    agents = np.arange(tables.neutral.size) if agents is None else agents
    centres = tables.neutral[agents] if centres is None else centres
    A = agents.size
    configs = np.repeat(centres[:, None], n, axis=1).astype(np.int64)
    legal = np.empty(A, dtype=np.bool_)
    _legal_each(tables.step_legal, tables.swings, st.J, st._step_offsets,
                st._swing_offsets, st._swing_strides, np.asarray(agents, dtype=np.int64),
                configs, legal)
    found = legal.copy()
    checks = np.ones(A, dtype=np.int64)
    blocked = np.flatnonzero(~legal)
    if blocked.size:
        dist = np.abs(st.step_j[None, :] - centres[blocked, None])
        cost = dist + 1e-7 * tables.cost[agents[blocked]]
        best, ok, work = cheapest(tables, cost, agents[blocked])
        configs[blocked[ok]] = best[ok]
        found[blocked] = ok
        checks[blocked] += work.transitions
        expanded = np.zeros(A, dtype=np.int64)
        expanded[blocked] = work.states
    else:
        expanded = np.zeros(A, dtype=np.int64)
    return SearchResult(configs, found, expanded, checks)


@nb.njit(cache=True, nogil=True)
def _legal_each(step_legal, sw, J, step_off, swing_off, strides, agents, configs,
                legal):
    """Whether each configuration ``configs[b]`` (B, n) is legal for table row
    ``agents[b]`` (compiled, as :meth:`~planners.lattice.StepTables.evaluate`)."""
    for b in range(configs.shape[0]):
        legal[b] = _legal_one(step_legal, sw, J, step_off, swing_off, strides,
                              agents[b], configs[b])


@nb.njit(cache=True, nogil=True)
def _legal_one(step_legal, sw, J, step_off, swing_off, strides, a, config):
    """Whether ``config`` (n,) is legal for table row ``a`` (every step and swing)."""
    m_prev, m_prev2, j_prev = 0, 0, 0
    ok = True
    for k in range(config.size):
        j = config[k]
        step = step_off[k] + m_prev * J + j
        swing = swing_off[k] + m_prev2 * strides[k] + j + (j_prev if k > 0 else 0)
        if ok and not (step_legal[a, step] and swing_at(sw, a, swing)):
            ok = False
        if k > 0:
            m_prev2 += j_prev
        m_prev += j
        j_prev = j
    return ok


def hill_climb(tables: StepTables, agents: np.ndarray, configs: np.ndarray):
    """BFP (Fig. 4) from ``configs`` (B, n) for table rows ``agents`` (B,), compiled.

    Steepest ascent: each expansion looks up every in-grid neighbour (see
    :func:`~planners.search.neighbour_deltas`) and moves to the most efficient legal one
    (the first among equals) while it beats the current configuration by more than 1e-12
    (relative). Returns the local optima (B, n), their efficiencies (B,), expansions and
    checks (B,).
    """
    st = tables.struct
    configs = np.ascontiguousarray(configs, dtype=np.int64).copy()
    B = agents.size
    current = np.empty(B)
    expanded = np.zeros(B, dtype=np.int64)
    checks = np.zeros(B, dtype=np.int64)
    run_parts(_climb, B, tables.step_legal, tables.swings,
              np.ascontiguousarray(tables.cost), np.ascontiguousarray(tables.progress), st.J,
              st._step_offsets, st._swing_offsets, st._swing_strides, _deltas(st.n),
              np.asarray(agents, dtype=np.int64), configs, current, expanded, checks)
    return configs, current, expanded, checks


@lru_cache(maxsize=8)
def _deltas(n: int) -> np.ndarray:
    """:func:`~planners.search.neighbour_deltas` ``(n)``, built once (read-only)."""
    deltas = neighbour_deltas(n)
    deltas.flags.writeable = False
    return deltas


@nb.njit(cache=True, nogil=True)
def _climb(step_legal, sw, cost, progress, J, step_off, swing_off, strides, deltas,
           agents, configs, current, expanded, checks, part, parts):
    """The climbs of :func:`hill_climb`, every ``parts``-th from ``part``
    (:func:`planners.lattice.run_parts`; :func:`_climb_one`)."""
    B, n = configs.shape
    r = np.empty(n, dtype=np.int64)
    for b in range(part, B, parts):
        current[b], exp, chk = _climb_one(step_legal, sw, cost, progress, J, step_off,
                                          swing_off, strides, deltas, agents[b], configs[b],
                                          r)
        expanded[b] += exp
        checks[b] += chk


@nb.njit(cache=True, nogil=True)
def _climb_one(step_legal, sw, cost, progress, J, step_off, swing_off, strides, deltas,
               a, q, r):
    """One climb of :func:`hill_climb` from the legal ``q`` (n,) of table row ``a``, in
    place (``r``: scratch (n,)); efficiencies rounded to 1e-12 as
    :meth:`~planners.lattice.StepTables.evaluate`. A neighbour's legality is read only
    where its efficiency could make it the move (above the best legal neighbour so far
    and the current configuration's threshold): the others cannot be chosen, so their
    swings need not be read. Returns (efficiency, expansions, checks)."""
    n = q.size
    expanded = 0
    checks = 0
    cur = efficiency_one(a, q, cost, progress, J, step_off)
    while True:
        expanded += 1
        best_eff, best_d = -np.inf, 0
        threshold = cur * (1 + 1e-12)
        for d in range(deltas.shape[0]):
            inside = True
            for k in range(n):
                r[k] = q[k] + deltas[d, k]
                if r[k] < 0 or r[k] >= J:
                    inside = False
            if not inside:
                continue
            checks += 1
            e = efficiency_one(a, r, cost, progress, J, step_off)
            if (e > best_eff and e > threshold
                    and _legal_one(step_legal, sw, J, step_off, swing_off, strides, a, r)):
                best_eff, best_d = e, d
        if not best_eff > threshold:
            break
        for k in range(n):
            q[k] += deltas[best_d, k]
        cur = best_eff
    return cur, expanded, checks


def greedy(tables: StepTables) -> SearchResult:
    """Step by step, the legal step of highest own efficiency (length / E); no lookahead."""
    st = tables.struct
    A, n, J = tables.neutral.size, st.n, st.J
    configs = np.zeros((A, n), dtype=np.int64)
    found = np.ones(A, dtype=bool)
    run_parts(_greedy, A, tables.step_legal, tables.swings, tables.length, tables.E, J,
              st._step_offsets, st._swing_offsets, st._swing_strides, configs, found)
    checks = np.full(A, n * J, dtype=np.int64)
    return SearchResult(configs, found, np.full(A, n, dtype=np.int64), checks)


@nb.njit(cache=True, nogil=True)
def _greedy(step_legal, sw, length, E, J, step_off, swing_off, strides, configs,
            found, part, parts):
    """The steps of :func:`greedy` (:func:`_greedy_one`), compiled, for every
    ``parts``-th agent from ``part`` (:func:`planners.lattice.run_parts`)."""
    for a in range(part, configs.shape[0], parts):
        if not _greedy_one(step_legal, sw, length, E, J, step_off, swing_off, strides,
                           a, configs[a]):
            found[a] = False


@nb.njit(cache=True, nogil=True)
def _greedy_one(step_legal, sw, length, E, J, step_off, swing_off, strides, a, config):
    """The steps of :func:`greedy` for table row ``a`` into ``config`` (n,): at step k
    the first j of highest ``length / E`` among the legal steps (of the swing from
    f_{k-2}), as ``np.argmax`` (a NaN score wins; where none is legal, j = 0 and not
    found). Returns whether found."""
    n = config.size
    found = True
    m_prev, m_prev2, j_prev = 0, 0, 0
    for k in range(n):
        best, best_j, nan = -np.inf, 0, False
        for j in range(J):
            step = step_off[k] + m_prev * J + j
            swing = swing_off[k] + m_prev2 * strides[k] + j + (j_prev if k > 0 else 0)
            if not step_legal[a, step]:
                continue
            score = length[a, step] / E[a, step]
            # the swing is read only where the step would be taken
            if not (np.isnan(score) or score > best) or not swing_at(sw, a, swing):
                continue
            if np.isnan(score):
                best_j, nan = j, True
                break
            best, best_j = score, j
        if nan or not np.isfinite(best):
            found = False
        config[k] = best_j
        if k > 0:
            m_prev2 += j_prev
        m_prev += best_j
        j_prev = best_j
    return found


def budget(tables: StepTables) -> SearchResult:
    """The legal configuration of least ``sum(E - lam0 * L)`` (one DP pass).

    ``lam0`` is the walker's energy per metre on flat ground: each metre of progress is
    worth what it normally costs. This is the linearisation of Eq. 5 at the neutral
    walk, a start for the best-first search that already accounts for the terrain. E and
    L are the tables' ``cost`` and ``progress`` (with the terminal energy, see
    :class:`~planners.config.PlannerConfig`).
    """
    cost = tables.cost - tables.neutral_cost[:, None] * tables.progress
    configs, found, work = cheapest(tables, cost)
    A = found.size
    return SearchResult(configs, found, np.full(A, work.states), np.full(A, work.transitions))


def best_first_multistart(tables: StepTables, starts: int | None = None) -> SearchResult:
    """Best-first planning (Fig. 4) from several starts, all agents at once.

    Fig. 4 pops the most efficient open configuration, opens its better unvisited legal
    neighbours and stops at a configuration none of whose legal neighbours is better.
    Since every opened neighbour is better than the node that opened it and the best
    open node is always expanded next, this is steepest-ascent hill climbing on
    efficiency over the grid neighbourhood, run here with one vectorised neighbour
    evaluation per expansion for every agent.

    Improvements over the paper's search (measured in ``benchmarks/bench_planners.py``):
    the neighbourhood also moves single footholds (see
    :func:`~planners.search.neighbour_deltas`), and the search runs from ``starts``
    initial configurations (``PlannerConfig.search_starts``) -- the nearest legal
    configuration to the neutral one (:func:`nearest_legal`), then the energy-budget
    configuration (:func:`budget`), the step-by-step greedy configuration, the nearest
    legal ones to constant steps spread over the grid -- keeping the best local optimum.
    """
    starts = tables.config.search_starts if starts is None else starts
    st = tables.struct
    A = tables.neutral.size
    out = SearchResult.empty(A, st.n)
    run_parts(_multistart, A, tables.step_legal, tables.swings,
              np.ascontiguousarray(tables.cost), np.ascontiguousarray(tables.progress),
              tables.length, tables.E, tables.neutral.astype(np.int64), tables.neutral_cost,
              st.step_j, st.J, st._step_offsets, st._swing_offsets, st._swing_strides,
              _deltas(st.n), _extra_starts(starts, st.J), starts, out.configs, out.found,
              out.expanded, out.checks)
    return out


def _composed(tables: StepTables, starts: int | None = None) -> SearchResult:
    """:func:`best_first_multistart` composed of the public steps (:func:`nearest_legal`,
    :func:`budget`, :func:`greedy`, :func:`hill_climb`), vectorised over the agents: what
    the compiled :func:`_multistart` does agent by agent (a test compares the two)."""
    J = tables.struct.J
    starts = tables.config.search_starts if starts is None else starts
    seeds = [nearest_legal(tables)]
    if starts >= 2:
        seeds.append(budget(tables))
    if starts >= 3:
        seeds.append(greedy(tables))
    configs, eff, found, expanded, checks, spread_out = _climb_all(tables, seeds)
    extra = _extra_starts(starts, J)
    # Where the first starts disagree the terrain is hard: climb from the extra starts too.
    hard = np.flatnonzero(spread_out & found) if extra.size else np.zeros(0, dtype=int)
    if hard.size:
        rows = np.repeat(hard, extra.size)
        sub = nearest_legal(tables, np.tile(extra, hard.size), rows)
        start = sub.found
        local, more_eff, exp, chk = hill_climb(tables, rows[start], sub.configs[start])
        np.add.at(expanded, rows, sub.expanded)
        np.add.at(checks, rows, sub.checks)
        np.add.at(expanded, rows[start], exp)
        np.add.at(checks, rows[start], chk)
        order = np.lexsort((-more_eff, rows[start]))
        firsts = np.ones(order.size, dtype=bool)
        firsts[1:] = rows[start][order][1:] != rows[start][order][:-1]
        winners = rows[start][order][firsts]
        win_eff = more_eff[order][firsts]
        better = win_eff > eff[winners]
        configs[winners[better]] = local[order][firsts][better]
    return SearchResult(configs, found, expanded, checks)




@nb.njit(cache=True, nogil=True)
def _nearest_one(step_legal, sw, cost, step_j, J, step_off, swing_off, strides, a,
                 centre, row, value, new, choice, config):
    """:func:`nearest_legal` from ``(centre, ..., centre)`` for table row ``a`` into
    ``config`` (n,) (``row``: scratch (Ns,); ``value``, ``new``, ``choice``:
    :func:`~planners.dp.dp_scratch`). Returns (found, expanded, checks)."""
    n = config.size
    config[:] = centre
    if _legal_one(step_legal, sw, J, step_off, swing_off, strides, a, config):
        return True, 0, 1
    for t in range(row.size):  # np.round(dist + 1e-7 * cost, 10), as cheapest
        row[t] = np.rint((abs(step_j[t] - centre) + 1e-7 * cost[a, t]) * 1e10) / 1e10
    best = np.empty(n, dtype=np.int64)
    ok, states, transitions = dp_one(step_legal, sw, row, a, J, step_off, swing_off,
                                     strides, value, new, choice, best)
    if ok:
        config[:] = best
    return ok, states, 1 + transitions


@nb.njit(cache=True, nogil=True)
def _multistart(step_legal, sw, cost, progress, length, E, neutral, neutral_cost,
                step_j, J, step_off, swing_off, strides, deltas, extra, starts, configs,
                found, expanded, checks, part, parts):
    """:func:`best_first_multistart` of every ``parts``-th agent from ``part``
    (:func:`planners.lattice.run_parts`), in one pass per agent: the starts
    (:func:`_nearest_one`, the budget DP, :func:`_greedy_one`), a climb from each one
    found (:func:`_climb_one`), the best kept as :func:`_keep_best` (the first among
    equals; a NaN only where all are NaN), and where the local optima differ by more
    than :data:`AGREE`, the climbs from the nearest legal configurations to the
    ``extra`` constant steps, the best of them (the first among equals, NaN last) taken
    where it is more efficient. The arithmetic of :func:`_composed`."""
    A, n = configs.shape
    Ns = cost.shape[1]
    value, new, choice = dp_scratch(J, n)
    row = np.empty(Ns)
    seeds = np.empty((3, n), dtype=np.int64)
    seed_found = np.zeros(3, dtype=np.bool_)
    q = np.empty(n, dtype=np.int64)
    r = np.empty(n, dtype=np.int64)
    for a in range(part, A, parts):
        exp_a, chk_a = 0, 0
        ok, e_, c_ = _nearest_one(step_legal, sw, cost, step_j, J, step_off,
                                  swing_off, strides, a, neutral[a], row, value, new,
                                  choice, seeds[0])
        seed_found[0] = ok
        exp_a += e_
        chk_a += c_
        count = 1
        if starts >= 2:  # budget: the least sum(E - lam0 * L), rounded as cheapest
            lam0 = neutral_cost[a]
            for t in range(Ns):
                row[t] = np.rint((cost[a, t] - lam0 * progress[a, t]) * 1e10) / 1e10
            ok, e_, c_ = dp_one(step_legal, sw, row, a, J, step_off, swing_off,
                                strides, value, new, choice, seeds[1])
            seed_found[1] = ok
            exp_a += e_
            chk_a += c_
            count = 2
        if starts >= 3:
            seed_found[2] = _greedy_one(step_legal, sw, length, E, J, step_off,
                                        swing_off, strides, a, seeds[2])
            exp_a += n
            chk_a += n * J
            count = 3
        configs[a, :] = seeds[0]
        best_eff, worst = -np.inf, np.inf
        seen = False
        any_found = False
        for i in range(count):
            if not seed_found[i]:
                continue
            any_found = True
            q[:] = seeds[i]
            e, x, c = _climb_one(step_legal, sw, cost, progress, J, step_off,
                                 swing_off, strides, deltas, a, q, r)
            exp_a += x
            chk_a += c
            if not np.isnan(worst) and (np.isnan(e) or e < worst):
                worst = e
            if not seen or (np.isnan(best_eff) and not np.isnan(e)) or e > best_eff:
                seen = True
                best_eff = e
                configs[a, :] = q
        found[a] = any_found
        if any_found and extra.size and worst < best_eff * (1 - AGREE):
            win_eff = np.nan
            for i in range(extra.size):
                ok, e_, c_ = _nearest_one(step_legal, sw, cost, step_j, J, step_off,
                                          swing_off, strides, a, extra[i], row, value, new,
                                          choice, q)
                exp_a += e_
                chk_a += c_
                if not ok:
                    continue
                e, x, c = _climb_one(step_legal, sw, cost, progress, J, step_off,
                                     swing_off, strides, deltas, a, q, r)
                exp_a += x
                chk_a += c
                if not np.isnan(e) and (np.isnan(win_eff) or e > win_eff):
                    win_eff = e
                    seeds[0, :] = q
            if win_eff > best_eff:
                configs[a, :] = seeds[0]
        expanded[a] = exp_a
        checks[a] = chk_a


@lru_cache(maxsize=64)
def _extra_starts(starts: int, J: int) -> np.ndarray:
    """The constant-step starts beyond the first three: ``starts - 3`` step-length indices
    spread over the grid (read-only)."""
    extra = np.linspace(0, J - 1, max(starts - 3, 0) + 2)[1:-1].round().astype(np.int64)
    extra.flags.writeable = False
    return extra


def _climb_all(tables: StepTables, seeds: list[SearchResult]):
    """Hill-climb every found seed; keep each agent's best.

    Returns configs (A, n), efficiency (A,), found (A,), expanded (A,), checks (A,) and
    whether an agent's local optima differ (A,).
    """
    A = tables.neutral.size
    rows = np.concatenate([np.flatnonzero(r.found) for r in seeds])
    start_configs = np.concatenate([r.configs[r.found] for r in seeds])
    expanded = sum(r.expanded for r in seeds)
    checks = sum(r.checks for r in seeds)
    found = np.zeros(A, dtype=bool)
    for r in seeds:
        found |= r.found
    configs = seeds[0].configs.copy()
    best_eff = np.full(A, -np.inf)
    differ = np.zeros(A, dtype=bool)
    if rows.size:
        local, eff, exp, chk = hill_climb(tables, rows, start_configs)
        worst = np.full(A, np.inf)
        _keep_best(rows, local, eff, exp, chk, configs, best_eff, worst, expanded, checks)
        differ = worst < best_eff * (1 - AGREE)
    return configs, best_eff, found, expanded, checks, differ


@nb.njit(cache=True, nogil=True)
def _keep_best(rows, local, eff, exp, chk, configs, best_eff, worst, expanded, checks):
    """Per agent ``rows[i]``: the local optimum ``local[i]`` of highest ``eff[i]`` (the
    first among equals; a NaN only where all are NaN) into ``configs`` and ``best_eff``
    (-inf where none), the least ``eff`` (NaN if any) into ``worst``; ``exp`` and ``chk``
    added to ``expanded`` and ``checks``."""
    seen = np.zeros(best_eff.size, dtype=np.bool_)
    for i in range(rows.size):
        a, e = rows[i], eff[i]
        expanded[a] += exp[i]
        checks[a] += chk[i]
        if not np.isnan(worst[a]) and (np.isnan(e) or e < worst[a]):
            worst[a] = e
        b = best_eff[a]
        if not seen[a] or (np.isnan(b) and not np.isnan(e)) or e > b:
            seen[a] = True
            best_eff[a] = e
            configs[a] = local[i]
