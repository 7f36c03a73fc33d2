"""planners.normal_mode: the step length / frequency / speed relation and its inverses;
validated against Schwartz et al. 2008 (not the WBDS data it was fitted to)."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from planners import Leg, ProfileError, normal_mode

REPO = Path(__file__).resolve().parents[2]
GAIT_DIR = next((p / "shared" / "data" / "gait" for p in (REPO.parent, REPO.parent.parent)
                 if (p / "shared" / "data" / "gait").is_dir()), None)


def test_inverses_round_trip_on_arrays():
    speed = np.linspace(0.3, 2.0, 12)[:, None]
    leg = np.array([0.75, 0.87, 1.0])[None, :]
    sl = normal_mode.step_length(speed, leg)
    f = normal_mode.step_frequency(speed, leg)
    assert sl.shape == f.shape == (12, 3)
    np.testing.assert_allclose(sl * f, np.broadcast_to(speed, sl.shape), rtol=1e-12)
    np.testing.assert_allclose(normal_mode.speed_from_step_length(sl, leg), speed + 0 * leg,
                               rtol=1e-12)
    np.testing.assert_allclose(normal_mode.speed_from_step_frequency(f, leg), speed + 0 * leg,
                               rtol=1e-12)


def test_steps_lengthen_with_speed_and_size():
    sl = normal_mode.step_length(np.array([0.8, 1.33, 1.8]), 0.9)
    assert np.all(np.diff(sl) > 0)
    short, tall = normal_mode.leg_length_from_height(np.array([1.5, 1.95]))
    # At the same speed the taller walker takes longer, slower steps.
    assert normal_mode.step_length(1.33, tall) > normal_mode.step_length(1.33, short)
    assert normal_mode.step_frequency(1.33, tall) < normal_mode.step_frequency(1.33, short)
    assert normal_mode.step_frequency(0.0, 0.9) == 0.0


def test_leg_length_of_matches_height_ratio():
    assert normal_mode.leg_length_of(Leg.from_body_height(1.8)) == pytest.approx(0.513 * 1.8)


@pytest.mark.parametrize("call", [
    lambda: normal_mode.step_length(-0.1, 0.9),
    lambda: normal_mode.step_length(1.0, np.array([0.9, 0.0])),
    lambda: normal_mode.speed_from_step_frequency(np.nan, 0.9),
])
def test_bad_input_names_field(call):
    with pytest.raises(ProfileError, match=r"normal_mode\.\w+ must be finite"):
        call()


@pytest.mark.skipif(GAIT_DIR is None, reason="measured gait data (../shared) not found")
def test_validates_on_schwartz_2008_within_one_sd():
    """Children walking overground (dimensionless units): every speed category's mean step
    length and cadence within 1 SD of the WBDS-calibrated relation."""
    spec = importlib.util.spec_from_file_location("fit", REPO / "scripts" / "fit_normal_mode.py")
    fit = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fit)
    cats = fit.schwartz_categories(GAIT_DIR)
    assert len(cats) == 5
    leg = 1.0  # dimensionless: L = 1 m, g = 9.81 -> v_hat * sqrt(g) m/s
    for _, v_hat, sl, sl_sd, f, f_sd in cats:
        v = v_hat * np.sqrt(9.81 * leg)
        assert abs(normal_mode.step_length(v, leg) - sl) < sl_sd
        f_pred = normal_mode.step_frequency(v, leg) / np.sqrt(9.81 / leg)
        assert abs(f_pred - f) < f_sd


@pytest.mark.parametrize("planner", ["best_first", "fixed"])
def test_planned_level_step_follows_speed_and_size(planner):
    """PlannerConfig.step_model = "normal_mode": the planned level step is the normal-mode
    step within 5 % for bodies 1.50-1.95 m at 0.8-1.8 m/s; "paper" keeps one step."""
    from planners import GroundProfile, PlannerConfig, plan

    flat = GroundProfile.flat(12.0, 0.0, -2.0)
    for height in (1.50, 1.95):
        leg = Leg.from_body_height(height)
        for speed in (0.8, 1.33, 1.8):
            want = normal_mode.step_length(speed, normal_mode.leg_length_of(leg))
            got = plan(flat, leg, speed, planner).step_lengths
            assert np.all(np.abs(got / want - 1) <= 0.05), (height, speed, got, want)
    paper = PlannerConfig(step_model="paper")
    leg = Leg.from_body_height(1.75)
    steps = {plan(flat, leg, v, planner, paper).step_lengths[0] for v in (0.8, 1.33, 1.8)}
    assert len(steps) == 1


def test_planned_steps_lie_in_the_gaitrite_adult_normal_pace_range():
    """Validation on other data: adults 18-69 walking at normal pace (GAITRite normals,
    mean +/- 1 SD: 1.10-1.65 m/s, steps 0.589-0.852 m) - a 1.70 m body's planned steps."""
    from planners import GroundProfile, plan

    leg = Leg.from_body_height(1.70)
    for speed in (1.10, 1.35, 1.65):
        step = plan(GroundProfile.flat(12.0, 0.0, -2.0), leg, speed).step_lengths[0]
        assert 0.589 <= step <= 0.852
