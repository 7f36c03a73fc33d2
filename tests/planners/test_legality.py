"""Legality of footholds and steps on crafted profiles: stair edge, riser, block, gap."""

import numpy as np
import pytest

from planners import PLANNERS, GroundProfile, PlannerConfig, plan
from planners.legality import Reason, foot_support, snap_to_support

CFG = PlannerConfig()
HEEL, TOE = 0.0665, 0.1995  # 1.75 m body


def support(profile, ankle):
    return foot_support(np.asarray(ankle, dtype=float), profile, HEEL, TOE, CFG)


def test_flat_ground_supports_the_foot_anywhere():
    assert np.all(support(GroundProfile.flat(), np.linspace(-1, 5, 13)) == 0)


def test_stair_edge_under_the_foot_is_illegal_both_ways():
    stairs = GroundProfile.stairs(0.17, 0.30, 3, first_edge=1.0)
    # toe over the riser (foot across the edge), heel behind it, ankle on the lower tread
    assert support(stairs, 0.9) & Reason.EDGE
    # heel over the lower tread, ankle on the upper one
    assert support(stairs, 1.03) & Reason.EDGE
    # whole foot on a tread: heel exactly at the riser, toe before the next one
    assert support(stairs, 1.0 + HEEL) == 0
    assert support(stairs, 1.30 - TOE) == 0


def test_block_narrower_than_the_foot_cannot_be_stood_on():
    block = GroundProfile([-2, 1.0, 1.0, 1.2, 1.2, 5], [0, 0, 0.1, 0.1, 0, 0])
    ankles = np.linspace(1.0 - TOE + 0.005, 1.2 + HEEL - 0.005, 41)  # foot overlaps it
    assert np.all(support(block, ankles) & Reason.EDGE)


def test_gap_under_the_foot_is_illegal_and_steep_ground_too():
    gap = GroundProfile([-2, 1.0, 1.0, 1.15, 1.15, 5], [0, 0, -0.5, -0.5, 0, 0])
    assert support(gap, 1.05) & Reason.EDGE
    steep = GroundProfile([-2, 0.0, 2.0, 5], [0, 0, 1.2, 1.2])  # slope 0.6 > 0.5
    assert support(steep, 1.0) == Reason.SLOPE
    assert support(GroundProfile([-2, 0, 2, 5], [0, 0, 0.6, 0.6]), 1.0) == 0  # slope 0.3


def test_snapping_moves_a_foothold_onto_the_tread_within_the_window():
    stairs = GroundProfile.stairs(0.17, 0.30, 3, first_edge=1.0)
    moved = snap_to_support(np.array([[1.05, 0.9]]), 0.025, stairs, HEEL, TOE, CFG)
    assert moved[0, 0] == pytest.approx(1.0 + HEEL)  # heel onto the riser line
    assert moved[0, 1] == 0.9  # nothing legal within 2.5 cm: unchanged
    assert support(stairs, moved[0, 0]) == 0


@pytest.mark.parametrize("planner", ["best_first", "fixed", "optimal"])
def test_planned_feet_never_stand_across_an_edge(leg, planner):
    stairs = GroundProfile.stairs(0.17, 0.30, 6, first_edge=0.4)
    p = plan(stairs, leg, 1.34, planner)
    assert p.ok
    assert np.all(support(stairs, p.footholds_s[1:]) == 0)
    assert np.all(np.abs(p.step_heights) <= CFG.max_step_rise + 1e-12)


def test_a_60_cm_wall_has_no_legal_foothold_and_says_where_and_why(leg):
    wall = GroundProfile([-2, 1.0, 1.0, 5], [0, 0, 0.6, 0.6])
    for planner in sorted(PLANNERS):
        p = plan(wall, leg, 1.34, planner)
        assert p.status == "no legal foothold"
        assert p.message.startswith("no legal foothold at s = 1.00 m: rise +0.60 m exceeds "
                                    "the largest step rise 0.25 m")
        # the longest legal prefix stays in front of the wall
        assert np.all(p.footholds_s + TOE <= 1.0 + 1e-9)
        assert p.step_lengths.size < 4
