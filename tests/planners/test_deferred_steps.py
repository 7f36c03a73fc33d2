"""Deferred steps (planners.lattice.DEFER_STEPS): tables evaluated up front that leave the
steps needing key frames to be evaluated where a search reads them, the DP passes bounded
by a lower bound of the step costs (planners.dp.settle), give the configurations the
tables evaluated in full give, hold the same values where evaluated, and count exactly
the steps evaluated."""

from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from planner_strategies import terrain_profiles

import planners.lattice as lattice
from planners import GroundProfile, Leg, PlannerConfig, plan_batch
from planners.lattice import DEFER_STEPS, build_tables
from planners.legality import Reason
from planners.plan import _SEARCHES

_STEP_FIELDS = ("length", "rise", "En", "Ev", "Ej", "E", "step_reason", "cost", "progress")


def _tables(profiles, legs, speeds, config, defer):
    A = len(profiles)
    return build_tables(profiles, legs, np.asarray(speeds), None, np.zeros(A), config,
                        defer_swings=True, defer_steps=defer)


def _check(profiles, legs, speeds, config):
    """The search on deferred steps against the tables in full, entry by entry."""
    eager = _tables(profiles, legs, speeds, config, False)
    deferred = _tables(profiles, legs, speeds, config, True)
    assert not eager.step_pending.any()
    want, got = _SEARCHES["optimal"](eager), _SEARCHES["optimal"](deferred)
    assert np.array_equal(want.found, got.found)
    assert np.array_equal(want.configs[want.found], got.configs[got.found])
    done = eager.step_reason != int(Reason.UNREACHED)  # what the full tables evaluate
    kept = ~deferred.step_pending
    # every step evaluated holds the value evaluated in full, where that evaluates it
    for field in _STEP_FIELDS:
        a, b = getattr(deferred, field), getattr(eager, field)
        assert np.array_equal(a[done & kept], b[done & kept]), field
    assert np.array_equal(deferred.step_legal[done & kept], eager.step_legal[done & kept])
    # a step left pending is neither level (no key frame) nor one the search used
    steps, _ = deferred.struct.indices(got.configs)
    rows = np.arange(got.found.size)[:, None]
    assert not deferred.step_pending[rows, steps][got.found].any()
    assert not deferred.step_legal[deferred.step_pending].any()
    # the counters count the steps evaluated: completing solves each pending step once
    work, full = deferred.work, eager.work
    pending = deferred.step_pending.sum(axis=1)
    deferred.complete()
    assert not deferred.step_pending.any()
    after = deferred.work
    assert np.array_equal(after.key_frames, work.key_frames + pending)
    assert np.array_equal(after.steps, work.steps + pending)
    # completed, the tables hold the values of the tables in full wherever those
    # evaluate (and, where a deferred step the knee cannot make was taken as legal for
    # the reach of its landing, a few steps more)
    for field in _STEP_FIELDS:
        a, b = getattr(deferred, field), getattr(eager, field)
        assert np.array_equal(a[done], b[done]), field
    assert (after.key_frames >= full.key_frames).all()
    return work, full


@settings(max_examples=10, deadline=None)
@given(terrain_profiles())
def test_deferred_steps_give_the_configurations_of_the_tables_in_full(leg, profile):
    for config in (PlannerConfig(), replace(PlannerConfig(), n_steps=3, intervals=7)):
        _check([profile] * 3, [leg] * 3, [0.9, 1.34, 1.7], config)


def test_deferred_steps_on_the_standard_grounds_skip_key_frames():
    """Flat ground, stairs up and down, a ramp and a low block: the same configurations,
    fewer key frames (the counters checked in :func:`_check`)."""
    leg = Leg.from_body_height(1.75)
    grounds = [GroundProfile.flat(), GroundProfile.stairs(0.17, 0.30, 8, first_edge=0.4),
               GroundProfile.stairs(-0.17, 0.30, 8, first_edge=0.4),
               GroundProfile(np.array([-2, 0.3, 8.0]), np.array([0, 0, 0.77])),
               GroundProfile(np.array([-2, 0.5, 0.5, 0.8, 0.8, 9]),
                             np.array([0, 0, 0.1, 0.1, 0, 0]))]  # a low block (Fig. 11)
    work, full = _check(grounds, [leg] * len(grounds), [1.34] * len(grounds),
                        PlannerConfig())
    # on the 10 % ramp every step needs key frames: the bound rules some out
    assert work.key_frames[3] < full.key_frames[3]
    assert work.key_frames.sum() < full.key_frames.sum()


def _random_terrain():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    from bench_planners import random_terrain

    return random_terrain


def test_plans_with_deferred_steps_are_the_plans_evaluated_in_full(monkeypatch):
    random_terrain = _random_terrain()
    rng = np.random.default_rng(11)
    profiles = [random_terrain(rng) for _ in range(24)]
    legs = [Leg.from_body_height(h) for h in rng.uniform(1.5, 1.95, 24)]
    speeds = rng.uniform(0.8, 1.8, 24)
    assert "optimal" in DEFER_STEPS
    got = plan_batch(profiles, legs, speeds, "optimal")
    monkeypatch.setattr(lattice, "DEFER_STEPS", frozenset())
    want = plan_batch(profiles, legs, speeds, "optimal")
    fewer = 0
    for p, q in zip(got, want, strict=True):
        assert (p.status, p.message) == (q.status, q.message)
        for field in ("footholds_s", "footholds_z", "swing_controls", "E"):
            assert np.array_equal(getattr(p, field), getattr(q, field)), field
        fewer += p.stats["key_frame_solves"] < q.stats["key_frame_solves"]
    assert fewer > len(got) // 2


@settings(max_examples=10, deadline=None)
@given(terrain_profiles())
def test_a_step_left_deferred_lies_on_no_configuration_as_cheap_as_the_least(leg, profile):
    """settle's guarantee, against every configuration: after a bounded pass, each step
    still deferred lies only on step-legal configurations (swings ignored) whose sum of
    the pass's entries exceeds the least total of a legal one (the DP over the tables in
    full), for several energies per metre."""
    from planners.dp import dp_one, dp_scratch, settle, settle_scratch

    config = PlannerConfig()
    speeds = [0.9, 1.34, 1.7]
    eager = _tables([profile] * 3, [leg] * 3, speeds, config, False)
    st = eager.struct
    steps, _ = st.all_indices
    J, n = st.J, st.n
    value, new, choice = dp_scratch(J, n)
    F, H, pred, q, path = settle_scratch(st.node_depth.size, n)
    best = np.empty(n, dtype=np.int64)
    for a in range(3):
        for scale in (0.8, 1.0, 1.25):
            deferred = _tables([profile] * 3, [leg] * 3, speeds, config, True)
            lam = scale * float(eager.neutral_cost[a])
            full_row = np.round(eager.cost[a] - lam * eager.progress[a], 10)
            ok = dp_one(eager.step_legal, eager.swings, full_row, a, J, st._step_offsets,
                        st._swing_offsets, st._swing_strides, value, new, choice, best)[0]
            if not ok:
                continue
            least = 0.0
            for t in st.indices(best)[0]:
                least = least + full_row[t]
            row = np.round(deferred.cost[a] - lam * deferred.progress[a], 10)
            settle(deferred.steps, deferred.swings, a, row, 1, 0, lam, st.step_j,
                   deferred.progress, J, st._step_offsets, st._swing_offsets,
                   st._swing_strides, np.inf, F, H, pred, q, path)
            left = np.flatnonzero(deferred.step_pending[a])
            legal = eager.step_legal[a][steps].all(axis=1)
            sums = np.zeros(steps.shape[0])
            for k in range(n):
                sums = sums + full_row[steps[:, k]]
            through = np.isin(steps, left).any(axis=1) & legal
            assert (sums[through] > least).all(), (a, scale)
            # and a pass over the evaluated steps alone finds the same configuration
            got = np.empty(n, dtype=np.int64)
            assert dp_one(deferred.step_legal, deferred.swings, row, a, J,
                          st._step_offsets, st._swing_offsets, st._swing_strides, value,
                          new, choice, got)[0]
            assert got.tolist() == best.tolist()
