"""Agents entering the walk: who may spawn now, and their first placement."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd.geometry import segment_distance
from crowdwalk.crowd.state import ACTIVE

__all__ = ["free_to_spawn", "place"]


def _left(d: np.ndarray) -> np.ndarray:
    return np.stack([-d[..., 1], d[..., 0]], axis=-1)


def free_to_spawn(state, due: np.ndarray, *, t: float, walkers: np.ndarray, xy: np.ndarray,
                  radius: np.ndarray) -> np.ndarray:
    """(k,) bool: the agents ``due`` (k,) to spawn at ``xy`` (k, 2) [m] at time ``t`` [s]
    whose bodies are clear of the walking agents' (``walkers``) remaining sweeps (nearest
    16) and of the agents due before them (lower index) in the same tick; ``radius``
    (n,) [m] every agent's."""
    st = state
    free = np.ones(due.size, bool)
    r_max = float(radius.max())
    if walkers.size:
        now, _ = st.position(t, walkers)
        k = min(16, walkers.size)
        reach = 1.0 + 2 * r_max
        _, nb = cKDTree(0.5 * (now + st.pos1[walkers])).query(
            xy, k=k, distance_upper_bound=reach)
        nb = np.asarray(nb).reshape(due.size, k)
        valid = nb < walkers.size
        j = walkers[np.where(valid, nb, 0)]
        d = segment_distance(xy[:, None, :], xy[:, None, :], now[np.where(valid, nb, 0)],
                             st.pos1[j])
        free = np.all((d >= radius[due][:, None] + radius[j]) | ~valid, axis=1)
    cand = np.flatnonzero(free)
    if cand.size > 1:
        pairs = cKDTree(xy[cand]).query_pairs(2 * r_max, output_type="ndarray")
        if len(pairs):
            i, j = cand[pairs[:, 0]], cand[pairs[:, 1]]
            clash = (np.linalg.norm(xy[i] - xy[j], axis=1)
                     < radius[due[i]] + radius[due[j]])
            free[np.maximum(i, j)[clash]] = False
    return free


def place(state, agents: np.ndarray, *, t: float, xy: np.ndarray, z: np.ndarray, table,
          foot_half_width) -> None:
    """Start ``agents`` (k,) walking at time ``t`` [s], feet together at ``xy`` (k, 2),
    ground height ``z`` (k,) [m], facing 1 m ahead along their route (``table``); the
    left foot swings first."""
    st, idx, p = state, agents, xy
    st.status[idx] = ACTIVE
    st.pos0[idx] = st.pos1[idx] = p
    st.z0[idx] = st.z1[idx] = z
    st.stance[idx] = st.trail[idx] = p
    st.stance_z[idx] = st.trail_z[idx] = z
    st.foot[idx] = 0  # the left foot swings first; the right one stands
    st.t0[idx] = st.t1[idx] = t
    st.start_time[idx] = t
    st.progress_time[idx] = t
    st.gain_time[idx] = t
    seg, s, _ = table.project(st.route[idx], st.segment[idx], p)
    st.segment[idx], st.progress[idx] = seg, s
    ahead = table.point_at(st.route[idx], s + 1.0)
    d = ahead - p
    st.heading[idx] = np.arctan2(d[:, 1], d[:, 0])
    st.yaw0[idx] = st.yaw1[idx] = st.heading[idx]
    right = -_left(np.column_stack([np.cos(st.heading[idx]), np.sin(st.heading[idx])]))
    st.stance_foot[idx] = np.column_stack([p + np.asarray(foot_half_width)[..., None] * right,
                                           z])
