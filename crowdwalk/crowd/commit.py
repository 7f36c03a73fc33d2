"""Taking the decided steps: the agents' state moves on, and the steps leave as one
:class:`~crowdwalk.steps.StepBatch`.

Between heel strikes the body (the midpoint between the two feet's centre-line
footholds) moves linearly from its position at the heel strike to the midpoint after the
new foothold.
"""

from __future__ import annotations

import numpy as np

from crowdwalk.steps import StepBatch

__all__ = ["take_steps", "swing_bezier"]


def _left(d: np.ndarray) -> np.ndarray:
    return np.stack([-d[..., 1], d[..., 0]], axis=-1)


def swing_bezier(swing: np.ndarray, *, stance: np.ndarray, stance_z: np.ndarray,
                 direction: np.ndarray, lateral: np.ndarray) -> np.ndarray:
    """The planner's swing-ankle Bezier (k, 4, 2) in (s, z) relative to the stance ankle
    at ``stance`` (k, 2), ``stance_z`` (k,) [m], along ``direction`` (k, 2), offset
    ``lateral`` (k,) [m] to the left, as world xyz control points (k, 4, 3) [m] (rows of
    NaN without one)."""
    d = direction
    bez = np.full((swing.shape[0], 4, 3), np.nan)
    has = np.all(np.isfinite(swing), axis=(1, 2))
    if has.any():
        lat = lateral[has][:, None] * _left(d[has])
        s_, z_ = swing[has, :, 0], swing[has, :, 1]
        bez[has, :, :2] = (stance[has, None, :] + s_[..., None] * d[has, None, :]
                           + lat[:, None, :])
        bez[has, :, 2] = stance_z[has, None] + z_
    return bez


def take_steps(state, queue, *, agents: np.ndarray, start_time: np.ndarray,
               direction: np.ndarray, yaw: np.ndarray, plan, duration: np.ndarray, terrain,
               legs, population, foot_half_width, turn, threads=None) -> StepBatch:
    """Start the steps ``plan`` (a :class:`~crowdwalk.crowd.stepping.StepPlan` of k rows)
    of ``agents`` (k,) at ``start_time`` (k,) [s] along unit ``direction`` (k, 2), lasting
    ``duration`` (k,) [s], the torso turning to face ``yaw`` (k,) [rad] (unwrapped against
    its facing now), oriented by MetaGait's ``turn``
    (:class:`~crowdwalk.gait.metagait.StepTurn`): ``state`` moves on (in place; the plan
    queue's anchor is the new stance) and the steps are returned. ``threads`` (a
    :class:`crowdwalk.workers.RowThreads`, optional) finds the footings of parts of the
    steps at once."""
    st, a, d = state, agents, direction
    L, H = plan.length, plan.rise
    new_c = st.stance[a] + L[:, None] * d
    new_z = st.stance_z[a] + H
    t0 = start_time
    end = 0.5 * (st.stance[a] + new_c)
    st.distance[a] += np.linalg.norm(end - st.pos1[a], axis=1)
    st.pos0[a] = st.pos1[a]
    st.z0[a] = st.z1[a]
    st.pos1[a] = end
    st.z1[a] = 0.5 * (st.stance_z[a] + new_z)
    st.t0[a] = t0
    st.t1[a] = t0 + duration
    st.heading[a] = np.arctan2(d[:, 1], d[:, 0])
    st.yaw0[a] = st.yaw1[a]
    st.yaw1[a] = yaw
    foot = st.foot[a].copy()
    side = np.where(foot == 0, 1.0, -1.0)
    foothold = new_c + (side * foot_half_width)[:, None] * _left(d)
    st.trail[a], st.trail_z[a] = st.stance[a], st.stance_z[a]
    st.stance[a], st.stance_z[a] = new_c, new_z
    queue.anchor[a] = new_c
    st.foot[a] = 1 - foot
    st.steps[a] += 1
    st.energy[a] += plan.energy
    st.climb[a] += np.maximum(H, 0.0)
    st.stuck[a] = 0.0
    start = st.stance_foot[a].copy()
    target = np.column_stack([foothold, new_z])
    st.stance_foot[a] = target
    # stepped over: at most one longest step (1.05 leg lengths) along the direction
    stride = 1.05 * legs.of(a).length
    kind, on_obstacle = (terrain.footing(foothold, d, stride=stride) if threads is None else
                         threads.map(terrain.footing, a.size, foothold, d, stride=stride))
    pop = population
    return StepBatch(
        agent=a, step=st.steps[a].copy(), start_time=t0, duration=duration, foot=foot,
        start=start, target=target, stance_centre=st.trail[a].copy(),
        heading=st.heading[a].copy(), length=L, rise=H, energy=plan.energy,
        planner=pop.planner[a].astype(str),
        group=np.asarray(pop.group_names, dtype=object)[pop.group[a]].astype(str),
        swing_bezier=swing_bezier(plan.swing, stance=st.trail[a], stance_z=st.trail_z[a],
                                  direction=d, lateral=side * foot_half_width),
        kind=kind, on_obstacle=on_obstacle, toe_out=turn.toe_out, spin=turn.spin)
