"""The DP's two passes (planners.dp.dp_one): the pass taking every swing as legal, then
the pass reading swings only where the first one's configuration has an illegal swing,
and the least-predecessor shortcut (planners.dp._least_value): the same results as the
pass reading swings and as planners.dp._least_after, ties and near-ties included."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from planners import GroundProfile, PlannerConfig
from planners.dp import _TIE, _dp_pass, _least_after, _least_value, dp_one, dp_scratch
from planners.lattice import build_tables


def _near_ties(rng, size):
    """Values a few ulps apart (and exactly equal, and infinite) around a few levels."""
    levels = rng.choice([0.0, 1e-10, 0.3, 1.0, 37.5, -2.0], size)
    ulps = rng.integers(-3, 4, size)
    v = levels + ulps * np.spacing(np.abs(levels) + 1e-300)
    v[rng.random(size) < 0.2] = np.inf
    return v


def test_least_value_shortcut_is_least_after_first_pick():
    rng = np.random.default_rng(5)
    J = 14
    hits = 0
    for _ in range(4000):
        value = _near_ties(rng, (3, J)).reshape(3, J)
        lo = int(rng.integers(0, J))
        hi = int(rng.integers(lo, J + 1))
        least, first, gap = _least_value(value, 1, lo, hi)
        for cost in (0.0, 1e-10, 0.7, -0.3, 37.5, float(rng.normal()), np.inf, np.nan):
            want = _least_after(value, 1, cost, lo, hi, -np.inf, -1)
            low = least + cost
            if low < np.inf and gap > _TIE * (abs(least) + abs(cost)) + 1e-300:
                hits += 1
                assert (low, first) == want
    assert hits > 1000  # the shortcut is taken, not only the fall-back


def _tables(profile, leg, config):
    return build_tables([profile] * 3, [leg] * 3, np.array([0.9, 1.34, 1.7]), None,
                        np.zeros(3), config, defer_swings=True)


def test_two_passes_give_the_pass_reading_swings(leg):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    from bench_planners import random_terrain

    config = replace(PlannerConfig(), n_steps=3, intervals=7)
    rng = np.random.default_rng(11)
    grounds = [GroundProfile.flat()] + [random_terrain(rng) for _ in range(8)]
    for profile in grounds:
        once, twice = _tables(profile, leg, config), _tables(profile, leg, config)
        st = once.struct
        A, Ns = once.E.shape
        # the searches' costs, costs with many exact ties, and near-ties
        costs = [once.cost.copy(), rng.integers(0, 3, (A, Ns)).astype(float),
                 _near_ties(rng, A * Ns).reshape(A, Ns)]
        for cost in costs:
            cost = np.ascontiguousarray(np.round(cost, 10))
            for a in range(A):
                value, new, choice = dp_scratch(st.J, st.n)
                want = np.zeros(st.n, dtype=np.int64)
                ok_w, _, _ = _dp_pass(twice.step_legal, twice.swings, cost[a], a, st.J,
                                      st._step_offsets, st._swing_offsets,
                                      st._swing_strides, value, new, choice, want, True)
                got = np.zeros(st.n, dtype=np.int64)
                ok_g, _, _ = dp_one(once.step_legal, once.swings, cost[a], a, st.J,
                                    st._step_offsets, st._swing_offsets, st._swing_strides,
                                    value, new, choice, got)
                assert ok_g == ok_w
                if ok_w:
                    assert got.tolist() == want.tolist()
