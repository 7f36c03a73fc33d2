"""The exact optimum over the same grid and horizon (Dinkelbach + dynamic programming)."""

from __future__ import annotations

import numpy as np

from planners.dp import cheapest
from planners.lattice import StepTables
from planners.multistart import nearest_legal
from planners.search import SearchResult

__all__ = ["optimal"]

#: Most Dinkelbach iterations (it converges superlinearly; 2-4 are typical).
MAX_ITERATIONS = 30


def optimal(tables: StepTables) -> SearchResult:
    """The legal configuration of highest efficiency (sum of lengths / sum of energies).

    The objective is a ratio, so it is not additive over steps. Dinkelbach's method
    solves it exactly: with ``lam`` the energy per metre (1 / efficiency) of the best
    configuration so far, dynamic programming finds the legal configuration minimising
    ``sum(E - lam * L)``; if that sum is negative the new configuration is more efficient
    and ``lam`` moves to it, otherwise ``lam`` is optimal. All agents iterate together.
    ``nodes_expanded`` counts the reachable DP states and ``legality_checks`` their
    transitions in every pass (:class:`~planners.dp.DPWork`; plus those of the start,
    :func:`~planners.multistart.nearest_legal`). E and L are
    the tables' ``cost`` and ``progress``: with ``PlannerConfig.terminal_cost`` every
    configuration progresses equally and the optimum is the least energy for it.
    """
    A = tables.neutral.size
    init = nearest_legal(tables)
    configs = init.configs.copy()
    found = init.found.copy()
    agents = np.flatnonzero(found)
    eff = np.zeros(A)
    if agents.size:
        _, eff[agents] = tables.evaluate(agents, configs[agents])
    expanded, checks = init.expanded.copy(), init.checks.copy()
    active = agents
    for _ in range(MAX_ITERATIONS):
        if active.size == 0:
            break
        lam = 1.0 / eff[active, None]
        best, ok, work = cheapest(tables, tables.cost[active] - lam * tables.progress[active],
                                  active)
        expanded[active] += work.states
        checks[active] += work.transitions
        _, new = tables.evaluate(active, best)
        better = ok & (new > eff[active] * (1 + 1e-12))
        movers = active[better]
        configs[movers] = best[better]
        eff[movers] = new[better]
        active = movers
    return SearchResult(configs, found, expanded, checks)
