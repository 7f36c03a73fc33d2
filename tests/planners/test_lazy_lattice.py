"""The lazy lattice (planners.lattice_kernel): a search that evaluates the tables where it
reads them finds what it finds on the tables evaluated up front, the entries it evaluated
hold the same values, and the table counters count exactly the entries evaluated."""

import numpy as np
from hypothesis import given, settings
from planner_strategies import terrain_profiles

from planners import PlannerConfig
from planners.lattice import LAZY, build_tables
from planners.plan import _SEARCHES

_STEP_FIELDS = ("length", "rise", "En", "Ev", "Ej", "E", "step_reason", "cost", "progress")


@settings(max_examples=10, deadline=None)
@given(terrain_profiles())
def test_lazy_searches_find_the_same_and_count_what_they_evaluate(leg, profile):
    config = PlannerConfig()
    args = ([profile, profile], [leg, leg], np.array([1.34, 1.1]), None, np.zeros(2), config)
    for name in sorted(LAZY):
        search = _SEARCHES[name]
        eager = build_tables(*args, lazy=False)
        lazy = build_tables(*args, lazy=True)
        want, got = search(eager), search(lazy)
        assert np.array_equal(want.found, got.found), name
        assert np.array_equal(want.configs[want.found], got.configs[got.found]), name
        assert np.array_equal(want.expanded, got.expanded), name
        assert np.array_equal(want.checks, got.checks), name
        done = lazy.lattice.step_done
        for field in _STEP_FIELDS:
            assert np.array_equal(getattr(lazy, field)[done], getattr(eager, field)[done]), (
                name, field)
        built = lazy.lattice.swing_done
        assert np.array_equal(lazy.swing_ok[built], eager.swing_ok[built]), name
        assert np.array_equal(lazy.controls[built], eager.controls[built]), name
        # the counters are the entries evaluated, no more, no less
        work = lazy.work
        assert np.array_equal(work.steps, done.sum(axis=1)), name
        assert np.array_equal(work.swing_curves + work.swing_curves_reused,
                              built.sum(axis=1)), name
        assert (done <= eager.lattice.step_done).all(), name  # only reachable steps
        # and what the search skipped is marked unevaluated: illegal, E = +inf
        assert not lazy.step_legal[~done].any() and np.isinf(lazy.E[~done]).all(), name


def test_best_first_reads_a_small_part_of_the_lattice(leg):
    from planners import GroundProfile, plan

    p = plan(GroundProfile([-2, 0.3, 8.0], [0, 0, 0.77]), leg, 1.34, "best_first")
    full = plan(GroundProfile([-2, 0.3, 8.0], [0, 0, 0.77]), leg, 1.34, "optimal")
    assert p.ok and full.ok
    # a 10 % ramp: every step needs its key frames; the search reads a fraction of them
    assert p.stats["lattice_steps"] < full.stats["lattice_steps"] / 3
    assert p.stats["swing_curves"] + p.stats["swing_curves_reused"] < full.stats[
        "swing_curves"] + full.stats["swing_curves_reused"]
