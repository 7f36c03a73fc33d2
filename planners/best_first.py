"""Chen & Li's planner: FIND_INIT (Fig. 3) then best-first planning BFP (Fig. 4)."""

from __future__ import annotations

import numpy as np

from planners.lattice import StepTables
from planners.search import SearchResult, all_configs_evaluated, neighbour_deltas

__all__ = ["find_init", "best_first"]


def find_init(tables: StepTables) -> SearchResult:
    """FIND_INIT (Fig. 3): the legal configuration nearest to (s_init, ..., s_init).

    Breadth-first search on the grid from ``q_init`` expands illegal configurations until
    it meets a legal one, i.e. it returns a legal configuration at the smallest grid
    (L1) distance from ``q_init``. Vectorised: ``q_init`` is looked up for every agent;
    only agents where it is illegal evaluate the whole grid, and among the nearest legal
    configurations the most efficient is taken (Fig. 3 leaves the order within one
    breadth-first ring open). ``checks`` counts the configurations breadth-first search
    would have examined (all closer ones, plus one).
    """
    A = tables.neutral.size
    n, J = tables.struct.n, tables.struct.J
    q_init = np.repeat(tables.neutral[:, None], n, axis=1).astype(np.int64)
    agents = np.arange(A)
    legal, _ = tables.evaluate(agents, q_init)
    configs = q_init.copy()
    found = legal.copy()
    checks = np.ones(A, dtype=np.int64)
    blocked = np.flatnonzero(~legal)
    if blocked.size:
        all_legal, all_eff = all_configs_evaluated(tables, blocked)
        grid = tables.struct.all_configs.astype(np.int64)
        dist = np.abs(grid[None, :, :] - tables.neutral[blocked, None, None]).sum(axis=-1)
        score = np.where(all_legal, dist * 1e6 - all_eff, np.inf)
        best = np.argmin(score, axis=1)
        ok = np.isfinite(score[np.arange(blocked.size), best])
        configs[blocked] = grid[best]
        found[blocked] = ok
        d_best = dist[np.arange(blocked.size), best]
        checks[blocked] = np.where(ok, (dist < d_best[:, None]).sum(axis=1) + 1, J**n)
    return SearchResult(configs, found, checks.copy(), checks)


def best_first(tables: StepTables) -> SearchResult:
    """Best-first planning (Fig. 4) from the FIND_INIT configuration, all agents at once.

    Fig. 4 pops the most efficient open configuration, opens its better unvisited legal
    neighbours and stops at a configuration none of whose legal neighbours is better.
    Since every opened neighbour is better than the node that opened it and the best
    open node is always expanded next, this is steepest-ascent hill climbing on
    efficiency over the grid neighbourhood (+-1 interval in one step), which is how it
    is run here: one vectorised neighbour evaluation per expansion for every agent.
    """
    init = find_init(tables)
    J = tables.struct.J
    deltas = neighbour_deltas(tables.struct.n)
    configs = init.configs.copy()
    expanded = init.expanded.copy()
    checks = init.checks.copy()
    agents = np.flatnonzero(init.found)
    if agents.size:
        _, eff = tables.evaluate(agents, configs[agents])
        current = np.full(configs.shape[0], -np.inf)
        current[agents] = eff
    active = agents
    while active.size:
        neighbours = configs[active, None, :] + deltas[None, :, :]
        inside = ((neighbours >= 0) & (neighbours < J)).all(axis=-1)
        legal, eff = tables.evaluate(active, np.clip(neighbours, 0, J - 1))
        eff = np.where(inside & legal, eff, -np.inf)
        expanded[active] += 1
        checks[active] += inside.sum(axis=1)
        best = np.argmax(eff, axis=1)
        best_eff = eff[np.arange(active.size), best]
        better = best_eff > current[active] * (1 + 1e-12)
        movers = active[better]
        configs[movers] = neighbours[better, best[better]]
        current[movers] = best_eff[better]
        active = movers
    return SearchResult(configs, init.found, expanded, checks)
