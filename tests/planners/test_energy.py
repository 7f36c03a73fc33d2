"""The energy model (Eqs. 1-5) against hand calculations."""

import numpy as np
import pytest

from planners import EnergyWeights, GroundProfile, Leg, PlannerConfig, flat_efficiency
from planners.energy import (
    EV_PEAK_CM,
    joint_energy,
    total_energy,
    vertical_energy,
    walking_energy,
)


def test_walking_energy_is_ralston_rate_over_cadence():
    # v = 1.34 m/s = 80.4 m/min; n = 80.4 / 0.7 steps/min
    expected = (32 + 0.005 * 80.4**2) / (80.4 / 0.7)
    assert walking_energy(0.7, 1.34) == pytest.approx(expected)
    # per metre it is minimal at Ralston's 80 m/min
    v = np.linspace(0.5, 2.5, 201)
    per_metre = walking_energy(1.0, v)
    assert 60 * v[np.argmin(per_metre)] == pytest.approx(80, abs=1)


def test_vertical_energy_matches_eq2_below_the_peak_and_stays_monotone():
    assert vertical_energy(0.17) == pytest.approx(-0.18 * 17**2 + 7.14 * 17)
    assert vertical_energy(0.0) == 0.0
    peak = -0.18 * EV_PEAK_CM**2 + 7.14 * EV_PEAK_CM
    assert vertical_energy(0.30) == pytest.approx(peak + 7.14 * (30 - EV_PEAK_CM))
    h = np.linspace(0, 0.4, 401)
    assert np.all(np.diff(vertical_energy(h)) > 0)
    # stepping down costs a third of stepping up
    assert vertical_energy(-0.17) == pytest.approx(vertical_energy(0.17) / 3)


def test_joint_and_total_energy_combine_with_the_weights():
    w = EnergyWeights(alpha=2.0, beta=0.5, gamma=3.0, c_thigh=0.7, c_calf=0.2)
    assert joint_energy(1.5, 2.0, w) == pytest.approx(0.7 * 1.5 + 0.2 * 2.0)
    assert total_energy(1.0, 10.0, 4.0, w) == pytest.approx(2.0 + 5.0 + 12.0)


def test_flat_efficiency_peaks_near_0_6_to_0_7_m_and_scales_with_body():
    L = np.linspace(0.25, 0.95, 71)
    best = {h: L[np.argmax(flat_efficiency(Leg.from_body_height(h), 1.34, L))]
            for h in (1.5, 1.75, 1.9)}
    assert 0.58 <= best[1.75] <= 0.70
    assert best[1.5] < best[1.75] < best[1.9]
    eff = flat_efficiency(Leg.from_body_height(1.75), 1.34, L)
    assert eff[0] < eff.max() and eff[-1] < eff.max()  # an interior maximum (Fig. 2)


def test_bad_weights_are_rejected():
    with pytest.raises(ValueError, match="EnergyWeights.beta must be finite and >= 0"):
        EnergyWeights(beta=-1.0)
    with pytest.raises(ValueError, match="PlannerConfig.n_steps"):
        PlannerConfig(n_steps=0)


def test_linear_vertical_energy_is_work_at_constant_efficiency():
    h = np.linspace(0, 0.4, 41)
    w = EnergyWeights()
    assert w.vertical == "linear" and w.beta == pytest.approx(0.0549)
    # beta * Ev = g h / 0.25 [J/kg]
    assert w.beta * vertical_energy(h, model="linear") == pytest.approx(9.81 * h / 0.25,
                                                                        rel=2e-3)
    paper = EnergyWeights(vertical="paper")
    assert paper.beta == pytest.approx(0.0961)
    # both forms cost the same for a 17 cm riser
    assert w.beta * vertical_energy(0.17, model="linear") == pytest.approx(
        paper.beta * vertical_energy(0.17), rel=2e-3)


def test_uphill_steps_shorten_with_the_linear_form_and_jump_with_the_printed_one():
    from planners import GroundProfile, plan

    leg = Leg.from_body_height(1.75)
    ramp = GroundProfile(np.array([-2.0, -1.0, 8.0]), np.array([0.0, 0.0, 0.9]))  # 10 %
    eqs = PlannerConfig(step_model="paper")  # Eqs. 1-4 alone (no step-frequency term)
    level = plan(GroundProfile.flat(), leg, 1.34, "optimal", eqs).step_lengths.mean()
    linear = plan(ramp, leg, 1.34, "optimal", eqs).step_lengths.mean()
    printed = plan(ramp, leg, 1.34, "optimal",
                   PlannerConfig(step_model="paper",
                                 weights=EnergyWeights(vertical="paper"))).step_lengths.mean()
    assert linear < level < printed
    assert printed == pytest.approx(1.05 * leg.length, rel=1e-6)  # the longest grid step


def _legs(leg):
    from planners.grids import LegArrays

    return LegArrays([leg])


def test_terminal_energy_is_level_walking_on_level_ground(leg):
    from planners.energy import terminal_energy

    start = np.array([[0.3, 1.0, 2.2]])
    got = terminal_energy(GroundProfile.flat(), start, np.array([2.5]), np.array([-2.0]),
                          _legs(leg), np.array([1.34]), np.array([6.3]), np.array([0.65]),
                          PlannerConfig())
    assert np.allclose(got, 6.3 * (2.5 - start))


def test_terminal_energy_charges_each_tread_of_a_flight_one_stair_step(leg):
    """From one tread to the next, the estimate drops by Eq. 4 of a step of one going."""
    from planners.energy import step_energy, terminal_energy

    cfg = PlannerConfig()
    flight = GroundProfile.stairs(0.17, 0.30, 6, first_edge=1.0)
    start = np.array([[1.15, 1.45, 1.75]])  # mid-tread of treads 1, 2, 3
    got = terminal_energy(flight, start, np.array([4.0]), np.array([-2.0]), _legs(leg),
                          np.array([1.34]), np.array([6.3]), np.array([0.65]), cfg)[0]
    z = np.zeros(1)
    lift = leg.ankle_height + 0.75 * cfg.swing_lift
    stair = step_energy(z, z, z + 0.30, z + 0.17, z + 0.17 + lift, leg, 1.34, cfg)[3][0]
    assert np.allclose(-np.diff(got), stair)
    assert got[0] > 6.3 * (4.0 - 1.15)  # climbing costs more than level walking


def test_terminal_energy_lets_a_low_obstacle_be_stridden_over(leg):
    from planners.energy import terminal_energy

    args = (np.array([[0.0]]), np.array([3.0]), np.array([-2.0]), _legs(leg),
            np.array([1.34]), np.array([6.3]), np.array([0.65]), PlannerConfig())
    low = GroundProfile([-2, 1, 1, 1.3, 1.3, 8], [0, 0, 0.1, 0.1, 0, 0])
    curb = GroundProfile([-2, 1, 1, 8], [0, 0, 0.1, 0.1])
    kerb_down = GroundProfile([-2, 1.3, 1.3, 8], [0, 0, -0.1, -0.1])
    step_on = (terminal_energy(curb, *args) + terminal_energy(kerb_down, *args)
               - 2 * 6.3 * 3.0)
    over = terminal_energy(low, *args) - 6.3 * 3.0
    assert 0 < over < step_on


def test_fitted_constants_are_selectable_and_price_descent_below_ascent(leg):
    """The measured constants (scripts/fit_energy_constants.py) plan like any others; a
    stair step down costs less than the step up, by more than with the hand-set ones."""
    from planners import EnergyWeights, GroundProfile, PlannerConfig, plan

    fitted = PlannerConfig(weights=EnergyWeights.fitted())
    assert PlannerConfig().weights == EnergyWeights.fitted()  # the default
    ratios = []
    for config in (PlannerConfig(weights=EnergyWeights.hand_set()), fitted):
        up = plan(GroundProfile.stairs(0.17, 0.30, 6, first_edge=0.4), leg, 0.6, config=config)
        down = plan(GroundProfile.stairs(-0.17, 0.30, 6, first_edge=0.4), leg, 0.6,
                    config=config)
        assert up.ok and down.ok
        ratios.append(down.energy_per_metre / up.energy_per_metre)
    assert ratios[1] < ratios[0] < 1
