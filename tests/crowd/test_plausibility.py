"""Plausibility against measurements (issue 5, item 6)."""

from pathlib import Path

import numpy as np
import pytest

from crowdwalk.scenario import load_scenario
from crowdwalk.world import build_world

SHARED = Path(__file__).parents[2] / ".." / "shared"
WBDS = SHARED / "data" / "gait" / "wbds_treadmill_speed_steplength_cadence.csv"


def test_rimea_1_lone_walker_crosses_40_m_in_26_to_34_s(run_of):
    summary, _ = run_of("rimea1_corridor")
    (agent,) = summary["agents"]
    assert agent["free_speed_m_s"] == 1.33
    assert agent["arrived"]
    # the walker spawns at x = 0.1 and arrives within 0.6 m of x = 40: add back what it
    # did not walk so the time is for the full 40 m at its mean speed
    speed = agent["distance_m"] / agent["travel_time_s"]
    full = agent["travel_time_s"] + (40.0 - agent["distance_m"]) / speed
    assert 26.0 <= full <= 34.0


def _measured_range(column: str, speed: float, band: float = 0.13):
    """Min and max of a WBDS column over trials within ``band`` m/s of ``speed``."""
    if not WBDS.exists():
        pytest.skip("shared gait data not available")
    data = np.genfromtxt(WBDS, delimiter=",", names=True, dtype=None, encoding="utf-8")
    near = np.abs(data["Speed"] - speed) <= band
    assert near.sum() >= 20
    values = data[column][near].astype(float)
    return values.min(), values.max()


def test_step_length_and_cadence_lie_in_the_measured_range(run_of):
    summary, run = run_of("rimea1_corridor")
    steps = run.footsteps()
    level = steps.step_length[2:-2]  # steady walking: drop the start and the stop
    durations = np.diff(steps.time)[2:-2]
    lo, hi = _measured_range("StepLength", 1.33)  # [m]
    assert lo <= level.mean() <= hi
    clo, chi = _measured_range("Cadence", 1.33)  # [steps/min]
    cadence = 60.0 / durations.mean()
    assert clo <= cadence <= chi
    # and the speed that results is the free speed
    assert level.mean() / durations.mean() == pytest.approx(1.33, rel=0.05)


def _stair_run(run_of):
    summary, run = run_of("stairs_up_down")
    world = build_world(load_scenario(run.scenario_path))
    return summary, run.footsteps(), world.terrain


def test_every_stair_foothold_rests_fully_on_one_tread(run_of):
    from planners import Leg

    summary, steps, terrain = _stair_run(run_of)
    leg = Leg.from_body_height(summary["agents"][0]["body_height_m"])
    xy = np.column_stack([steps.x, steps.y])
    d = np.column_stack([np.cos(steps.heading), np.sin(steps.heading)])
    on_stairs = steps.kind == 2
    assert on_stairs.sum() >= 12  # both flights were walked on
    # heel, ankle and toe points all at the foothold's height: the whole foot on a tread
    # (to 1 mm: a riser line belongs to one tread, and plans are reused to 0.5 mm)
    for offset in np.linspace(-leg.heel_offset + 1e-3, leg.toe_offset - 1e-3, 9):
        z = terrain.height(xy + offset * d)
        np.testing.assert_allclose(z, steps.z, atol=1e-3)


def test_descending_the_flight_is_faster_than_climbing_it(run_of):
    summary, steps, terrain = _stair_run(run_of)
    assert summary["agents"][0]["arrived"]
    up = (steps.kind == 2) & (steps.step_height > 0)
    down = (steps.kind == 2) & (steps.step_height < 0)
    assert up.sum() >= 5 and down.sum() >= 5

    def horizontal_speed(mask):
        i = np.flatnonzero(mask)
        dx = steps.x[i[-1]] - steps.x[i[0]]
        return dx / (steps.time[i[-1]] - steps.time[i[0]])

    v_up, v_down = horizontal_speed(up), horizontal_speed(down)
    assert v_down > v_up
    # Weidmann (1993): 0.610 m/s up, 0.694 m/s down (horizontal)
    assert 0.45 <= v_up <= 0.75 and 0.5 <= v_down <= 0.85


def test_planned_walker_strides_over_the_obstacle_the_fixed_one_steps_on_it(run_of):
    """Chen & Li, Fig. 11."""
    summary, run = run_of("obstacle_stride")
    steps = run.footsteps()
    planned = steps.group == "planned"
    assert steps.on_obstacle[planned].sum() == 0
    assert steps.on_obstacle[~planned].sum() >= 1
    agents = {a["group"]: a for a in summary["agents"]}
    assert agents["planned"]["energy_per_metre_J_per_kg_m"] < \
        agents["unplanned"]["energy_per_metre_J_per_kg_m"]
    assert agents["unplanned"]["climb_m"] > 0 == agents["planned"]["climb_m"]


def test_no_step_is_quicker_than_the_quickest_measured(run_of):
    """Planned steps keep to the highest cadence WBDS measured (2.48 steps/s; issue 11
    item 5): on the rough park the planners plan steps of 0.1-0.27 m, which at the
    walking speed lasted 0.06-0.19 s (163 of 2,470 steps) — about two frames at 25 fps,
    too quick for a pose to follow."""
    from crowdwalk.gait.datasets import normative

    _, run = run_of("uneven_park", duration=15.0)
    steps = run.footsteps()
    shortest = 1.0 / normative()["cadence_max"]["steps_per_s"]
    assert 0.39 < shortest < 0.42  # WBDS: 148.8 steps/min at most
    for agent in np.unique(steps.agent):
        t = np.sort(steps.time[steps.agent == agent])
        assert np.all(np.diff(t) >= shortest - 2e-5)  # footsteps.csv keeps 10 µs
