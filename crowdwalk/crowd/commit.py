"""Taking the decided steps: the agents' state moves on, and the steps leave as one
:class:`~crowdwalk.steps.StepBatch`.

Between heel strikes the body (the midpoint between the two feet's centre-line
footholds) moves linearly from its position at the heel strike to the midpoint after the
new foothold.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from crowdwalk.steps import StepBatch

__all__ = ["take_steps", "swing_bezier"]


def swing_bezier(swing: np.ndarray, *, stance: np.ndarray, stance_z: np.ndarray,
                 direction: np.ndarray, lateral: np.ndarray) -> np.ndarray:
    """The planner's swing-ankle Bezier (k, 4, 2) in (s, z) relative to the stance ankle
    at ``stance`` (k, 2), ``stance_z`` (k,) [m], along ``direction`` (k, 2), offset
    ``lateral`` (k,) [m] to the left, as world xyz control points (k, 4, 3) [m] (rows of
    NaN without one)."""
    bez = np.full((swing.shape[0], 4, 3), np.nan)
    f = np.ascontiguousarray
    _bezier(f(swing, float), f(stance, float), f(stance_z, float), f(direction, float),
            f(lateral, float), bez)
    return bez


@nb.njit(cache=True, nogil=True)
def _bezier(swing, stance, stance_z, d, lateral, bez):
    """:func:`swing_bezier` row by row into ``bez`` (k, 4, 3) (NaN already): the rows
    whose four control points are all finite, by the numpy formulation's operations."""
    for r in range(swing.shape[0]):
        has = True
        for j in range(4):
            for c in range(2):
                if not np.isfinite(swing[r, j, c]):
                    has = False
        if not has:
            continue
        lx, ly = lateral[r] * -d[r, 1], lateral[r] * d[r, 0]  # lateral · left(d)
        for j in range(4):
            s_, z_ = swing[r, j, 0], swing[r, j, 1]
            bez[r, j, 0] = stance[r, 0] + s_ * d[r, 0] + lx
            bez[r, j, 1] = stance[r, 1] + s_ * d[r, 1] + ly
            bez[r, j, 2] = stance_z[r] + z_


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
    st, a = state, np.ascontiguousarray(agents, dtype=np.int64)
    d = np.ascontiguousarray(direction, dtype=float)
    L, H = plan.length, plan.rise
    t0 = start_time
    k = a.size
    foot, side = np.empty(k, st.foot.dtype), np.empty(k)
    foothold, start, target = np.empty((k, 2)), np.empty((k, 3)), np.empty((k, 3))
    _advance(a, _f(L), _f(H), d, _f(t0), _f(duration), _f(yaw), _f(plan.energy),
             _f(foot_half_width), st.stance, st.stance_z, st.pos0, st.pos1, st.z0, st.z1,
             st.t0, st.t1, st.heading, st.yaw0, st.yaw1, st.trail, st.trail_z, st.foot,
             st.stance_foot, queue.anchor, st.steps, st.distance, st.energy, st.climb,
             st.stuck, foot, side, foothold, start, target)
    # stepped over: at most one longest step (1.05 leg lengths) along the direction
    stride = 1.05 * legs.of(a).length
    kind, on_obstacle = (terrain.footing(foothold, d, stride=stride) if threads is None else
                         threads.map(terrain.footing, a.size, foothold, d, stride=stride,
                                     light=True))
    pop = population
    return StepBatch(
        agent=a, step=st.steps[a].copy(), start_time=t0, duration=duration, foot=foot,
        start=start, target=target, stance_centre=st.trail[a].copy(),
        heading=st.heading[a].copy(), length=L, rise=H, energy=plan.energy,
        planner=_names(pop.planner_names, pop.group[a]),
        group=_names(pop.group_names, pop.group[a]),
        swing_bezier=swing_bezier(plan.swing, stance=st.trail[a], stance_z=st.trail_z[a],
                                  direction=d, lateral=side * foot_half_width),
        kind=kind, on_obstacle=on_obstacle, toe_out=turn.toe_out, spin=turn.spin)


def _names(names: tuple[str, ...], group: np.ndarray) -> np.ndarray:
    """The name of each row's group (k,) str: ``names`` (one per group) at ``group`` (k,)
    (``Population.planner[a].astype(str)`` without gathering every agent's)."""
    return np.asarray(names, dtype=object)[group].astype(str)


def _f(x) -> np.ndarray:
    """``x`` as a contiguous float array (one kernel signature)."""
    return np.ascontiguousarray(x, dtype=float)


@nb.njit(cache=True, nogil=True)
def _advance(a, length, rise, d, t0, duration, yaw, energy, half_width, stance, stance_z,
             pos0, pos1, z0, z1, s_t0, s_t1, heading, yaw0, yaw1, trail, trail_z, foot,
             stance_foot, anchor, steps, distance, s_energy, climb, stuck, o_foot, o_side,
             o_foothold, o_start, o_target):
    """:func:`take_steps`' state update, row by row (the distinct agents ``a`` (k,)): the
    new stance centre ``stance + length d`` and height ``stance_z + rise``, the body from
    its position to the midpoint of the two feet, the feet swapped. Writes the swinging
    foot ``o_foot`` (k,), its side ``o_side`` (+1 left, -1 right), its foothold
    ``o_foothold`` (k, 2) [m], and the stance foot's foothold before (``o_start``) and
    after (``o_target``) (k, 3) [m]. The same operations as the numpy formulation it
    replaces (the body's distance ``sqrt(dx dx + dy dy)`` is ``np.linalg.norm``'s)."""
    for r in range(a.size):
        i = a[r]
        cx = stance[i, 0] + length[r] * d[r, 0]
        cy = stance[i, 1] + length[r] * d[r, 1]
        cz = stance_z[i] + rise[r]
        ex = 0.5 * (stance[i, 0] + cx)
        ey = 0.5 * (stance[i, 1] + cy)
        dx, dy = ex - pos1[i, 0], ey - pos1[i, 1]
        distance[i] += np.sqrt(dx * dx + dy * dy)
        pos0[i, 0], pos0[i, 1] = pos1[i, 0], pos1[i, 1]
        z0[i] = z1[i]
        pos1[i, 0], pos1[i, 1] = ex, ey
        z1[i] = 0.5 * (stance_z[i] + cz)
        s_t0[i] = t0[r]
        s_t1[i] = t0[r] + duration[r]
        heading[i] = np.arctan2(d[r, 1], d[r, 0])
        yaw0[i] = yaw1[i]
        yaw1[i] = yaw[r]
        f = foot[i]
        side = 1.0 if f == 0 else -1.0
        w = side * half_width[r]
        fx = cx + w * -d[r, 1]
        fy = cy + w * d[r, 0]
        trail[i, 0], trail[i, 1], trail_z[i] = stance[i, 0], stance[i, 1], stance_z[i]
        stance[i, 0], stance[i, 1], stance_z[i] = cx, cy, cz
        anchor[i, 0], anchor[i, 1] = cx, cy
        foot[i] = 1 - f
        steps[i] += 1
        s_energy[i] += energy[r]
        h = rise[r]
        climb[i] += h if not h < 0.0 else 0.0  # np.maximum(h, 0.0), NaN and -0.0 kept
        stuck[i] = 0.0
        for c in range(3):
            o_start[r, c] = stance_foot[i, c]
        stance_foot[i, 0], stance_foot[i, 1], stance_foot[i, 2] = fx, fy, cz
        o_target[r, 0], o_target[r, 1], o_target[r, 2] = fx, fy, cz
        o_foot[r] = f
        o_side[r] = side
        o_foothold[r, 0], o_foothold[r, 1] = fx, fy
