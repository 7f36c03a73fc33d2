"""Two-link IK, Table 1 timing and §5.4 turn splitting."""

import math

import numpy as np
import pytest

from planners import Leg, split_turn
from planners.kinematics import leg_angles
from planners.timing import phase_durations, phase_fractions


def test_straight_leg_below_the_hip_has_zero_elevation_angles():
    leg = Leg(0.43, 0.43, 0.26, 0.065, 0.195)
    thigh, shank, ok = leg_angles(np.array(0.0), np.array(0.86), np.array(0.0),
                                  np.array(0.0), leg, 0.2)
    assert ok and thigh == pytest.approx(0, abs=1e-6) and shank == pytest.approx(0, abs=1e-6)


def test_knee_bends_forward_and_reach_is_checked():
    leg = Leg(0.43, 0.43, 0.26, 0.065, 0.195)
    thigh, shank, ok = leg_angles(np.array(0.0), np.array(0.6), np.array(0.0),
                                  np.array(0.0), leg, 0.2)
    # law of cosines: hip angle acos(0.3 / 0.43)
    assert ok and thigh == pytest.approx(math.acos(0.3 / 0.43))
    assert shank == pytest.approx(-math.acos(0.3 / 0.43))
    _, _, too_far = leg_angles(np.array(0.0), np.array(0.9), np.array(0.0),
                               np.array(0.0), leg, 0.2)
    _, _, too_close = leg_angles(np.array(0.0), np.array(0.1), np.array(0.0),
                                 np.array(0.0), leg, 0.2)
    assert not too_far and not too_close


def test_phase_timing_follows_table_1():
    assert phase_fractions(0.0, 0.86) == pytest.approx([0.44, 0.28, 0.28])
    f = phase_fractions(0.172, 0.86)  # h / l = 0.2: T1 loses 6 percentage points
    assert f == pytest.approx([0.38, 0.31, 0.31]) and f.sum() == pytest.approx(1)
    assert phase_fractions(-0.172, 0.86) == pytest.approx(f)
    d = phase_durations(0.67, 1.34, 0.0, 0.86)
    assert d.sum() == pytest.approx(0.5)


def test_split_turn_divides_large_turns_over_steps():
    rot, feet = split_turn(math.pi, math.radians(45), "left")
    assert len(rot) == 4 and rot.sum() == pytest.approx(math.pi)  # Fig. 8
    assert np.all(np.abs(rot) <= math.radians(45) + 1e-12)
    assert feet == ["left", "right", "left", "right"]
    rot, feet = split_turn(math.radians(-60), math.radians(45), "left")
    assert rot[0] == 0 and feet[0] == "left"  # a right turn starts with the right foot
    assert rot.sum() == pytest.approx(math.radians(-60)) and len(rot) == 3
    with pytest.raises(ValueError, match="split_turn.threshold"):
        split_turn(1.0, 0.0)
