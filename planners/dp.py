"""Dynamic programming over the foothold lattice: the cheapest legal configuration.

The state before step k is (m_{k-1}, j_{k-1}): the lattice index of the stance foothold
and the previous step (the swing curve of step k depends on f_{k-2} = m_{k-1} - j_{k-1}).
Step costs are additive, so one pass per depth over (state, j_k) gives the exact minimum
for all agents at once. The pass reads the lattice through its lazy kernels
(:mod:`planners.lattice_kernel`): every step from a reachable state, and a swing only
where its transition would lower the state's value.
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np

from planners.lattice import StepTables, run_parts
from planners.lattice_kernel import eval_step, eval_swing
from planners.lattice_kernel import inline as _inline

__all__ = ["DISTANCE", "DPWork", "RATIO", "cheapest", "groups"]

#: Step costs of :func:`cheapest`: ``|j - param| + 1e-7 cost`` (grid distance to a
#: constant step, ties to the lower energy) or ``cost - param * progress``.
DISTANCE, RATIO = 0, 1


class DPWork(NamedTuple):
    """Work of one DP pass, per agent (B,) each, counted in the pass.

    ``states``: reachable (m_{k-1}, j_{k-1}) states expanded over all depths (a state no
    legal sequence of steps reaches is skipped); ``transitions``: their state -> j_k
    transitions (each step's legality looked up, then the swings of a legal one where
    they would lower a state's value).
    """

    states: np.ndarray
    transitions: np.ndarray


def groups(agents: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Searches grouped by agent: their order (B,) (stable) and each agent's first
    position in it (U + 1,), so that a kernel runs one agent's searches on one thread."""
    order = np.argsort(agents, kind="stable")
    sorted_ = agents[order]
    starts = np.flatnonzero(np.concatenate([[True], sorted_[1:] != sorted_[:-1], [True]]))
    return order.astype(np.int64), starts.astype(np.int64)


def cheapest(tables: StepTables, kind: int, param: np.ndarray,
             agents: np.ndarray | None = None):
    """The legal configuration of least total step cost for each search.

    Parameters
    ----------
    tables : StepTables
    kind : {DISTANCE, RATIO}
        The step cost, rounded to 1e-10 (ties broken alike): ``|j - param| + 1e-7 cost``
        (``j`` the step's length index) or ``cost - param * progress``, with the tables'
        ``cost`` and ``progress``.
    param : ndarray, shape (B,)
        Each search's constant step index or energy per metre [J/(kg m)].
    agents : ndarray of int, shape (B,), optional
        Table row of each search (rows may repeat; default: all).

    Returns
    -------
    configs : ndarray of int, shape (B, n)
    found : ndarray of bool, shape (B,)
    work : DPWork
        States and transitions the pass went through, per search.
    """
    st = tables.struct
    agents = np.arange(tables.neutral.size) if agents is None else agents
    agents = np.asarray(agents, dtype=np.int64)
    B = agents.size
    configs = np.zeros((B, st.n), dtype=np.int64)
    found = np.zeros(B, dtype=np.bool_)
    states = np.zeros(B, dtype=np.int64)
    transitions = np.zeros(B, dtype=np.int64)
    order, starts = groups(agents)
    run_parts(_cheapest, starts.size - 1, tables.lattice, agents, order, starts, kind,
           np.asarray(param, dtype=float), configs, found, states, transitions)
    return configs, found, DPWork(states, transitions)


@nb.njit(cache=True, nogil=True)
def _cheapest(L, agents, order, starts, kind, param, configs, found, states, transitions,
              part, parts):
    """The DP of every search, one agent's searches after the other on one thread."""
    for u in range(part, starts.size - 1, parts):
        for i in range(starts[u], starts[u + 1]):
            b = order[i]
            _one(L, agents[b], kind, param[b], configs[b], found, states, transitions, b)


@_inline
def _one(L, a, kind, param, config, found, states, transitions, b):
    """One DP of :func:`cheapest` for agent ``a``: per depth k, the value of each state
    (m_{k-1}, j_{k-1}) plus each step j_k, the least over j_{k-1} (the first on ties),
    then the way back from the least final state. States of infinite value (no legal way
    to them) are skipped: they cannot lower any value."""
    n = config.size
    J = L.flat_Ej.shape[1]
    step_off, swing_off, strides = L.step_offset, L.swing_offset, L.swing_strides
    step_done, reason, swing_done, swing_ok = L.step_done, L.reason, L.swing_done, L.swing_ok
    costs, progress = L.cost, L.progress
    M_last = (J - 1) * n + 1
    value = np.empty((M_last, J))
    new = np.empty((M_last, J))
    choice = np.zeros((n, M_last, J), dtype=np.int64)
    value[0, 0] = 0.0
    for k in range(1, n + 1):
        M = (J - 1) * (k - 1) + 1
        P = 1 if k == 1 else J
        new[:M + J - 1, :] = np.inf
        choice[k - 1, :M + J - 1, :] = 0
        for m in range(M):
            reachable = 0  # states (m, jp) of this depth some legal sequence reaches
            for jp in range(P):
                if value[m, jp] < np.inf:
                    reachable += 1
            states[b] += reachable
            if reachable == 0:
                continue  # new[m + j, j] stays +inf
            for j in range(J):
                transitions[b] += reachable
                step = step_off[k - 1] + m * J + j
                if not step_done[a, step]:
                    eval_step(L, a, step)
                if reason[a, step] != 0:
                    continue
                if kind == 0:
                    cost = float(abs(j - param)) + 1e-7 * costs[a, step]
                else:
                    cost = costs[a, step] - param * progress[a, step]
                cost = np.rint(cost * 1e10) / 1e10
                best = np.inf
                arg = 0
                for jp in range(P):
                    v = value[m, jp]
                    if not v < np.inf or not v + cost < best:
                        continue
                    if k == 1:
                        q = swing_off[0] + j
                    else:
                        m2 = m - jp
                        if not 0 <= m2 <= (J - 1) * (k - 2):
                            continue
                        q = swing_off[k - 1] + m2 * strides[k - 1] + jp + j
                    if not swing_done[a, q]:
                        eval_swing(L, a, q)
                    ok = swing_ok[a, q]
                    if ok:
                        best = v + cost
                        arg = jp
                new[m + j, j] = best
                choice[k - 1, m + j, j] = arg
        M_next = M + J - 1
        value[:M_next, :] = new[:M_next, :]
    best = np.inf
    last_m, last_j = 0, 0
    for m in range(M_last):
        for j in range(J):
            if value[m, j] < best:
                best = value[m, j]
                last_m, last_j = m, j
    found[b] = best < np.inf
    m_cur, j_cur = last_m, last_j
    for k in range(n, 0, -1):
        config[k - 1] = j_cur
        jp = choice[k - 1, m_cur, j_cur]
        m_cur, j_cur = m_cur - j_cur, jp
