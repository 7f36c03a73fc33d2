"""Dynamic programming over the foothold lattice: the cheapest legal configuration.

The state before step k is (m_{k-1}, j_{k-1}): the lattice index of the stance foothold
and the previous step (the swing curve of step k depends on f_{k-2} = m_{k-1} - j_{k-1}).
Step costs are additive, so one pass per depth over (state, j_k) gives the exact minimum
for all agents at once.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from planners.lattice import StepTables, Structure

__all__ = ["DPWork", "cheapest"]


class DPWork(NamedTuple):
    """Work of one DP pass per agent (the same for every agent of a pass).

    ``states``: (m_{k-1}, j_{k-1}) states expanded over all depths; ``transitions``:
    state -> j_k transitions whose legality was looked up.
    """

    states: int
    transitions: int


@lru_cache(maxsize=16)
def _depth_indices(struct: Structure):
    """Per depth: step and swing indices (M, P, J) over (m_{k-1}, j_{k-1}, j_k), validity."""
    J, out = struct.J, []
    for k in range(1, struct.n + 1):
        M = (J - 1) * (k - 1) + 1
        P = 1 if k == 1 else J
        m, jp, j = np.meshgrid(np.arange(M), np.arange(P), np.arange(J), indexing="ij")
        step = struct.step_offset[k - 1] + m * J + j
        if k == 1:
            swing = struct.swing_offset[0] + j
            valid = np.ones(m.shape, dtype=bool)
        else:
            m2 = m - jp  # lattice index of f_{k-2}; states outside its range are impossible
            valid = (m2 >= 0) & (m2 <= (J - 1) * (k - 2))
            m2 = np.clip(m2, 0, (J - 1) * (k - 2))
            swing = struct.swing_offset[k - 1] + m2 * struct.swing_strides[k - 1] + jp + j
        mm, jj = np.meshgrid(np.arange(M), np.arange(J), indexing="ij")
        out.append((step, swing, valid, mm + jj, jj))
    return out


def dp_legal(tables: StepTables) -> list[np.ndarray]:
    """Per depth, whether a transition (m_{k-1}, j_{k-1}) -> j_k is legal.

    Shapes (A, M, P, J), bool; computed once per set of tables and cached on it.
    """
    cached = tables.__dict__.get("_dp_legal")
    if cached is None:
        cached = [valid & np.take(tables.step_legal, step, axis=1)
                  & np.take(tables.swing_ok, swing, axis=1)
                  for step, swing, valid, _, _ in _depth_indices(tables.struct)]
        tables.__dict__["_dp_legal"] = cached
    return cached


def cheapest(tables: StepTables, step_cost: np.ndarray, agents: np.ndarray | None = None):
    """The legal configuration of least total ``step_cost`` for each agent.

    Parameters
    ----------
    tables : StepTables
    step_cost : ndarray, shape (B, Ns)
        Additive cost of every step entry, for the agents ``agents``.
    agents : ndarray of int, shape (B,), optional
        Rows of ``tables`` (default: all).

    Returns
    -------
    configs : ndarray of int, shape (B, n)
    found : ndarray of bool, shape (B,)
    work : DPWork
        States and transitions the pass went through, per agent.
    """
    st = tables.struct
    J, n = st.J, st.n
    agents = np.arange(tables.neutral.size) if agents is None else agents
    B = agents.size
    step_cost = np.round(step_cost, 10)  # ties broken alike whatever the offsets
    value = np.zeros((B, 1, 1))  # (B, M_{k-1}, P_k) over (m_{k-1}, j_{k-1})
    choices = []
    states = transitions = 0
    legal = dp_legal(tables)
    every = B == tables.neutral.size and np.array_equal(agents, np.arange(B))
    for k, (step, _, valid, m_next, j_next) in enumerate(_depth_indices(st), start=1):
        states += int(valid[..., 0].sum())
        transitions += int(valid.sum())
        # illegal transitions cost +inf; the step cost broadcasts over j_{k-1}
        total = value[..., None] + np.take(
            step_cost, step[:, :1, :].reshape(step.shape[0], -1), axis=1)[:, :, None, :]
        total[~(legal[k - 1] if every else legal[k - 1][agents])] = np.inf
        best_prev = np.argmin(total, axis=2)  # over j_{k-1}: (B, M, J)
        best = total.min(axis=2)
        M = step.shape[0]
        new = np.full((B, M + J - 1, J), np.inf)
        new[:, m_next, j_next] = best
        arg = np.zeros((B, M + J - 1, J), dtype=np.int64)
        arg[:, m_next, j_next] = best_prev
        choices.append(arg)
        value = new
        if k == n:
            break
    flat = value.reshape(B, -1)
    last = np.argmin(flat, axis=1)
    found = np.isfinite(flat[np.arange(B), last])
    m_end, j_end = np.divmod(last, J)
    configs = np.zeros((B, n), dtype=np.int64)
    m_cur, j_cur = m_end, j_end
    for k in range(n, 0, -1):
        configs[:, k - 1] = j_cur
        jp = choices[k - 1][np.arange(B), m_cur, j_cur]
        m_cur, j_cur = m_cur - j_cur, jp
    return configs, found, DPWork(states, transitions)
