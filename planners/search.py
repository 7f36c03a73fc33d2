"""Shared search helpers over the step tables: configurations and their evaluation."""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from planners.lattice import StepTables
from planners.lattice_kernel import efficiency_one, swing_at

__all__ = ["SearchResult", "all_configs_evaluated", "efficiency_one", "evaluate_one",
           "neighbour_deltas"]

#: Largest number of (agent, configuration, step) entries evaluated in one gather.
GATHER_BUDGET = 1 << 22


@dataclass(frozen=True)
class SearchResult:
    """Outcome of a search for A agents.

    Attributes
    ----------
    configs : ndarray of int, shape (A, n)
        Step-length indices of the chosen configuration (meaningless where not found).
    found : ndarray of bool, shape (A,)
    expanded : ndarray of int, shape (A,)
        Nodes expanded (configurations whose neighbours were generated).
    checks : ndarray of int, shape (A,)
        Configurations whose legality was looked up.
    """

    configs: np.ndarray
    found: np.ndarray
    expanded: np.ndarray
    checks: np.ndarray

    @classmethod
    def empty(cls, agents: int, n: int) -> SearchResult:
        """A result for ``agents`` agents of ``n`` steps for a kernel to fill in: nothing
        found, nothing counted."""
        return cls(np.empty((agents, n), dtype=np.int64), np.zeros(agents, dtype=np.bool_),
                   np.zeros(agents, dtype=np.int64), np.zeros(agents, dtype=np.int64))


def neighbour_deltas(n: int, shifts: bool = True) -> np.ndarray:
    """Grid neighbours of a configuration, shape (2n [+ 2(n-1)], n).

    The grid neighbours of Fig. 4 change one step length by one interval, which moves
    every later foothold too. With ``shifts`` the neighbourhood also holds the moves of a
    single foothold by one interval (step i one longer and step i+1 one shorter, or the
    reverse), which lets the search slide one foot off an obstacle without disturbing
    the others.
    """
    eye = np.eye(n, dtype=np.int64)
    moves = [-eye, eye]
    if shifts and n > 1:
        shift = eye[:-1] - eye[1:]
        moves += [shift, -shift]
    return np.concatenate(moves)


def all_configs_evaluated(tables: StepTables, agents: np.ndarray):
    """Legality and efficiency (B, J**n) of every configuration, in agent chunks."""
    st = tables.struct
    steps, swings = st.all_indices
    per_agent = steps.size
    chunk = max(1, GATHER_BUDGET // per_agent)
    legal = np.empty((agents.size, steps.shape[0]), dtype=bool)
    eff = np.empty((agents.size, steps.shape[0]))
    for start in range(0, agents.size, chunk):
        rows = agents[start:start + chunk, None, None]
        sl = slice(start, start + chunk)
        legal[sl] = (tables.step_legal[rows, steps].all(axis=-1)
                     & tables.swing_ok[rows, swings].all(axis=-1))
        eff[sl] = (tables.progress[rows, steps].sum(axis=-1)
                   / tables.cost[rows, steps].sum(axis=-1))
    return legal, eff


@nb.njit(cache=True, nogil=True)
def evaluate_one(a, q, step_legal, sw, cost, progress, J, step_off, swing_off, strides):
    """Legality and efficiency of configuration ``q`` (n,) for table row ``a``, rounded
    to 1e-12 as :meth:`~planners.lattice.StepTables.evaluate` (compiled, for the
    searches' kernels; swings read through ``sw``,
    :func:`~planners.lattice_kernel.swing_at`, up to the first illegal step or swing)."""
    n = q.size
    m_prev = 0  # lattice index of the stance foothold f_{k-1}
    m_prev2 = 0  # of the lift-off foothold f_{k-2}
    j_prev = 0
    legal = True
    energy = 0.0
    length = 0.0
    for k in range(n):
        step = step_off[k] + m_prev * J + q[k]
        stride = q[k] + (j_prev if k > 0 else 0)
        swing = swing_off[k] + m_prev2 * strides[k] + stride
        if legal and not (step_legal[a, step] and swing_at(sw, a, swing)):
            legal = False
        energy += cost[a, step]
        length += progress[a, step]
        if k > 0:
            m_prev2 += j_prev
        m_prev += q[k]
        j_prev = q[k]
    return legal, np.rint(length / energy * 1e12) / 1e12


