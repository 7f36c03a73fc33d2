"""speed_kernels.route_lane_headway (headway_speed with lane_direction) against the numpy
formulation it replaced, bit for bit (signed zeros and NaNs included), on random walkers,
neighbours and candidate directions, with ties at the tests' thresholds."""

from __future__ import annotations

import numpy as np
import pytest

from crowdwalk.crowd.speed import headway_speed


def numpy_route_lane_headway(*, position, direction, radius, others, others_radius, valid,
                             free_speed, time_gap, lane, lane_direction, shift):
    """crowdwalk.crowd.speed._route_lane_headway as numpy arrays (before the kernel)."""
    d = direction if direction.ndim == 3 else direction[:, None, :]
    rel = (others - position[:, None, :])[:, None, :, :]  # (k, 1, m, 2)
    need = (radius[:, None] + others_radius)[:, None, :]
    e = lane_direction
    along = np.einsum("kcmj,kj->kcm", rel, e)  # (k, 1, m)
    lateral = rel[..., 0] * e[:, None, None, 1] - rel[..., 1] * e[:, None, None, 0]
    end = shift[:, None] * (d[..., 0] * e[:, None, 1] - d[..., 1] * e[:, None, 0])  # (k, C)
    ahead = (valid[:, None, :] & (along > 0)
             & (np.abs(lateral - end[:, :, None]) < lane[:, None, None]))
    gap = np.where(ahead, along - need, np.inf).min(axis=2)  # (k, C)
    forward = np.einsum("kcj,kj->kc", d, e)
    v_e = np.maximum(gap, 0.0) / time_gap
    v = np.where(forward > 1e-3, np.minimum(free_speed[:, None],
                                            v_e / np.maximum(forward, 1e-3)),
                 free_speed[:, None])
    return v if direction.ndim == 3 else v[:, 0]


def _case(rng, k, m, n_c, *, ties=False, nans=False):
    position = rng.uniform(-5, 5, (k, 2))
    others = position[:, None, :] + rng.normal(0, 1.2, (k, m, 2))
    if ties:  # neighbours on the walker, exactly abreast along e, or zero-size
        others[:, : m // 4] = position[:, None, :]
        others = np.round(others * 4) / 4
    heading = rng.uniform(-np.pi, np.pi, k)
    e = np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    if ties:  # axis-aligned routes: along and lateral exactly representable
        e[: k // 2] = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])[
            rng.integers(0, 4, k // 2)]
    off = rng.uniform(-np.pi, np.pi, (k, n_c))
    off[:, 0] = 0.0
    off[:, 1:2] = np.pi / 2  # across: d . e is zero (or a rounding of it)
    ang = heading[:, None] + off
    d = np.stack([np.cos(ang), np.sin(ang)], axis=-1)
    if ties:
        d[: k // 2] = np.where(rng.random((k // 2, n_c, 1)) < 0.5, e[: k // 2, None, :],
                               -e[: k // 2, None, :])
    radius = rng.uniform(0.15, 0.25, k)
    others_radius = rng.uniform(0.15, 0.25, (k, m))
    if ties:
        others_radius[:, ::3] = 0.25
        radius[::2] = 0.25
    valid = rng.random((k, m)) < 0.8
    free = rng.uniform(0.8, 1.8, k)
    lane = rng.uniform(0.2, 0.6, k)
    if ties:
        lane[::2] = 0.5
    shift = rng.uniform(0.0, 0.8, k)
    if ties:
        shift[::3] = 0.0
    if nans:
        others[rng.random((k, m)) < 0.05] = np.nan
        others_radius[rng.random((k, m)) < 0.05] = np.nan
        free[rng.random(k) < 0.1] = np.nan
        d[rng.random((k, n_c)) < 0.05] = np.nan
    return dict(position=position, direction=d, radius=radius, others=others,
                others_radius=others_radius, valid=valid, free_speed=free,
                time_gap=1.06, lane=lane, lane_direction=e, shift=shift)


def _same(a, b):
    assert a.shape == b.shape and a.dtype == b.dtype
    assert np.array_equal(a.view(np.uint64), b.view(np.uint64))  # bits: -0.0, NaN


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("ties, nans", [(False, False), (True, False), (False, True),
                                        (True, True)])
def test_route_lane_headway_is_the_numpy_formulation_bit_for_bit(seed, ties, nans):
    rng = np.random.default_rng(seed)
    for k, m, n_c in ((1, 1, 1), (7, 12, 11), (300, 24, 11), (50, 40, 3)):
        case = _case(rng, k, m, n_c, ties=ties, nans=nans)
        _same(headway_speed(**case), numpy_route_lane_headway(**case))
        one = dict(case, direction=case["direction"][:, 0])  # (k, 2): speeds (k,)
        _same(headway_speed(**one), numpy_route_lane_headway(**one))


def test_route_lane_headway_without_neighbours_is_the_free_speed():
    """No neighbours (the numpy formulation's min has no identity there)."""
    rng = np.random.default_rng(9)
    case = _case(rng, 20, 6, 5)
    case.update(others=case["others"][:, :0], others_radius=case["others_radius"][:, :0],
                valid=case["valid"][:, :0])
    v = headway_speed(**case)
    assert np.array_equal(v, np.broadcast_to(case["free_speed"][:, None], v.shape))


def test_route_lane_headway_slows_for_a_leader_in_the_lane_only():
    """A leader 1 m ahead in the route lane limits the speed to (1 − 0.36) / 1.06 along
    the route; moved out of the lane (or behind) it does not."""
    base = dict(position=np.zeros((1, 2)), direction=np.array([[1.0, 0.0]]),
                radius=np.array([0.18]), others_radius=np.array([[0.18]]),
                valid=np.array([[True]]), free_speed=np.array([1.4]), time_gap=1.06,
                lane=np.array([0.3]), lane_direction=np.array([[1.0, 0.0]]),
                shift=np.array([0.0]))
    v = headway_speed(others=np.array([[[1.0, 0.0]]]), **base)
    assert v[0] == pytest.approx((1.0 - 0.36) / 1.06)
    for where in ([1.0, 0.5], [-1.0, 0.0]):
        assert headway_speed(others=np.array([[where]]), **base)[0] == 1.4
