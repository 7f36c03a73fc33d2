"""Chen & Li's planner as written: FIND_INIT (Fig. 3), then best-first planning BFP (Fig. 4).

One search per agent, from ``q_init = (s_init, ..., s_init)`` (the neutral step), over the
grid neighbours of a configuration: one step length one interval longer or shorter
(2n neighbours). Compiled with numba; a step or a swing of the lattice is evaluated when
the search first reads it (:mod:`planners.lattice_kernel`), agents in parallel.
"""

from __future__ import annotations

from functools import lru_cache

import numba as nb
import numpy as np

from planners import lattice
from planners.lattice import StepTables, run_parts
from planners.lattice_kernel import (
    config_efficiency,
    config_legal,
    probe,
    probe_efficiency,
)
from planners.lattice_kernel import inline as _inline
from planners.search import SearchResult

__all__ = ["best_first", "bfp", "fifo_order", "find_init"]


def best_first(tables: StepTables) -> SearchResult:
    """FIND_INIT then BFP for every agent of ``tables`` (counts add up), one compiled
    pass."""
    A = tables.neutral.size
    orders, which, configs = _orders(tables)
    tables.prepare()
    found = np.zeros(A, dtype=np.bool_)
    expanded = np.zeros(A, dtype=np.int64)
    checks = np.zeros(A, dtype=np.int64)
    run_parts(_best_first, A, tables.lattice, orders, which, configs, found, expanded, checks,
              3, *_scratch(tables, True))
    return SearchResult(configs, found, expanded, checks)


def _orders(tables: StepTables):
    """Fig. 3's queue orders of the agents' q_init (K, J**n, n), each agent's order
    (A,) and the configurations q_init (A, n)."""
    n, J = tables.struct.n, tables.struct.J
    centres = tables.neutral.astype(np.int64)
    if centres.size == 1:  # a single plan
        distinct, which = centres, np.zeros(1, dtype=np.int64)
    else:
        distinct, which = np.unique(centres, return_inverse=True)
    orders = fifo_orders(tuple(distinct.tolist()), n, J)
    return orders, which.astype(np.int64), np.repeat(centres[:, None], n, axis=1)


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
    A = tables.neutral.size
    orders, which, configs = _orders(tables)
    tables.prepare()
    found = np.zeros(A, dtype=np.bool_)
    expanded = np.zeros(A, dtype=np.int64)
    checks = np.zeros(A, dtype=np.int64)
    run_parts(_best_first, A, tables.lattice, orders, which, configs, found, expanded, checks,
              1, *_scratch(tables, False))
    return SearchResult(configs, found, expanded, checks)


@lru_cache(maxsize=64)
def fifo_order(centre: int, n: int, J: int) -> np.ndarray:
    """Fig. 3's queue over the whole grid from ``(centre, ..., centre)``, every
    configuration expanded: the configurations (J**n, n) in the order they are popped."""
    order = np.empty((J**n, n), dtype=np.int8)
    _fifo(centre, n, J, order)
    order.setflags(write=False)
    return order


@lru_cache(maxsize=8)
def fifo_orders(centres: tuple, n: int, J: int) -> np.ndarray:
    """:func:`fifo_order` of each of ``centres`` (K, J**n, n), read-only (cached: a batch's
    chunks mostly have the same few neutral steps, and stacking them is ~0.6 MB a chunk;
    the benchmark's 1,000 walkers have 4 sets in 16 chunks; few entries, as each holds
    K * J**n * n bytes)."""
    orders = (fifo_order(centres[0], n, J)[None] if len(centres) == 1
              else np.stack([fifo_order(c, n, J) for c in centres]))
    orders.setflags(write=False)
    return orders


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
    tables.prepare()
    configs, found = init.configs.copy(), init.found.copy()
    A = found.size
    expanded = np.zeros(A, dtype=np.int64)
    checks = np.zeros(A, dtype=np.int64)
    orders = np.zeros((1, 1, configs.shape[1]), dtype=np.int8)
    run_parts(_best_first, A, tables.lattice, orders, np.zeros(A, dtype=np.int64), configs,
              found, expanded, checks, 2, *_scratch(tables, True))
    return SearchResult(configs, found, expanded, checks)


def _scratch(tables: StepTables, climbs: bool) -> tuple:
    """The kernel's scratch, a row per thread (:func:`run_parts`): two configurations
    (T, 2, n); for BFP (``climbs``) the visited flags (all False), the codes set in
    them and the OPEN list's codes and efficiencies (T, J**n); T = ``lattice.THREADS``,
    read now, as :func:`run_parts` reads it (a part writes only its own row: the kernel
    has no bounds checks, so fewer rows than parts would write past the arrays)."""
    n, J, T = tables.struct.n, tables.struct.J, lattice.THREADS
    size = J**n if climbs else 0
    return (np.empty((T, 2, n), dtype=np.int64),
            np.zeros((T, size), dtype=np.bool_), np.empty((T, size), dtype=np.int64),
            np.empty((T, size), dtype=np.int64), np.empty((T, size)))


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


@nb.njit(cache=True, nogil=True, _nrt=False)
def _best_first(L, orders, which, configs, found, expanded, checks, phases, pair, visited,
                seen, open_code, open_eff, part, parts):
    """FIND_INIT (``phases`` & 1) and BFP (& 2) of every agent
    (every ``parts``-th from ``part``, :func:`~planners.lattice.run_parts`), on the
    scratch rows ``part`` of :func:`_scratch`. Compiled without numba's runtime: it
    allocates nothing, so reading an array of ``L`` (or passing it to an evaluation)
    takes no reference."""
    q, r = pair[part, 0], pair[part, 1]
    for a in range(part, configs.shape[0], parts):
        if phases & 1:
            _find_init(L, a, orders[which[a]], configs[a], found, expanded, checks)
        if phases & 2 and found[a]:
            _bfp(L, a, configs[a], expanded, checks, q, r, visited[part], seen[part],
                 open_code[part], open_eff[part])


@_inline
def _find_init(L, a, order, config, found, expanded, checks):
    """Walk the FIFO order ``order`` to agent ``a``'s first legal configuration, counting
    the look-ups (the configurations walked) and the illegal (expanded) ones."""
    n = config.size
    J = L.flat_Ej.shape[1]
    sd, rs, wd, wo = L.step_done, L.reason, L.swing_done, L.swing_ok
    so, wf, ws = L.step_offset, L.swing_offset, L.swing_strides
    popped = order.shape[0]  # looked up: every configuration, where none is legal
    hit = False
    for i in range(order.shape[0]):
        legal = probe(sd, rs, wd, wo, so, wf, ws, J, a, order[i])
        if legal < 0:
            legal = config_legal(L, a, order[i])
        if legal:
            popped = i + 1
            hit = True
            for k in range(n):
                config[k] = order[i, k]
            found[a] = True
            break  # one exit (see the note at lattice_kernel.inline)
    checks[a] += popped
    expanded[a] += popped - 1 if hit else popped  # the illegal ones


@_inline
def _bfp(L, a, config, expanded, checks, q, r, visited, seen, open_code, open_eff):
    """BFP from agent ``a``'s legal ``config`` (n,), which it replaces by the result.
    Scratch: ``q``, ``r`` (n,); ``visited`` (J**n,) all False, and left so; ``seen``,
    ``open_code``, ``open_eff`` (J**n,)."""
    n = config.size
    J = L.flat_Ej.shape[1]
    sd, rs, wd, wo = L.step_done, L.reason, L.swing_done, L.swing_ok
    co, pr, so, wf, ws = L.cost, L.progress, L.step_offset, L.swing_offset, L.swing_strides
    init = _code(config, J)
    visited[init] = True
    seen[0] = init
    marked = 1
    _, e0 = config_efficiency(L, a, config)
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
                for i in range(n):
                    r[i] = q[i]
                r[k] = v
                checks[a] += 1
                legal, e2 = _efficiency(L, a, r, sd, rs, wd, wo, co, pr, so, wf, ws, J)
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
                    seen[marked] = c2
                    marked += 1
        if all_worse:
            result = c
            break
    for i in range(marked):
        visited[seen[i]] = False
    _decode(result if result >= 0 else best_code, n, J, config)


@_inline
def _efficiency(L, a, q, sd, rs, wd, wo, co, pr, so, wf, ws, J):
    """:func:`~planners.lattice_kernel.config_efficiency` from the arrays of ``L``
    (taken once per search), evaluating through ``L`` only what is missing."""
    legal, e = probe_efficiency(sd, rs, wd, wo, co, pr, so, wf, ws, J, a, q)
    ok = legal == 1
    if legal < 0:
        ok, e = config_efficiency(L, a, q)
    return ok, e
