"""Chen & Li's planner as written: FIND_INIT (Fig. 3), then best-first planning BFP (Fig. 4).

One search per agent, from ``q_init = (s_init, ..., s_init)`` (the neutral step), over the
grid neighbours of a configuration: one step length one interval longer or shorter
(2n neighbours). Compiled with numba; the step tables are looked up, never recomputed.
"""

from __future__ import annotations

from functools import lru_cache

import numba as nb
import numpy as np

from planners.lattice import StepTables
from planners.search import SearchResult, evaluate_one

__all__ = ["best_first", "bfp", "fifo_order", "find_init"]


def best_first(tables: StepTables) -> SearchResult:
    """FIND_INIT then BFP for every agent of ``tables`` (counts add up)."""
    init = find_init(tables)
    climb = bfp(tables, init)
    return SearchResult(climb.configs, init.found, init.expanded + climb.expanded,
                        init.checks + climb.checks)


def _run(kernel, tables: StepTables, configs: np.ndarray, found: np.ndarray) -> SearchResult:
    st = tables.struct
    A = tables.neutral.size
    expanded = np.zeros(A, dtype=np.int64)
    checks = np.zeros(A, dtype=np.int64)
    kernel(tables.step_legal, tables.swing_ok, np.ascontiguousarray(tables.cost),
           np.ascontiguousarray(tables.progress), st.J,
           np.asarray(st.step_offset, dtype=np.int64), np.asarray(st.swing_offset, dtype=np.int64),
           np.asarray(st.swing_strides, dtype=np.int64), configs, found, expanded, checks)
    return SearchResult(configs, found, expanded, checks)


def find_init(tables: StepTables) -> SearchResult:
    """FIND_INIT (Fig. 3): breadth-first search from ``q_init`` for a legal configuration.

    Pops configurations in FIFO order, returns the first legal one, and enqueues the
    unvisited grid neighbours of each illegal one (order: step 1 shorter, step 1 longer,
    step 2 shorter, ...). The result is a legal configuration at the least grid (L1)
    distance from ``q_init``. Counted: ``checks`` -- configurations popped and looked up
    (Collide); ``expanded`` -- illegal ones whose neighbours were generated. Where nothing
    is legal the whole grid is searched and ``found`` is False.

    Every configuration popped before the first legal one is illegal and expanded, so
    the FIFO order of the pops does not depend on the ground: it is generated once per
    ``(q_init, J, n)`` (:func:`fifo_order`, cached) and each search walks it, looking
    every configuration up until the first legal one.
    """
    A, n, J = tables.neutral.size, tables.struct.n, tables.struct.J
    centres = tables.neutral.astype(np.int64)
    distinct, which = np.unique(centres, return_inverse=True)
    orders = (fifo_order(int(distinct[0]), n, J)[None] if distinct.size == 1
              else np.stack([fifo_order(int(c), n, J) for c in distinct]))
    configs = np.repeat(centres[:, None], n, axis=1)
    found = np.zeros(A, dtype=np.bool_)
    expanded = np.zeros(A, dtype=np.int64)
    checks = np.zeros(A, dtype=np.int64)
    st = tables.struct
    _find_init(tables.step_legal, tables.swing_ok, J, np.asarray(st.step_offset, dtype=np.int64),
               np.asarray(st.swing_offset, dtype=np.int64),
               np.asarray(st.swing_strides, dtype=np.int64), orders,
               which.astype(np.int64), configs, found, expanded, checks)
    return SearchResult(configs, found, expanded, checks)


@lru_cache(maxsize=64)
def fifo_order(centre: int, n: int, J: int) -> np.ndarray:
    """Fig. 3's queue over the whole grid from ``(centre, ..., centre)``, every
    configuration expanded: the configurations (J**n, n) in the order they are popped."""
    order = np.empty((J**n, n), dtype=np.int8)
    _fifo(centre, n, J, order)
    order.setflags(write=False)
    return order


def bfp(tables: StepTables, init: SearchResult) -> SearchResult:
    """BFP (Fig. 4) from the configurations ``init`` found by :func:`find_init`.

    Keeps an OPEN list: pops the configuration of highest efficiency (the first inserted
    among equals), inserts every legal unvisited grid neighbour more efficient than it,
    and returns it when every legal neighbour is less efficient (a local optimum). Where
    OPEN runs empty first (a plateau of equal efficiencies, which Fig. 4 leaves open) the
    most efficient configuration popped is returned. Efficiency is the tables'
    ``progress / cost`` (Eq. 5, or Eq. 5 for the same progress with
    ``PlannerConfig.terminal_cost``), rounded to 1e-12 like :meth:`StepTables.evaluate`.
    Counted: ``expanded`` -- configurations popped; ``checks`` -- in-grid neighbours
    looked up. Agents not ``init.found`` keep their configuration.
    """
    return _run(_bfp, tables, init.configs.copy(), init.found.copy())


@nb.njit(cache=True, nogil=True)
def _legal(a, q, step_legal, swing_ok, J, step_off, swing_off, strides):
    """Legality of configuration ``q`` (n,) for agent ``a`` (stops at the first illegal
    step)."""
    m_prev = 0
    m_prev2 = 0
    j_prev = 0
    for k in range(q.size):
        step = step_off[k] + m_prev * J + q[k]
        swing = swing_off[k] + m_prev2 * strides[k] + q[k] + (j_prev if k > 0 else 0)
        if not (step_legal[a, step] and swing_ok[a, swing]):
            return False
        if k > 0:
            m_prev2 += j_prev
        m_prev += q[k]
        j_prev = q[k]
    return True


@nb.njit(cache=True, nogil=True)
def _code(q, J):
    c = 0
    for k in range(q.size):
        c = c * J + q[k]
    return c


@nb.njit(cache=True, nogil=True)
def _decode(c, n, J, out):
    for k in range(n - 1, -1, -1):
        out[k] = c % J
        c //= J


@nb.njit(cache=True, nogil=True)
def _fifo(centre, n, J, order):
    """Breadth-first order of the whole grid from (centre, ..., centre) (Fig. 3's queue,
    every configuration expanded): fills ``order`` (J**n, n)."""
    total = J**n
    visited = np.zeros(total, dtype=np.bool_)
    queue = np.empty(total, dtype=np.int64)
    q = np.empty(n, dtype=np.int64)
    place = np.empty(n, dtype=np.int64)  # code change of step k by one interval
    for k in range(n):
        place[k] = J ** (n - 1 - k)
    q[:] = centre
    start = _code(q, J)
    queue[0] = start
    visited[start] = True
    head, tail = 0, 1
    while head < tail:
        c = queue[head]
        _decode(c, n, J, q)
        order[head, :] = q
        head += 1
        for k in range(n):
            if q[k] > 0 and not visited[c - place[k]]:
                visited[c - place[k]] = True
                queue[tail] = c - place[k]
                tail += 1
            if q[k] < J - 1 and not visited[c + place[k]]:
                visited[c + place[k]] = True
                queue[tail] = c + place[k]
                tail += 1


@nb.njit(cache=True, nogil=True)
def _find_init(step_legal, swing_ok, J, step_off, swing_off, strides, orders, which,
               configs, found, expanded, checks):
    """Walk each agent's FIFO order ``orders[which[a]]`` to the first legal
    configuration, counting the look-ups and the illegal (expanded) configurations."""
    A, n = configs.shape
    q = np.empty(n, dtype=np.int64)
    for a in range(A):
        order = orders[which[a]]
        for i in range(order.shape[0]):
            for k in range(n):
                q[k] = order[i, k]
            checks[a] += 1
            if _legal(a, q, step_legal, swing_ok, J, step_off, swing_off, strides):
                configs[a, :] = q
                found[a] = True
                break
            expanded[a] += 1


@nb.njit(cache=True, nogil=True)
def _bfp(step_legal, swing_ok, cost, progress, J, step_off, swing_off, strides,
         configs, found, expanded, checks):
    A, n = configs.shape
    total = J**n
    visited = np.zeros(total, dtype=np.bool_)
    open_code = np.empty(total, dtype=np.int64)
    open_eff = np.empty(total)
    q = np.empty(n, dtype=np.int64)
    r = np.empty(n, dtype=np.int64)
    for a in range(A):
        if not found[a]:
            continue
        visited[:] = False
        init = _code(configs[a], J)
        visited[init] = True
        _, e0 = evaluate_one(a, configs[a], step_legal, swing_ok, cost, progress, J, step_off,
                          swing_off, strides)
        open_code[0] = init
        open_eff[0] = e0
        size = 1
        best_code, best_eff = init, e0
        result = -1
        while size > 0:
            pick = 0
            for i in range(1, size):
                if open_eff[i] > open_eff[pick]:
                    pick = i
            c, e = open_code[pick], open_eff[pick]
            for i in range(pick, size - 1):  # keep insertion order among the rest
                open_code[i] = open_code[i + 1]
                open_eff[i] = open_eff[i + 1]
            size -= 1
            if e > best_eff:
                best_code, best_eff = c, e
            _decode(c, n, J, q)
            expanded[a] += 1
            all_worse = True
            for k in range(n):
                for d in (-1, 1):
                    v = q[k] + d
                    if v < 0 or v >= J:
                        continue
                    r[:] = q
                    r[k] = v
                    checks[a] += 1
                    legal, e2 = evaluate_one(a, r, step_legal, swing_ok, cost, progress, J,
                                          step_off, swing_off, strides)
                    if not legal:
                        continue
                    if e2 >= e:
                        all_worse = False
                    c2 = _code(r, J)
                    if e2 > e and not visited[c2]:
                        open_code[size] = c2
                        open_eff[size] = e2
                        size += 1
                        visited[c2] = True
            if all_worse:
                result = c
                break
        _decode(result if result >= 0 else best_code, n, J, configs[a])
