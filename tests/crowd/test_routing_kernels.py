"""routing_kernels.steering_rows (steering_targets and lane_runs_into_wall as one kernel)
against the numpy formulation it replaced, bit for bit, on random route tables, walls and
walkers (targets hit exactly, at route ends and beyond, still walkers, NaN rows)."""

from __future__ import annotations

from dataclasses import replace

import numba as nb
import numpy as np
import pytest
import shapely

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.navigation import RouteTable
from crowdwalk.crowd.params import CrowdParams
from crowdwalk.crowd.routing import lane_runs_into_wall, steering_targets
from crowdwalk.crowd.routing_kernels import _point_at


def _unit(v):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 1e-12, n, 1.0)


def _first_clear(target, blind, b, candidates, clear):
    found = np.zeros(b.size, bool)
    for cand in candidates:
        ok = ~found & clear(cand)
        target[b[ok]] = cand[ok]
        found |= ok
    blind[b[found]] = False


def _lane(table, route, progress, xy, radius, clearance, params):
    on_route = table.point_at(route, progress)
    ahead = table.point_at(route, progress + params.target_distance)
    target = xy + (ahead - on_route) + params.centre_pull * (on_route - xy)
    blind = clearance(target) < radius
    blind |= clearance(0.5 * (target + xy)) < radius
    return ahead, target, blind


def numpy_steering_targets(table, *, route, progress, xy, heading, radius, clearance, params):
    """crowdwalk.crowd.routing.steering_targets as numpy arrays (before the kernel)."""
    ahead, target, blind = _lane(table, route, progress, xy, radius, clearance, params)
    b = np.flatnonzero(blind)
    if b.size and params.lane_keep:
        u = target[b] - ahead[b]
        size = np.maximum(np.linalg.norm(u, axis=1), 1e-9)
        xb, rb = xy[b], radius[b]
        _first_clear(target, blind, b, (
            ahead[b] + u * np.minimum(1.0, cap / size)[:, None]
            for cap in (0.6, 0.45, 0.3, 0.2, 0.1)),
            lambda cand: (clearance(cand) >= rb) & (clearance(0.5 * (cand + xb)) >= rb))
    b = np.flatnonzero(blind)
    if b.size and params.line_up:
        xb, rb = xy[b], radius[b]

        def clear(cand):
            ok = (clearance(cand) >= rb) & (np.linalg.norm(cand - xb, axis=1) >= rb)
            for f in (0.25, 0.5, 0.75):
                ok &= clearance(xb + f * (cand - xb)) >= rb
            return ok

        _first_clear(target, blind, b, (table.point_at(route[b], progress[b] + reach)
                                        for reach in (1.5, 1.0, 0.6, 0.3, 0.0)), clear)
    target[blind] = ahead[blind]
    direction = _unit(target - xy)
    still = np.linalg.norm(target - xy, axis=1) < 1e-9
    heading_dir = np.column_stack([np.cos(heading), np.sin(heading)])
    direction[still] = heading_dir[still]
    return target, direction


def _world(rng):
    """A room with random pillars and door-like walls, and a table of random routes
    through it (some with collinear and very short segments)."""
    area = shapely.box(0, 0, 20, 12)
    for _ in range(rng.integers(3, 9)):
        x, y = rng.uniform(1, 19), rng.uniform(1, 11)
        w, h = rng.uniform(0.1, 3), rng.uniform(0.1, 3)
        area = area.difference(shapely.box(x, y, x + w, y + h))
    table = RouteTable()
    for _ in range(rng.integers(1, 6)):
        k = int(rng.integers(2, 8))
        line = rng.uniform([0, 0], [20, 12], size=(k, 2))
        if k > 2 and rng.random() < 0.5:
            line[1] = line[0] + 1e-7 * rng.normal(size=2)  # a (dropped) tiny segment
        table.add(line)
    return ClearanceField.from_area(area, cell=0.1), table


def _walkers(rng, table, k):
    route = rng.integers(0, len(table), size=k)
    s0, s1 = table.s0[route], table.s1[route]
    progress = rng.uniform(s0 - 1.0, s1 + 1.0)
    pick = rng.random(k)
    v = rng.integers(0, table.s.size, size=k)  # exactly on a vertex (of any route)
    progress = np.where(pick < 0.15, table.s[v], progress)
    progress = np.where((pick >= 0.15) & (pick < 0.25), s1 - 2.0, progress)  # the end ahead
    on = table.point_at(route, progress)
    xy = on + rng.normal(scale=0.8, size=(k, 2))
    heading = rng.uniform(-np.pi, np.pi, size=k)
    radius = rng.uniform(0.15, 0.3, size=k)
    return route, progress, xy, heading, radius


def _same(a, b):
    assert a.shape == b.shape
    assert np.array_equal(a, b, equal_nan=True)
    assert np.array_equal(np.signbit(a), np.signbit(b))


def _case(seed, lane_keep, line_up):
    rng = np.random.default_rng(seed)
    field, table = _world(rng)
    k = 400
    route, progress, xy, heading, radius = _walkers(rng, table, k)
    params = replace(CrowdParams(), lane_keep=lane_keep, line_up=line_up,
                     target_distance=float(rng.choice([2.0, 1.0, 0.0])),
                     centre_pull=float(rng.choice([0.1, 0.0, 1.0])))
    if params.target_distance == 0.0 and params.centre_pull == 1.0:
        # walkers standing at their target (the direction is the heading)
        xy[:40] = table.point_at(route[:40], progress[:40])
    return table, dict(route=route, progress=progress, xy=xy, heading=heading,
                       radius=radius, clearance=field, params=params)


MODES = [(False, False), (True, False), (False, True), (True, True)]


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("lane_keep,line_up", MODES)
def test_steering_targets_are_the_numpy_code(seed, lane_keep, line_up):
    table, args = _case(seed, lane_keep, line_up)
    t0, d0 = numpy_steering_targets(table, **args)
    t1, d1 = steering_targets(table, **args)
    _same(t1, t0)
    _same(d1, d0)
    blind = _lane(table, args["route"], args["progress"], args["xy"], args["radius"],
                  args["clearance"], args["params"])[2]
    walled = lane_runs_into_wall(table, **{k: v for k, v in args.items() if k != "heading"})
    assert np.array_equal(walled, blind)


def test_the_random_cases_take_every_branch():
    """Lanes into walls and clear ones, lane keeping and lining up changing targets, and
    walkers at their targets all occur in the cases above."""
    changed = {mode: 0 for mode in MODES[1:]}
    blind_rows = still_rows = 0
    for seed in range(12):
        for mode in MODES[1:]:
            table, args = _case(seed, *mode)
            plain = replace(args["params"], lane_keep=False, line_up=False)
            t1, _ = steering_targets(table, **args)
            t2, _ = steering_targets(table, **{**args, "params": plain})
            changed[mode] += int((t1 != t2).any(axis=1).sum())
        blind = lane_runs_into_wall(table, **{k: v for k, v in args.items() if k != "heading"})
        blind_rows += int(blind.sum())
        assert not blind.all()
        still_rows += int((np.linalg.norm(t1 - args["xy"], axis=1) < 1e-9).sum())
    assert all(v > 0 for v in changed.values()), changed
    assert blind_rows > 0 and still_rows > 0


def test_nan_rows_and_points_outside_the_grid_are_the_numpy_code():
    rng = np.random.default_rng(99)
    field, table = _world(rng)
    route, progress, xy, heading, radius = _walkers(rng, table, 60)
    progress[:5] = np.nan
    xy[5:10, 0] = np.nan
    xy[10:15] += 100.0  # far outside the field
    heading[15:20] = np.nan
    params = replace(CrowdParams(), lane_keep=True, line_up=True)
    args = dict(route=route, progress=progress, xy=xy, heading=heading, radius=radius,
                clearance=field, params=params)
    t0, d0 = numpy_steering_targets(table, **args)
    t1, d1 = steering_targets(table, **args)
    _same(t1, t0)
    _same(d1, d0)


@nb.njit
def _points(s, xy, start, stop, s0, s1, route, x):
    out = np.empty((route.size, 2))
    for i in range(route.size):
        out[i, 0], out[i, 1] = _point_at(s, xy, start, stop, s0, s1, route[i], x[i])
    return out


def test_the_points_on_the_routes_are_numpys_interp():
    rng = np.random.default_rng(5)
    _, table = _world(rng)
    route, progress, *_ = _walkers(rng, table, 2000)
    progress[:20] = np.nan
    got = _points(table.s, np.ascontiguousarray(table.xy), table.start, table.stop, table.s0,
                  table.s1, route, progress)
    _same(got, table.point_at(route, progress))
