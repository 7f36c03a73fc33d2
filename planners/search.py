"""Shared search helpers over the step tables: configurations and their evaluation."""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from planners.lattice import StepTables, run_parts
from planners.lattice_kernel import config_efficiency

__all__ = ["SearchResult", "all_configs_evaluated", "evaluate", "neighbour_deltas"]

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


def evaluate(tables: StepTables, agents: np.ndarray, configs: np.ndarray):
    """Legality (B,) and efficiency (B,) of configurations (B, n) of table rows
    ``agents`` (B,), read through the lazy lattice (illegal ones: efficiency 0, their
    steps evaluated up to the first illegal one); the efficiencies of legal ones are
    :meth:`~planners.lattice.StepTables.evaluate`'s."""
    from planners.dp import groups

    agents = np.asarray(agents, dtype=np.int64)
    configs = np.ascontiguousarray(configs, dtype=np.int64)
    legal = np.zeros(agents.size, dtype=np.bool_)
    eff = np.zeros(agents.size)
    order, starts = groups(agents)
    run_parts(_evaluate, starts.size - 1, tables.lattice, agents, order, starts, configs, legal,
              eff)
    return legal, eff


@nb.njit(cache=True, nogil=True)
def _evaluate(L, agents, order, starts, configs, legal, eff, part, parts):
    for u in range(part, starts.size - 1, parts):
        for i in range(starts[u], starts[u + 1]):
            b = order[i]
            legal[b], eff[b] = config_efficiency(L, agents[b], configs[b])


