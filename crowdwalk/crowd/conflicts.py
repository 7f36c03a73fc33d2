"""The exact in-time check of the steps a tick decided: against the neighbours'
committed steps, then between the agents deciding in the same tick.

Steering tested sampled step lengths only; here the step actually chosen is tested: the
outline moving linearly along its sweep over the step's duration (its torso turning
linearly) must stay clear, at every instant from now on, of each neighbour moving along
its own committed sweep (:func:`crowdwalk.crowd.shape.body_gaps`).
"""

from __future__ import annotations

import numba as nb
import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd.shape import FAR_MARGIN, _gaps, _segment_distance, body_gaps
from crowdwalk.crowd.steering import Neighbours

__all__ = ["clashes_with_neighbours", "same_tick_yielders"]


def clashes_with_neighbours(neighbours: Neighbours, rows: np.ndarray, *, start: np.ndarray,
                            end: np.ndarray, duration: np.ndarray, elapsed: np.ndarray,
                            yaw: np.ndarray, yaw_end: np.ndarray,
                            shape: np.ndarray) -> np.ndarray:
    """(k,) bool: the steps of the deciders at ``rows`` (k,) of ``neighbours`` — bodies
    from ``start`` to ``end`` (k, 2) [m] over ``duration`` (k,) [s], ``elapsed`` (k,) [s]
    of it already gone, turning from ``yaw`` to ``yaw_end`` (k,) [rad], of outline
    ``shape`` (k, 3) — come closer to a neighbour than touching."""
    f = np.ascontiguousarray
    clash = np.zeros(rows.size, bool)
    if rows.size == 0 or neighbours.valid.shape[1] == 0:
        return clash
    yaw_now, yaw_end_nb = neighbours.yaws()
    _clashes(f(rows, np.int64), f(neighbours.valid, bool), f(start, float), f(yaw, float),
             f(end, float)[:, None, :], f(yaw_end, float)[:, None], f(duration, float)[:, None],
             f(elapsed, float), f(shape, float), f(neighbours.now, float), f(yaw_now, float),
             f(neighbours.end, float), f(yaw_end_nb, float), f(neighbours.remaining, float),
             f(neighbours.outlines(), float), clash)
    return clash


@nb.njit(cache=True, nogil=True)
def _clashes(rows, valid, start, yaw, end, yaw_end, duration, elapsed, shape, nb_now,
             nb_yaw_now, nb_end, nb_yaw_end, nb_remaining, nb_shape, clash):
    """``clash`` (k,): whether the step of each of the k deciders at ``rows`` of the
    neighbour arrays (m, K, ...) comes closer than touching to one of its ``valid``
    neighbours (:func:`~crowdwalk.crowd.shape.body_gaps` of the step against them, one
    decider at a time; the a-arrays have k rows, one candidate each). A neighbour whose
    sweep keeps clear of the decider's by the two holding discs (``FAR_MARGIN`` to
    spare) is not evaluated: ``body_gaps`` gives it a gap >= 0 then (the centres'
    approach is at least the sweeps' distance)."""
    n_k = valid.shape[1]
    pa = np.zeros(n_k, np.int64)
    b_now, b_end = np.empty((n_k, 2)), np.empty((n_k, 2))
    b_yaw_now, b_yaw_end, b_remaining = np.empty(n_k), np.empty(n_k), np.empty(n_k)
    b_shape = np.empty((n_k, 3))
    out, out_centre = np.empty((n_k, 1)), np.empty((n_k, 1))
    no = np.ones((0, 0), np.bool_)
    for q in range(rows.shape[0]):
        r = rows[q]
        hold_a = max(shape[q, 0], shape[q, 2] + shape[q, 1])
        n = 0
        for k in range(n_k):
            if not valid[r, k]:
                continue
            bound = hold_a + max(nb_shape[r, k, 0], nb_shape[r, k, 2] + nb_shape[r, k, 1])
            far = _segment_distance(start[q, 0], start[q, 1], end[q, 0, 0], end[q, 0, 1],
                                    nb_now[r, k, 0], nb_now[r, k, 1], nb_end[r, k, 0],
                                    nb_end[r, k, 1], False)
            if far - bound >= FAR_MARGIN:
                continue
            b_now[n], b_end[n], b_shape[n] = nb_now[r, k], nb_end[r, k], nb_shape[r, k]
            b_yaw_now[n], b_yaw_end[n] = nb_yaw_now[r, k], nb_yaw_end[r, k]
            b_remaining[n] = nb_remaining[r, k]
            n += 1
        if n == 0:
            continue
        one = slice(q, q + 1)
        _gaps(pa[:n], start[one], yaw[one], end[one], yaw_end[one], duration[one],
              elapsed[one], shape[one], b_now[:n], b_yaw_now[:n], b_end[:n], b_yaw_end[:n],
              b_remaining[:n], b_shape[:n], 0, no, no, out[:n], out_centre[:n])
        for p in range(n):
            if out[p, 0] < 0.0:
                clash[q] = True
                break


def same_tick_yielders(*, agent: np.ndarray, start: np.ndarray, end: np.ndarray,
                       duration: np.ndarray, elapsed: np.ndarray, heel_strike: np.ndarray,
                       yaw: np.ndarray, yaw_end: np.ndarray, shape: np.ndarray) -> np.ndarray:
    """Indices into the k movers of one tick that yield to another mover: each checked the
    others' positions at its heel strike, not their new steps. Of two steps that would
    come too close (in time, as against the neighbours), the later heel strike (then the
    higher ``agent`` id) yields and waits.

    ``start``, ``end`` (k, 2) [m], ``duration``, ``elapsed`` (time since the heel strike
    ``heel_strike``) (k,) [s], torso ``yaw`` now and ``yaw_end`` (k,) [rad], outlines
    ``shape`` (k, 3).
    """
    mid = 0.5 * (start + end)
    half = 0.5 * np.linalg.norm(end - start, axis=1)
    bound = np.maximum(shape[:, 0], shape[:, 1] + shape[:, 2])
    tree = cKDTree(mid)
    pairs = tree.query_pairs(2 * (half.max() + bound.max()), output_type="ndarray")
    if not len(pairs):
        return np.zeros(0, dtype=np.int64)
    i, j = pairs[:, 0], pairs[:, 1]
    gone = np.minimum(elapsed, duration)
    f = gone / np.where(duration > 0, duration, 1.0)
    now = start + f[:, None] * (end - start)  # each one now
    yaw_now = yaw + f * (yaw_end - yaw)
    gap = body_gaps(i, a_start=start, a_yaw0=yaw, a_end=end[:, None, :],
                    a_yaw1=yaw_end[:, None], a_duration=duration[:, None], a_elapsed=elapsed,
                    a_shape=shape, b_now=now[j], b_yaw_now=yaw_now[j], b_end=end[j],
                    b_yaw_end=yaw_end[j], b_remaining=(duration - gone)[j],
                    b_shape=shape[j])[0][:, 0]
    bad = gap < 0.0
    if not bad.any():
        return np.zeros(0, dtype=np.int64)
    later = np.where((heel_strike[i] > heel_strike[j])
                     | ((heel_strike[i] == heel_strike[j]) & (agent[i] > agent[j])), i, j)
    return np.unique(later[bad])
