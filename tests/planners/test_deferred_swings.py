"""Deferred swings (planners.lattice.DEFER_SWINGS): tables evaluated up front that leave the
§5.2 curves to be built where a search reads them give every search what the tables built
in full give it, hold the same values where built, count exactly the curves built, and the
DP that reads a step's predecessors in order of value finds what reading all of them
finds."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from planner_strategies import terrain_profiles

import planners.lattice as lattice
from planners import Leg, PlannerConfig, plan_batch
from planners.dp import cheapest
from planners.lattice import DEFER_SWINGS, build_tables
from planners.plan import _SEARCHES

_STEP_FIELDS = ("length", "rise", "En", "Ev", "Ej", "E", "step_reason", "cost", "progress")


def _tables(profile, leg, config, defer):
    A = 3
    return build_tables([profile] * A, [leg] * A, np.array([0.9, 1.34, 1.7]), None,
                        np.zeros(A), config, defer_swings=defer)


@settings(max_examples=8, deadline=None)
@given(terrain_profiles())
def test_deferred_swings_give_the_same_search_and_count_the_curves_built(leg, profile):
    config = PlannerConfig()
    for name in sorted(DEFER_SWINGS):
        eager = _tables(profile, leg, config, False)
        deferred = _tables(profile, leg, config, True)
        assert not eager.deferred and not eager.pending.any()
        want, got = _SEARCHES[name](eager), _SEARCHES[name](deferred)
        for field in ("found", "configs", "expanded", "checks"):
            assert np.array_equal(getattr(want, field), getattr(got, field)), (name, field)
        for field in _STEP_FIELDS:  # the steps are built up front either way
            assert np.array_equal(getattr(deferred, field), getattr(eager, field)), name
        built = deferred.lattice.swing_done
        full = eager.lattice.swing_done
        # built and pending: exactly the curves built in full, none twice
        assert not (built & deferred.pending).any(), name
        assert np.array_equal(built | deferred.pending, full), name
        assert np.array_equal(deferred.swing_ok[built], eager.swing_ok[built]), name
        assert np.array_equal(deferred.controls[built], eager.controls[built]), name
        assert np.array_equal(deferred.rounds[built], eager.rounds[built]), name
        # the counters count the curves built and reused, no more, no less
        work = deferred.work
        assert np.array_equal(work.swing_curves + work.swing_curves_reused,
                              built.sum(axis=1)), name
        assert np.array_equal(work.swing_adjustments,
                              np.where(built, deferred.rounds, 0).sum(axis=1)), name
        # every swing of a configuration found was read, so built
        steps, swings = deferred.struct.indices(got.configs)
        rows = np.arange(got.found.size)[:, None]
        assert built[rows, swings][got.found].all(), name
        # completing the tables builds the rest: the tables built in full
        deferred.complete()
        assert not deferred.pending.any()
        assert np.array_equal(deferred.lattice.swing_done, full), name
        assert np.array_equal(deferred.swing_ok, eager.swing_ok), name
        assert np.array_equal(deferred.controls, eager.controls), name
        assert np.array_equal(deferred.rounds, eager.rounds), name
        assert np.array_equal(deferred.work.swing_curves, eager.work.swing_curves), name
        assert np.array_equal(deferred.work.swing_adjustments,
                              eager.work.swing_adjustments), name


def _all_predecessors_dp(tables, a, step_cost):
    """The DP of planners.dp.cheapest as it was written before the swings were deferred:
    every predecessor of a legal step read, the least value plus cost over those of a
    legal swing (the first on ties)."""
    st = tables.struct
    J, n = st.J, st.n
    legal = tables.step_legal[a]
    ok = tables.swing_ok[a]
    value = {(0, 0): 0.0}
    choice = {}
    for k in range(1, n + 1):
        new = {}
        M = (J - 1) * (k - 1) + 1
        for m in range(M):
            for j in range(J):
                step = st.step_offset[k - 1] + m * J + j
                if not legal[step]:
                    continue
                best, arg = np.inf, 0
                for jp in range(1 if k == 1 else J):
                    v = value.get((m, jp), np.inf)
                    if not v < np.inf:
                        continue
                    if k == 1:
                        swing = st.swing_offset[0] + j
                    else:
                        m2 = m - jp
                        if not 0 <= m2 <= (J - 1) * (k - 2):
                            continue
                        swing = st.swing_offset[k - 1] + m2 * st.swing_strides[k - 1] + jp + j
                    if ok[swing] and v + step_cost[step] < best:
                        best, arg = v + step_cost[step], jp
                new[m + j, j] = best
                choice[k, m + j, j] = arg
        value = new
    finals = [(v, m, j) for (m, j), v in sorted(value.items()) if v < np.inf]
    if not finals:
        return None
    _, m, j = min(finals, key=lambda f: f[0])  # the first of least value (m, j order)
    config = []
    for k in range(n, 0, -1):
        config.append(j)
        m, j = m - j, choice[k, m, j]
    return config[::-1]


def _random_terrain():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    from bench_planners import random_terrain

    return random_terrain


def test_dp_reading_predecessors_in_order_of_value_finds_the_same(leg):
    from planners import GroundProfile

    config = replace(PlannerConfig(), n_steps=3, intervals=7)
    rng = np.random.default_rng(3)
    grounds = [GroundProfile.flat()] + [_random_terrain()(rng) for _ in range(6)]
    for profile in grounds:
        tables = _tables(profile, leg, config, False)
        A, Ns = tables.E.shape
        # costs with many ties (a few integer values) and the searches' own costs
        costs = [rng.integers(0, 4, (A, Ns)).astype(float) for _ in range(3)]
        for cost in costs + [tables.cost.copy()]:
            configs, found, _ = cheapest(tables, cost)
            for a in range(A):
                want = _all_predecessors_dp(tables, a, np.round(cost[a], 10))
                assert found[a] == (want is not None)
                if want is not None:
                    assert configs[a].tolist() == want


@pytest.mark.parametrize("planner", sorted(DEFER_SWINGS))
def test_plans_with_deferred_swings_are_the_plans_built_in_full(planner, monkeypatch):
    random_terrain = _random_terrain()
    rng = np.random.default_rng(5)
    profiles = [random_terrain(rng) for _ in range(12)]
    legs = [Leg.from_body_height(h) for h in rng.uniform(1.5, 1.95, 12)]
    speeds = rng.uniform(0.8, 1.8, 12)
    got = plan_batch(profiles, legs, speeds, planner)
    monkeypatch.setattr(lattice, "DEFER_SWINGS", frozenset())
    want = plan_batch(profiles, legs, speeds, planner)
    fewer = 0
    for p, q in zip(got, want, strict=True):
        assert (p.status, p.message) == (q.status, q.message)
        for field in ("footholds_s", "footholds_z", "swing_controls", "E"):
            assert np.array_equal(getattr(p, field), getattr(q, field)), field
        for key in ("nodes_expanded", "legality_checks", "lattice_steps", "key_frame_solves"):
            assert p.stats[key] == q.stats[key], key
        assert p.stats["swing_curves"] <= q.stats["swing_curves"]
        fewer += p.stats["swing_curves"] < q.stats["swing_curves"]
    assert fewer > 0  # random terrain: some curves are never read


def _climb_reading_every_neighbour(tables, a, q):
    """hill_climb as written before the swings were deferred: every in-grid neighbour's
    legality and efficiency read (StepTables.evaluate), the most efficient legal one
    taken (the first among equals) while it beats the current one by 1e-12."""
    from planners.multistart import _deltas

    J, n = tables.struct.J, tables.struct.n
    q = np.array(q)
    _, cur = tables.evaluate(np.array([a]), q[None])
    cur = float(cur[0])
    expanded = checks = 0
    while True:
        expanded += 1
        best_eff, best_d = -np.inf, None
        for d in _deltas(n):
            r = q + d
            if (r < 0).any() or (r >= J).any():
                continue
            checks += 1
            legal, e = tables.evaluate(np.array([a]), r[None])
            if legal[0] and e[0] > best_eff:
                best_eff, best_d = float(e[0]), d
        if not best_eff > cur * (1 + 1e-12):
            return q, cur, expanded, checks
        q, cur = q + best_d, best_eff


def _greedy_reading_every_step(tables, a):
    """greedy as written before: each step's legality and swing read, the first j of
    highest length / E (a NaN wins)."""
    st = tables.struct
    J = st.J
    config, found = [], True
    for k in range(st.n):
        scores = []
        for j in range(J):
            steps, swings = st.indices(np.array(config + [j] + [0] * (st.n - k - 1)))
            step, swing = steps[k], swings[k]
            legal = tables.step_legal[a, step] and tables.swing_ok[a, swing]
            scores.append(tables.length[a, step] / tables.E[a, step] if legal else -np.inf)
        best = int(np.argmax(scores))
        if not np.isfinite(scores[best]) and not np.isnan(scores[best]):
            found = False
        config.append(best)
    return config, found


def test_climbs_and_greedy_reading_swings_where_they_decide_find_the_same(leg):
    from planners.multistart import greedy, hill_climb, nearest_legal

    rng = np.random.default_rng(11)
    config = PlannerConfig()
    for profile in [_random_terrain()(rng) for _ in range(4)]:
        eager = _tables(profile, leg, config, False)
        deferred = _tables(profile, leg, config, True)
        starts = nearest_legal(eager)
        agents = np.flatnonzero(starts.found)
        local, eff, exp, chk = hill_climb(deferred, agents, starts.configs[agents])
        for i, a in enumerate(agents):
            q, cur, e, c = _climb_reading_every_neighbour(eager, a, starts.configs[a])
            assert local[i].tolist() == q.tolist()
            assert eff[i] == cur and exp[i] == e and chk[i] == c
        g = greedy(deferred)
        for a in range(eager.neutral.size):
            want, found = _greedy_reading_every_step(eager, a)
            assert bool(g.found[a]) == found
            if found:
                assert g.configs[a].tolist() == want
