"""Agents that do not step this tick: they stand for ``wait_time`` and decide again.

Standing still brings the feet together under the body where the whole foot, heel to
toe, rests on even ground there (so the next step may go any way); where it cannot (the
body over an edge), a walker held up for a while shifts its weight to the other foot, so
that its next step may start from there (e.g. a step back off a curb).
"""

from __future__ import annotations

import numpy as np

__all__ = ["stand"]


def stand(state, queue, *, agents: np.ndarray, t: float, terrain, legs, params,
          wake: np.ndarray | None = None) -> None:
    """Let ``agents`` (k,) stand from their heel strike until ``t + wait_time`` [s], or
    until ``wake`` (k,) [s] where that is sooner (``wake_on_step``) (``state`` updated in
    place; their queued plans are dropped). ``legs`` is the crowd's
    :class:`~crowdwalk.crowd.legs.LegTable`, ``params`` its ``CrowdParams``."""
    st, wait = state, agents
    queue.clear(wait)
    st.pos0[wait] = st.pos1[wait]
    st.z0[wait] = st.z1[wait]
    st.yaw0[wait] = st.yaw1[wait]
    st.t0[wait] = st.t1[wait]
    end = t + params.wait_time
    st.t1[wait] = end if wake is None else np.minimum(wake, end)
    apart = wait[np.linalg.norm(st.stance[wait] - st.trail[wait], axis=1) > 1e-6]
    if apart.size:
        here = st.pos1[apart]
        d = np.column_stack([np.cos(st.heading[apart]), np.sin(st.heading[apart])])
        leg = legs.of(apart)
        heel, toe = leg.heel_offset, leg.toe_offset
        pts = np.concatenate([here - (heel + 0.03)[:, None] * d, here,
                              here + (toe + 0.03)[:, None] * d])
        z = terrain.height(pts).reshape(3, -1)
        even = np.ptp(z, axis=0) <= 0.01
        level = apart[even]
        st.stance[level] = st.trail[level] = here[even]
        st.stance_z[level] = st.trail_z[level] = z[1, even]
        swap = apart[~even & (st.stuck[apart] >= params.steering.give_way_after)]
        if swap.size:
            st.stance[swap], st.trail[swap] = st.trail[swap], st.stance[swap].copy()
            st.stance_z[swap], st.trail_z[swap] = (st.trail_z[swap],
                                                   st.stance_z[swap].copy())
            st.foot[swap] = 1 - st.foot[swap]
            queue.clear(swap)
    dur = st.t1[wait] - st.t0[wait]
    st.wait[wait] += dur
    st.stuck[wait] += dur
