"""Energy accounting in the crowd: what footsteps.csv and summary.json charge, and the
planned against the unplanned lone walker on the same route."""

import numpy as np
import pytest

from planners import Leg, PlannerConfig
from planners.energy import step_energy


def _energy_to(steps, x):
    """Summed footstep energy [J/kg] up to the point where the footholds pass ``x`` [m]
    (the step across ``x`` pro rata): the same stretch of a route walked along +x."""
    return float(np.interp(x, steps.x, np.cumsum(steps.energy)))


@pytest.mark.parametrize("scenario", ["rimea1_corridor", "stairs_up_down"])
def test_lone_planned_walker_spends_no_more_than_the_fixed_one_on_the_same_route(run_of,
                                                                                scenario):
    runs = {p: run_of(scenario, planner=p) for p in ("best_first_multistart", "fixed")}
    steps = {p: r[1].footsteps() for p, r in runs.items()}
    for p, (summary, _) in runs.items():
        assert summary["agents_arrived"] == 1, p
    end = min(float(s.x.max()) for s in steps.values())
    planned, fixed = (_energy_to(steps[p], end) for p in ("best_first_multistart", "fixed"))
    assert planned <= fixed * (1 + 1e-9)
    if scenario == "rimea1_corridor":  # level ground: the neutral step is the optimum
        assert planned == pytest.approx(fixed, rel=1e-9)


@pytest.mark.parametrize("planner", ["best_first", "fixed"])
def test_every_footstep_is_charged_eq_4_of_the_step_taken(run_of, planner):
    """Planned and unplanned steps are charged alike: Eq. 4 of the step's length and rise
    at the walker's speed (the planners' 5 cm/s speed class), and the summary's energy is
    the sum of its footsteps."""
    summary, run = run_of("stairs_up_down", planner=planner)
    steps = run.footsteps()
    agent = summary["agents"][0]
    cfg = PlannerConfig(n_steps=3, min_step_ratio=0.15)
    leg = Leg.from_body_height(round(agent["body_height_m"] / 0.02) * 0.02)
    L, H = steps.step_length, steps.step_height
    zero = np.zeros_like(L)
    summit = np.maximum(H, 0) + leg.ankle_height + 0.75 * cfg.swing_lift
    speed = round(agent["free_speed_m_s"] / 0.05) * 0.05
    expected = step_energy(zero, zero, L, H, summit, leg, speed, cfg)[3]
    assert np.allclose(steps.energy, expected, rtol=2e-3)
    assert agent["energy_J_per_kg"] == pytest.approx(float(steps.energy.sum()), rel=1e-6)


def test_steps_the_planner_did_not_plan_are_charged_like_planned_ones():
    """crowd.stepping.fallback_energy (shortened and positioning steps) against the
    planner's own Eq. 4 for the same step, level and onto a stair."""
    from pathlib import Path

    from crowdwalk.crowd.run import RunOverrides, prepare
    from crowdwalk.crowd.stepping import fallback_energy
    from planners import GroundProfile, plan

    scenario = Path(__file__).parents[2] / "scenarios" / "stairs_up_down.yaml"
    _, _, sim, _, _ = prepare(scenario, RunOverrides(poses=False))
    a = np.array([0])
    leg = sim.legs.legs[sim.legs.index[0]]
    speed = float(sim.pop.free_speed[0])
    for ground in (GroundProfile.flat(), GroundProfile.stairs(0.17, 0.30, 4, first_edge=0.45)):
        p = plan(ground, leg, speed, "fixed", sim.footsteps.config)
        got = fallback_energy(np.asarray(p.step_lengths[:1]), np.asarray(p.step_heights[:1]),
                              legs=sim.legs.of(a), speed=sim.pop.free_speed[a],
                              config=sim.footsteps.config)
        assert got[0] == pytest.approx(p.E[0], rel=1e-9)
