"""The neighbours' motion gathered by the kernel is what the state's numpy arithmetic
gives, bit for bit (the reference below is the gathering before the kernel)."""

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd.neighbours import gather_neighbours
from crowdwalk.crowd.shape import BodyShape
from crowdwalk.crowd.state import AgentState


def _reference(st, deciders, t, walkers, shape, k, reach):
    now, _ = st.position(t, walkers)
    me, _ = st.position(t, deciders)
    _, nb = cKDTree(now).query(me, k=k, distance_upper_bound=reach)
    valid = nb < walkers.size
    agent = walkers[np.where(valid, nb, 0)]
    valid &= agent != deciders[:, None]
    t1, span = st.t1[agent], st.t1[agent] - st.t0[agent]
    moving = (t1 > t) & (span > 0)
    vel = np.where(moving[..., None], (st.pos1[agent] - st.pos0[agent])
                   / np.where(span > 0, span, 1.0)[..., None], 0.0)
    return dict(valid=valid, now=now[np.where(nb < walkers.size, nb, 0)],
                end=st.pos1[agent], velocity=vel, heading=st.heading[agent],
                radius=shape.radius[agent], remaining=np.where(moving, t1 - t, 0.0),
                yaw_now=st.yaw(t, agent.ravel()).reshape(agent.shape), yaw_end=st.yaw1[agent],
                shape=shape.packed()[agent])


def test_gathered_motion_is_the_numpy_arithmetic_bit_for_bit():
    rng = np.random.default_rng(3)
    n = 300
    st = AgentState(n)
    st.pos0 = rng.uniform(0, 12, (n, 2))
    st.pos1 = st.pos0 + rng.uniform(-0.4, 0.4, (n, 2))
    st.t0 = rng.uniform(0, 1, n)
    st.t1 = st.t0 + np.where(rng.random(n) < 0.2, 0.0, rng.uniform(0.2, 0.7, n))
    st.heading, st.yaw0 = rng.uniform(-3, 3, n), rng.uniform(-3, 3, n)
    st.yaw1 = st.yaw0 + rng.uniform(-1, 1, n)
    shape = BodyShape.from_axes(rng.uniform(0.15, 0.2, n), rng.uniform(0.2, 0.26, n))
    walkers = np.sort(rng.choice(n, 250, replace=False))
    deciders = walkers[rng.random(walkers.size) < 0.4]
    t = 0.9
    got = gather_neighbours(st, deciders, t=t, walkers=walkers, shape=shape, count=12,
                            reach=1.5)
    want = _reference(st, deciders, t, walkers, shape, 13, 1.5)
    assert (~want["valid"]).any() and want["valid"].any()  # missing neighbours occur
    for name, value in want.items():
        np.testing.assert_array_equal(getattr(got, name), value, err_msg=name, strict=True)
        assert getattr(got, name).tobytes() == value.tobytes(), name  # -0.0 too


def _brute_force(now, me, k, reach):
    """The k nearest within ``reach``, nearest first, equal distances by index."""
    d2 = ((me[:, None, :] - now[None, :, :]) ** 2).sum(axis=2)
    out = np.full((len(me), k), len(now), np.int64)
    for r, row in enumerate(d2):
        near = np.flatnonzero(row < reach**2)
        near = near[np.lexsort((near, row[near]))][:k]
        out[r, :near.size] = near
    return out


def test_grid_finds_the_nearest_with_ties_by_index_and_far_walkers():
    """On a lattice (many equal distances), with walkers spread over 5 km (cells wider
    than the reach) and deciders outside the walkers' extent."""
    from crowdwalk.crowd.neighbours import _Grid, _nearest

    rng = np.random.default_rng(5)
    lattice = np.stack(np.meshgrid(np.arange(0, 8, 0.5), np.arange(0, 6, 0.5)), -1).reshape(-1, 2)
    far = rng.uniform(0, 5000, (400, 2))
    for now in (lattice, np.concatenate([lattice, far])):
        me = np.concatenate([now[rng.integers(0, len(now), 40)], [[-2.0, 3.0], [9.5, 6.5]],
                             rng.uniform(-10, 10, (10, 2))])
        grid = _Grid(now, 1.2)
        found = np.full((len(me), 9), len(now), np.int64)
        _nearest(me, now, grid.origin, grid.cell, grid.shape, grid.start, grid.order,
                 1.2**2, found)
        np.testing.assert_array_equal(found, _brute_force(now, me, 9, 1.2))
        assert (found < len(now)).sum(axis=1).min() == 0  # some find no one
        assert (found[:40] < len(now)).all(axis=1).any()  # and some a full list


def test_grid_bounds_are_numpys_min_and_max():
    from crowdwalk.crowd.neighbours import _bounds

    rng = np.random.default_rng(5)
    for w in (1, 2, 7, 1000):
        now = rng.normal(0.0, 50.0, (w, 2))
        lo, hi = _bounds(now)
        assert lo.tobytes() == now.min(axis=0).tobytes()
        assert hi.tobytes() == now.max(axis=0).tobytes()
    now[10, 1] = np.nan
    lo, hi = _bounds(now)
    assert lo[0] == now[:, 0].min() and np.isnan(lo[1]) and np.isnan(hi[1])
