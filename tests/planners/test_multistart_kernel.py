"""best_first_multistart's compiled pass (planners.multistart._multistart) finds, agent by
agent, what its public steps composed over all agents find (nearest_legal, budget, greedy,
hill_climb and the extra starts where the local optima differ), with the same counters;
so does optimal's (planners.optimal._optimal: nearest_legal, then Dinkelbach)."""

import numpy as np
from hypothesis import given, settings
from planner_strategies import terrain_profiles

from planners import PlannerConfig
from planners.lattice import build_tables
from planners.multistart import _composed, best_first_multistart
from planners.optimal import _composed as optimal_composed
from planners.optimal import optimal


@settings(max_examples=15, deadline=None)
@given(terrain_profiles())
def test_compiled_multistart_is_the_composed_search(leg, profile):
    config = PlannerConfig()
    tables = build_tables([profile, profile, profile], [leg, leg, leg],
                          np.array([1.34, 0.9, 1.7]), None, np.zeros(3), config)
    for starts in (1, 2, 3, 8, 20):
        got, want = best_first_multistart(tables, starts), _composed(tables, starts)
        assert np.array_equal(got.found, want.found), starts
        assert np.array_equal(got.configs[got.found], want.configs[want.found]), starts
        assert np.array_equal(got.expanded, want.expanded), starts
        assert np.array_equal(got.checks, want.checks), starts


@settings(max_examples=15, deadline=None)
@given(terrain_profiles())
def test_compiled_optimal_is_the_composed_search(leg, profile):
    tables = build_tables([profile, profile, profile], [leg, leg, leg],
                          np.array([1.34, 0.9, 1.7]), None, np.zeros(3), PlannerConfig())
    got, want = optimal(tables), optimal_composed(tables)
    assert np.array_equal(got.found, want.found)
    assert np.array_equal(got.configs[got.found], want.configs[want.found])
    assert np.array_equal(got.expanded, want.expanded)
    assert np.array_equal(got.checks, want.checks)
