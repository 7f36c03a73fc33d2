"""The exact in-time check of the steps a tick decided: against the neighbours'
committed steps, then between the agents deciding in the same tick.

Steering tested sampled step lengths only; here the step actually chosen is tested: the
body moving linearly along its sweep over the step's duration must stay clear, at every
instant from now on, of each neighbour moving along its own committed sweep
(:func:`crowdwalk.crowd.geometry.step_distance`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd.geometry import step_distance
from crowdwalk.crowd.steering import Neighbours

__all__ = ["clashes_with_neighbours", "same_tick_yielders"]


def clashes_with_neighbours(neighbours: Neighbours, rows: np.ndarray, *, start: np.ndarray,
                            end: np.ndarray, duration: np.ndarray, elapsed: np.ndarray,
                            radius: np.ndarray) -> np.ndarray:
    """(k,) bool: the steps of the deciders at ``rows`` (k,) of ``neighbours`` — bodies
    from ``start`` to ``end`` (k, 2) [m] over ``duration`` (k,) [s], ``elapsed`` (k,) [s]
    of it already gone, of ``radius`` (k,) [m] — come closer to a neighbour than the two
    radii."""
    gap = step_distance(start[:, None, :], end[:, None, :], duration[:, None],
                        elapsed[:, None], neighbours.now[rows], neighbours.end[rows],
                        neighbours.remaining[rows])
    return ((gap < radius[:, None] + neighbours.radius[rows])
            & neighbours.valid[rows]).any(axis=1)


def same_tick_yielders(*, agent: np.ndarray, start: np.ndarray, end: np.ndarray,
                       duration: np.ndarray, elapsed: np.ndarray, heel_strike: np.ndarray,
                       radius: np.ndarray) -> np.ndarray:
    """Indices into the k movers of one tick that yield to another mover: each checked the
    others' positions at its heel strike, not their new steps. Of two steps that would
    come too close (in time, as against the neighbours), the later heel strike (then the
    higher ``agent`` id) yields and waits.

    ``start``, ``end`` (k, 2) [m], ``duration``, ``elapsed`` (time since the heel strike
    ``heel_strike``), ``radius`` (k,) [s], [m].
    """
    mid = 0.5 * (start + end)
    half = 0.5 * np.linalg.norm(end - start, axis=1)
    tree = cKDTree(mid)
    pairs = tree.query_pairs(2 * (half.max() + radius.max()), output_type="ndarray")
    if not len(pairs):
        return np.zeros(0, dtype=np.int64)
    i, j = pairs[:, 0], pairs[:, 1]
    gone = np.minimum(elapsed, duration)
    now = start + gone[:, None] * ((end - start) / duration[:, None])  # each one now
    gap = step_distance(start[i], end[i], duration[i], elapsed[i], now[j], end[j],
                        (duration - gone)[j])
    bad = gap < radius[i] + radius[j]
    if not bad.any():
        return np.zeros(0, dtype=np.int64)
    later = np.where((heel_strike[i] > heel_strike[j])
                     | ((heel_strike[i] == heel_strike[j]) & (agent[i] > agent[j])), i, j)
    return np.unique(later[bad])
