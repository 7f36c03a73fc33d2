"""The unplanned walker: the neutral step every time, no lookahead (Fig. 11a)."""

from __future__ import annotations

import numba as nb
import numpy as np

from planners.lattice import StepTables, run_parts
from planners.lattice_kernel import eval_step, eval_swing, inline, step_legal, swing_legal
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
    if stuck.size:  # a dead end: the pass again, then depth-first backtracking
        run_parts(_dead_ends, stuck.size, tables.lattice, stuck, order, configs, found,
                  expanded, checks, tables.lazy)
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


#: Candidate steps a dead end's depth-first backtracking may look up per agent.
BACKTRACK_BUDGET = 20000


@nb.njit(cache=True, nogil=True)
def _dead_ends(L, agents, order, configs, found, expanded, checks, lazy, part, parts):
    """The dead ends ``agents`` (D,) of the step-by-step pass, every ``parts``-th from
    ``part``: the pass again and depth-first backtracking in preference order, both over
    the entries a complete table holds (:func:`~planners.lattice_kernel.complete`),
    evaluated only where read (lazy tables).

    Sets ``configs[a]`` (the pass's, the first choice where no step is legal, or the
    first legal configuration in preference order), ``found[a]``; ``checks[a]`` becomes
    the pass's candidates looked up plus the backtracking's, ``expanded[a]`` gains the
    step decisions the backtracking opened. ``order`` (A, J): each agent's preference
    order of step lengths."""
    n = configs.shape[1]
    J = order.shape[1]
    step_offset, swing_offset, strides = L.step_offset, L.swing_offset, L.swing_strides
    reach = np.empty(L.node_depth.size, dtype=np.int8)  # -1 unknown, 0 no, 1 yes
    stack = np.empty((n + 2, 2), dtype=np.int64)  # _reach's (node, predecessor m)
    pos = np.empty(n, dtype=np.int64)  # the backtracking's next candidate per depth
    prefix = np.empty(n, dtype=np.int64)
    sums = np.zeros(n + 1, dtype=np.int64)  # sums[k]: m_k, the sum of prefix[:k]
    for i in range(part, agents.size, parts):
        a = agents[i]
        reach[:] = -1
        reach[0] = 1
        reach[1] = 1
        # the step-by-step pass over the complete table (the steps past the dead end
        # start from footholds no legal sequence may reach)
        m_prev, m_prev2, j_prev = 0, 0, 0
        looked = 0
        for k in range(n):
            pick = order[a, 0]
            tried = J
            for c in range(J):
                j = order[a, c]
                step = step_offset[k] + m_prev * J + j
                swing = swing_offset[k] + m_prev2 * strides[k] + j + (j_prev if k > 0 else 0)
                if _complete_legal(L, a, step, swing, reach, stack, lazy):
                    pick, tried = j, c + 1
                    break
            looked += tried
            configs[a, k] = pick
            if k > 0:
                m_prev2 += j_prev
            m_prev += pick
            j_prev = pick
        checks[a] = looked
        # depth-first backtracking (a stack of positions in the preference order)
        budget = BACKTRACK_BUDGET
        looked = pushes = 0
        depth = 0
        pos[0] = 0
        done = False
        while depth >= 0 and budget > 0 and not done:
            if pos[depth] >= J:
                depth -= 1
                continue
            choice = order[a, pos[depth]]
            pos[depth] += 1
            budget -= 1
            looked += 1
            k = depth
            step = step_offset[k] + sums[k] * J + choice
            swing = swing_offset[k] + choice + (sums[k - 1] * strides[k] + prefix[k - 1]
                                                if k > 0 else 0)
            if _complete_legal(L, a, step, swing, reach, stack, lazy):
                prefix[k] = choice
                sums[k + 1] = sums[k] + choice
                if k + 1 == n:
                    done = True
                else:
                    depth = k + 1
                    pos[depth] = 0
                    pushes += 1
        expanded[a] += pushes
        checks[a] += looked
        if done:
            configs[a] = prefix
            found[a] = True


@inline
def _complete_legal(L, a, step, swing, reach, stack, lazy):
    """Whether step ``step`` and swing ``swing`` of agent ``a`` are legal in its
    complete table: evaluated where a complete table holds them, read on tables
    evaluated up front. A lazy table with pruning (``iparams[2]``) holds the steps whose
    stance foothold a legal sequence of steps reaches (``reach`` (Nn,) int8 caches that,
    -1 unknown) and the swings whose lift-off foothold it reaches with a legal step from
    there to the swing's middle foothold and one on to its landing."""
    if not lazy:
        ok = L.reason[a, step] == 0 and L.swing_ok[a, swing]
    elif L.iparams[2] == 0:  # no pruning: every step, swings between supported footholds
        ok = step_legal(L, a, step) and (
            L.support[a, L.swing_back[swing]] == 0 and L.support[a, L.swing_front[swing]] == 0
            and swing_legal(L, a, swing))
    else:
        ok = _reached(L, a, L.step_stance[step], reach, stack) and step_legal(L, a, step)
        if ok:
            reach[L.step_front[step]] = 1
            ok = _reached(L, a, L.swing_back[swing], reach, stack)
        if ok:
            through = False
            J = L.pair_valid.shape[1]
            for jp in range(J):
                if (L.pair_valid[swing, jp]
                        and _reached(L, a, L.step_stance[L.pair_first[swing, jp]], reach,
                                     stack)
                        and step_legal(L, a, L.pair_first[swing, jp])
                        and step_legal(L, a, L.pair_second[swing, jp])):
                    through = True
                    break
            ok = through and swing_legal(L, a, swing)
    return ok


@inline
def _reached(L, a, node, reach, stack):
    """Whether a legal sequence of steps from the start reaches foothold ``node`` of agent
    ``a`` (``reach`` (Nn,) int8: 1 yes, 0 no, -1 unknown, filled as found; ``stack``
    (n + 2, 2) int64 scratch): the steps onto it are tried in order of their stance
    foothold, each evaluated once its stance is known to be reached."""
    J = L.flat_Ej.shape[1]
    if reach[node] < 0:
        top = 0
        stack[0, 0] = node
        stack[0, 1] = max(0, L.node_m[node] - (J - 1))
        while top >= 0:
            v = stack[top, 0]
            d, m = L.node_depth[v], L.node_m[v]
            hi = min(m, (J - 1) * (d - 1))
            mp = stack[top, 1]
            pushed = False
            hit = False
            while mp <= hi and not pushed and not hit:
                t = L.step_offset[d - 1] + mp * J + (m - mp)
                s = L.step_stance[t]
                if reach[s] < 0:  # its stance first
                    stack[top, 1] = mp
                    top += 1
                    stack[top, 0] = s
                    stack[top, 1] = max(0, L.node_m[s] - (J - 1))
                    pushed = True
                elif reach[s] == 1 and step_legal(L, a, t):
                    hit = True
                else:
                    mp += 1
            if not pushed:
                reach[v] = 1 if hit else 0
                top -= 1
    return reach[node] == 1
