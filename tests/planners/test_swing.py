"""Swing curves: §5.2 adjustment clears the ground by the margin (dense check)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from planner_strategies import terrain_profiles

from planners import GroundProfile, PlannerConfig, plan
from planners.swing import adjust_swings, bezier_points, sole_clearance

CFG = PlannerConfig()


def dense_deficit(controls, start_s, end_s, profile, leg):
    pts = bezier_points(controls, 400)
    return sole_clearance(pts, start_s, end_s, profile, leg, CFG)


def test_flat_ground_needs_no_adjustment(leg):
    flat = GroundProfile.flat()
    s0 = np.full(5, -0.6)
    s3 = np.linspace(0.4, 1.0, 5)
    result = adjust_swings(s0, np.zeros(5), s3, np.zeros(5), flat, leg, CFG)
    assert result.ok.all() and (result.rounds == 0).all()


def test_adjustment_lifts_the_curve_over_a_step_up(leg):
    step = GroundProfile([-2, 0.2, 0.2, 5], [0, 0, 0.17, 0.17])
    s0, s3 = np.array([-0.35]), np.array([0.45])
    result = adjust_swings(s0, [0.0], s3, [0.17], step, leg, CFG)
    assert result.ok.all() and result.rounds[0] >= 1
    assert dense_deficit(result.controls, s0, s3, step, leg).max() <= 1e-9
    # the unadjusted initial curve would have hit the riser
    initial = result.controls.copy()
    initial[:, 1:3] = 0.5 * (initial[:, 0] + initial[:, 3])[:, None] + [0, CFG.swing_lift]
    assert dense_deficit(initial, s0, s3, step, leg).max() > 0


def test_a_swing_over_a_wall_leaves_the_legal_region_and_fails(leg):
    wall = GroundProfile([-2, 0.0, 0.0, 0.2, 0.2, 5], [0, 0, 1.0, 1.0, 0, 0])
    result = adjust_swings(np.array([-0.4]), [0.0], np.array([0.6]), [0.0], wall, leg, CFG)
    assert not result.ok[0]


@settings(max_examples=30, deadline=None)
@given(terrain_profiles(), st.sampled_from(["best_first", "fixed", "optimal"]))
def test_every_planned_swing_curve_clears_the_profile_by_the_margin(leg, profile, planner):
    p = plan(profile, leg, 1.34, planner)
    feet = np.concatenate([[p.trailing_s], p.footholds_s])
    k = p.step_lengths.size
    if k == 0:
        return
    deficit = dense_deficit(p.swing_controls, feet[:k], feet[2:k + 2], profile, leg)
    assert deficit.max() <= 1e-9
    # curves start and end at the ankles of the footholds
    assert np.allclose(p.swing_controls[:, 0, 0], feet[:k])
    assert np.allclose(p.swing_controls[:, 3, 0], p.footholds_s[1:])
    assert np.allclose(p.swing_controls[:, 3, 1], p.footholds_z[1:] + leg.ankle_height)
