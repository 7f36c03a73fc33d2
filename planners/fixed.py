"""The unplanned walker: the neutral step every time, no lookahead (Fig. 11a)."""

from __future__ import annotations

import numpy as np

from planners.lattice import StepTables
from planners.search import SearchResult

__all__ = ["fixed"]


def fixed(tables: StepTables) -> SearchResult:
    """Neutral steps, adjusted only where the neutral step itself is illegal.

    Step by step, every agent takes the legal step length closest to the neutral one
    (shorter first on ties) given the steps already chosen: no energy model and no
    lookahead, so it steps onto low obstacles (Fig. 11a) and only shortens or lengthens
    a step where it would land on an edge or cannot swing over. The swing curve gets the
    same §5.2 adjustment. Agents that run into a dead end retry with depth-first
    backtracking (rare). Counted: ``expanded`` -- step decisions (a foothold whose
    candidate landings were tried), ``checks`` -- candidate steps looked up.
    """
    st = tables.struct
    A, n, J = tables.neutral.size, st.n, st.J
    j = np.arange(J)
    # Preference order per agent: distance to neutral, then shorter first.
    order = np.argsort(np.abs(j[None, :] - tables.neutral[:, None]) * 2 * J + j[None, :],
                       axis=1, kind="stable")
    configs = np.zeros((A, n), dtype=np.int64)
    found = np.ones(A, dtype=bool)
    checks = np.zeros(A, dtype=np.int64)
    rows = np.arange(A)
    for k in range(n):
        trial = np.repeat(configs[:, None, :], J, axis=1)
        trial[:, :, k] = order
        steps, swings = st.indices(trial)
        ok = (tables.step_legal[rows[:, None], steps[:, :, k]]
              & tables.swing_ok[rows[:, None], swings[:, :, k]])
        first = np.argmax(ok, axis=1)
        has = ok[rows, first]
        checks += np.where(has, first + 1, J)
        configs[:, k] = order[rows, first]
        found &= has
    expanded = np.full(A, n, dtype=np.int64)
    for a in np.flatnonzero(~found):
        result, pushes, looked = _backtrack(tables, a, order[a])
        expanded[a] += pushes
        checks[a] += looked
        if result is not None:
            configs[a], found[a] = result, True
    return SearchResult(configs, found, expanded, checks)


def _backtrack(tables: StepTables, agent: int, order: np.ndarray):
    """Depth-first search in preference order for one agent.

    Returns the configuration (None if nothing is legal), the step decisions opened and
    the candidate steps looked up."""
    st = tables.struct
    n = st.n
    prefix: list[int] = []
    stack = [iter(order)]
    budget = 20000
    looked = pushes = 0
    while stack and budget > 0:
        try:
            choice = int(next(stack[-1]))
        except StopIteration:
            stack.pop()
            if prefix:
                prefix.pop()
            continue
        budget -= 1
        looked += 1
        trial = np.array([*prefix, choice] + [0] * (n - len(prefix) - 1))
        steps, swings = st.indices(trial)
        k = len(prefix)
        if tables.step_legal[agent, steps[k]] and tables.swing_ok[agent, swings[k]]:
            prefix.append(choice)
            if len(prefix) == n:
                return np.array(prefix), pushes, looked
            stack.append(iter(order))
            pushes += 1
    return None, pushes, looked
