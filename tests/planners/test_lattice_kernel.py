"""The compiled table pass (planners.lattice_kernel) against the vectorised definitions it
implements: foothold snapping and support, heights, step energies, terminal energy and
the §5.2 swing curves."""

import numpy as np
from hypothesis import given, settings
from planner_strategies import terrain_profiles

from planners import PlannerConfig
from planners.energy import step_energy, terminal_energy
from planners.grids import LegArrays
from planners.lattice import build_tables
from planners.legality import Reason, foot_support, snap_to_support
from planners.swing import adjust_swings


@settings(max_examples=12, deadline=None)
@given(terrain_profiles())
def test_tables_follow_the_vectorised_definitions(leg, profile):
    config = PlannerConfig()
    t = build_tables([profile], [leg], np.array([1.34]), None, np.zeros(1), config)
    st, legs = t.struct, LegArrays([leg])
    lo, delta = t.step_min[0], t.step_delta[0]
    on_grid = np.maximum(st.node_depth, 0) * lo + st.node_m * delta
    snapped = snap_to_support(on_grid[None, 2:], 0.5 * delta, profile, legs.heel_offset,
                              legs.toe_offset, config)[0]
    assert np.array_equal(t.node_s[0, 2:], snapped)
    assert np.array_equal(t.node_z[0], profile.height(t.node_s[0]))
    # every evaluated step: support flags of its landing, and its energy where finite
    done = t.step_reason[0] != Reason.UNREACHED
    front = st.step_front[done]
    support = foot_support(t.node_s[0, front], profile, leg.heel_offset, leg.toe_offset,
                           config)
    assert np.array_equal(t.step_reason[0, done] & (Reason.EDGE | Reason.SLOPE), support)
    finite = done & np.isfinite(t.E[0])
    stance_s, front_s = t.node_s[0, st.step_stance[finite]], t.node_s[0, st.step_front[finite]]
    stance_z, front_z = t.node_z[0, st.step_stance[finite]], t.node_z[0, st.step_front[finite]]
    summit = profile.max_height(stance_s, front_s) + leg.ankle_height + 0.75 * config.swing_lift
    E = step_energy(stance_s, stance_z, front_s, front_z, summit, leg, 1.34, config)[3]
    assert np.allclose(t.E[0, finite], E, rtol=1e-12, atol=0)
    # terminal energy of the last footholds
    last = slice(st.node_offset[st.n], None)
    want = terminal_energy(profile, t.node_s[:, last], t.reach, t.node_s[:, 0] - 2.0, legs,
                           np.array([1.34]), t.neutral_cost, lo + delta * t.neutral, config)
    assert np.allclose(t.terminal[:, last], want, rtol=1e-12, atol=1e-12)
    # curves the §5.2 adjustment moved (the others may come from the level-ground cache)
    built = np.flatnonzero(t.rounds[0] > 0)
    b, f = st.swing_back[built], st.swing_front[built]
    swing = adjust_swings(t.node_s[0, b], t.node_z[0, b], t.node_s[0, f], t.node_z[0, f],
                          profile, leg, config)
    assert np.array_equal(t.swing_ok[0, built], swing.ok)
    assert np.array_equal(t.rounds[0, built], swing.rounds)
    assert np.allclose(t.controls[0, built], swing.controls, rtol=0, atol=1e-12)
