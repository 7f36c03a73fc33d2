"""commit._advance (take_steps' state update as a kernel) against the numpy formulation it
replaced, bit for bit, on random states."""

import math

import numpy as np

from crowdwalk.crowd.commit import _advance, swing_bezier
from crowdwalk.crowd.state import AgentState


def _numpy_arctan2_is_libm() -> bool:
    """Whether numpy's arctan2 is the C library's atan2 (the kernel's) on this CPU; numpy's
    AVX-512 builds use their own vectorised arctan2, which differs by an ulp in some values."""
    rng = np.random.default_rng(0)
    y, x = rng.normal(size=(2, 10_000))
    return all(v == math.atan2(b, c) for v, b, c in zip(np.arctan2(y, x), y, x, strict=True))


#: heading bit for bit where numpy's arctan2 is libm's, else within one ulp (the rest bitwise)
ARCTAN2_IS_LIBM = _numpy_arctan2_is_libm()


def _left(d):
    return np.stack([-d[..., 1], d[..., 0]], axis=-1)


def _numpy_update(st, anchor, a, L, H, d, t0, duration, yaw, energy, fhw):
    """take_steps' state update as numpy arrays (crowdwalk before the kernel)."""
    new_c = st.stance[a] + L[:, None] * d
    new_z = st.stance_z[a] + H
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
    foothold = new_c + (side * fhw)[:, None] * _left(d)
    st.trail[a], st.trail_z[a] = st.stance[a], st.stance_z[a]
    st.stance[a], st.stance_z[a] = new_c, new_z
    anchor[a] = new_c
    st.foot[a] = 1 - foot
    st.steps[a] += 1
    st.energy[a] += energy
    st.climb[a] += np.maximum(H, 0.0)
    st.stuck[a] = 0.0
    start = st.stance_foot[a].copy()
    target = np.column_stack([foothold, new_z])
    st.stance_foot[a] = target
    return foot, side, foothold, start, target


def _random_state(rng, n):
    st = AgentState(n)
    for value in vars(st).values():
        if value.dtype.kind == "f":
            value[...] = rng.normal(0.0, 20.0, value.shape)
    st.foot[:] = rng.integers(0, 2, n)
    st.steps[:] = rng.integers(0, 100, n)
    return st


def test_advance_is_the_numpy_update_bit_for_bit():
    rng = np.random.default_rng(7)
    n, k = 500, 300
    for trial in range(5):
        ref = _random_state(np.random.default_rng(trial), n)
        got = _random_state(np.random.default_rng(trial), n)
        anchor_ref, anchor_got = np.zeros((n, 2)), np.zeros((n, 2))
        a = rng.choice(n, k, replace=False).astype(np.int64)
        ang = rng.uniform(-np.pi, np.pi, k)
        d = np.column_stack([np.cos(ang), np.sin(ang)])
        L, H = rng.uniform(0.0, 1.0, k), rng.normal(0.0, 0.1, k)
        H[:5] = [0.0, -0.0, 1e-300, -1e-300, 0.17]
        t0, dur = rng.uniform(0, 10, k), rng.uniform(0.3, 0.7, k)
        yaw, energy, fhw = rng.normal(0, 3, k), rng.uniform(0, 2, k), rng.uniform(0, 0.1, k)
        want = _numpy_update(ref, anchor_ref, a, L, H, d, t0, dur, yaw, energy, fhw)
        out = (np.empty(k, got.foot.dtype), np.empty(k), np.empty((k, 2)), np.empty((k, 3)),
               np.empty((k, 3)))
        _advance(a, L, H, d, t0, dur, yaw, energy, fhw, got.stance, got.stance_z, got.pos0,
                 got.pos1, got.z0, got.z1, got.t0, got.t1, got.heading, got.yaw0, got.yaw1,
                 got.trail, got.trail_z, got.foot, got.stance_foot, anchor_got, got.steps,
                 got.distance, got.energy, got.climb, got.stuck, *out)
        for w, o in zip(want, out, strict=True):
            assert w.dtype == o.dtype
            np.testing.assert_array_equal(w, o, strict=True)
        np.testing.assert_array_equal(anchor_ref, anchor_got, strict=True)
        for name, value in vars(ref).items():
            if name == "heading" and not ARCTAN2_IS_LIBM:
                np.testing.assert_array_max_ulp(value, got.heading, maxulp=1)
                continue
            assert value.tobytes() == getattr(got, name).tobytes(), name


def _numpy_bezier(swing, *, stance, stance_z, direction, lateral):
    """swing_bezier as numpy arrays (crowdwalk before the kernel)."""
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


def test_swing_bezier_is_the_numpy_formulation_bit_for_bit():
    rng = np.random.default_rng(3)
    k = 400
    swing = rng.normal(0.0, 0.4, (k, 4, 2))
    swing[::7] = np.nan  # the planner gave none
    swing[3, 2, 1] = np.inf
    swing[5, 0, 0] = np.nan  # one point missing: no curve
    ang = rng.uniform(-np.pi, np.pi, k)
    args = dict(stance=rng.normal(0, 30, (k, 2)), stance_z=rng.normal(0, 2, k),
                direction=np.column_stack([np.cos(ang), np.sin(ang)]),
                lateral=rng.choice([-1.0, 1.0], k) * rng.uniform(0, 0.1, k))
    want = _numpy_bezier(swing, **args)
    got = swing_bezier(swing, **args)
    assert np.isnan(got[5]).all() and np.isnan(got[3]).all() and np.isfinite(got[1]).all()
    assert want.tobytes() == got.tobytes()
