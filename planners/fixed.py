"""The unplanned walker: the neutral step every time, no lookahead (Fig. 11a)."""

from __future__ import annotations

import numba as nb
import numpy as np

from planners.lattice import StepTables, run_parts
from planners.lattice_kernel import eval_step, eval_swing
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
    tables.prepare()
    j = np.arange(J)
    # Preference order per agent: distance to neutral, then shorter first.
    order = np.argsort(np.abs(j[None, :] - tables.neutral[:, None]) * 2 * J + j[None, :],
                       axis=1, kind="stable").astype(np.int64)
    configs = np.zeros((A, n), dtype=np.int64)
    found = np.ones(A, dtype=np.bool_)
    checks = np.zeros(A, dtype=np.int64)
    run_parts(_fixed, A, tables.lattice, order, configs, found, checks)
    expanded = np.full(A, n, dtype=np.int64)
    stuck = np.flatnonzero(~found)
    if stuck.size:
        # a dead end: the whole table (as a search may read it), the step-by-step pass
        # again over it (its counts), then depth-first backtracking
        tables.complete(stuck)
        configs[stuck], checks[stuck] = _greedy_rows(tables, stuck, order[stuck])
    for a in stuck:
        result, pushes, looked = _backtrack(tables, a, order[a])
        expanded[a] += pushes
        checks[a] += looked
        if result is not None:
            configs[a], found[a] = result, True
    return SearchResult(configs, found, expanded, checks)


@nb.njit(cache=True, nogil=True)
def _fixed(L, order, configs, found, checks, part, parts):
    """The step-by-step pass of every agent, its steps and swings read up to the first
    depth without a legal step (:func:`fixed`'s dead ends are handled there)."""
    J = L.flat_Ej.shape[1]
    # what is evaluated is read from the arrays; L is passed only to evaluate (see the
    # note at lattice_kernel.inline)
    step_done, reason, swing_done, swing_ok = L.step_done, L.reason, L.swing_done, L.swing_ok
    step_offset, swing_offset, swing_strides = L.step_offset, L.swing_offset, L.swing_strides
    for a in range(part, configs.shape[0], parts):
        m_prev, m_prev2, j_prev = 0, 0, 0
        for k in range(configs.shape[1]):
            pick = -1
            for i in range(J):
                j = order[a, i]
                step = step_offset[k] + m_prev * J + j
                swing = swing_offset[k] + m_prev2 * swing_strides[k] + j + (
                    j_prev if k > 0 else 0)
                if not step_done[a, step]:
                    eval_step(L, a, step)
                if reason[a, step] != 0:
                    continue
                if not swing_done[a, swing]:
                    eval_swing(L, a, swing)
                if swing_ok[a, swing]:
                    pick = j
                    checks[a] += i + 1
                    break
            if pick < 0:
                found[a] = False
                break
            configs[a, k] = pick
            if k > 0:
                m_prev2 += j_prev
            m_prev += pick
            j_prev = pick


def _greedy_rows(tables: StepTables, rows: np.ndarray, order: np.ndarray):
    """The step-by-step pass over the complete tables of agents ``rows`` (C,) with
    preference orders (C, J): configurations (C, n) (the first choice where no step is
    legal) and candidate steps looked up (C,)."""
    st = tables.struct
    C, n, J = rows.size, st.n, st.J
    configs = np.zeros((C, n), dtype=np.int64)
    checks = np.zeros(C, dtype=np.int64)
    at = np.arange(C)
    for k in range(n):
        trial = np.repeat(configs[:, None, :], J, axis=1)
        trial[:, :, k] = order
        steps, swings = st.indices(trial)
        ok = (tables.step_legal[rows[:, None], steps[:, :, k]]
              & tables.swing_ok[rows[:, None], swings[:, :, k]])
        first = np.argmax(ok, axis=1)
        has = ok[at, first]
        checks += np.where(has, first + 1, J)
        configs[:, k] = order[at, first]
    return configs, checks


def _backtrack(tables: StepTables, agent: int, order: np.ndarray):
    """Depth-first search in preference order for one agent.

    Returns the configuration (None if nothing is legal), the step decisions opened and
    the candidate steps looked up."""
    st = tables.struct
    n, J = st.n, st.J
    # the agent's rows of the complete tables (read only), and the indices of step and
    # swing k of a configuration by Structure.indices' formulas, from the prefix's sums
    step_legal, swing_ok = tables.step_legal[agent].tolist(), tables.swing_ok[agent].tolist()
    step_off, swing_off, strides = st.step_offset, st.swing_offset, st.swing_strides
    prefix: list[int] = []
    sums = [0]  # sums[k] = m_k, the sum of prefix[:k]
    order = order.tolist()
    stack = [iter(order)]
    budget = 20000
    looked = pushes = 0
    while stack and budget > 0:
        try:
            choice = next(stack[-1])
        except StopIteration:
            stack.pop()
            if prefix:
                prefix.pop()
                sums.pop()
            continue
        budget -= 1
        looked += 1
        k = len(prefix)
        step = step_off[k] + sums[k] * J + choice
        swing = (swing_off[k] + (sums[k - 1] * strides[k] + prefix[-1] if k else 0)
                 + choice)
        if step_legal[step] and swing_ok[swing]:
            prefix.append(choice)
            sums.append(sums[-1] + choice)
            if len(prefix) == n:
                return np.array(prefix), pushes, looked
            stack.append(iter(order))
            pushes += 1
    return None, pushes, looked
