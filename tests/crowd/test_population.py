"""Heterogeneous populations drawn from the scenario's distributions."""

from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml

from crowdwalk.population import Population, cadence_at, step_length_at
from crowdwalk.scenario import load_scenario
from crowdwalk.world import build_world

SCENARIOS = Path(__file__).parents[2] / "scenarios"


def _population(tmp_path, seed=5, count=400):
    sc = yaml.safe_load((SCENARIOS / "bottleneck.yaml").read_text())
    sc["groups"][0].update(count=count, body_height={"mean": 1.70, "sd": 0.08},
                           free_speed={"mean": 1.30, "sd": 0.2, "min": 0.8, "max": 1.8})
    sc["groups"].append({"name": "late", "count": 10, "spawn": "outside",
                         "spawn_times": {"start": 5.0, "interval": 2.0},
                         "destinations": ["room"], "planner": "fixed"})
    sc["simulation"]["seed"] = seed
    path = tmp_path / "pop.yaml"
    path.write_text(yaml.safe_dump(sc))
    scenario = load_scenario(path)
    world = build_world(scenario)
    return Population.from_scenario(scenario, world.routes, np.random.default_rng(seed)), world


def test_distributions_bounds_and_groups(tmp_path):
    pop, world = _population(tmp_path)
    first = pop.group == 0
    assert first.sum() == 400 and (~first).sum() == 10
    assert pop.body_height[first].mean() == pytest.approx(1.70, abs=0.02)
    assert pop.body_height[first].std() == pytest.approx(0.08, abs=0.015)
    assert pop.free_speed[first].min() >= 0.8 and pop.free_speed[first].max() <= 1.8
    assert pop.free_speed[first].std() > 0.1  # heterogeneous, not one speed
    np.testing.assert_allclose(pop.body_height, np.round(pop.body_height, 2))
    np.testing.assert_allclose(pop.spawn_time[~first], 5.0 + 2.0 * np.arange(10))
    assert np.all(pop.spawn_time[first] == 0.0)
    assert list(pop.planner) == ["best_first_multistart"] * 400 + ["fixed"] * 10
    room = world.routes.node_area("room")
    assert shapely.contains_xy(room, pop.spawn_xy[first, 0], pop.spawn_xy[first, 1]).all()
    assert pop.destinations[0] == ("outside",) and pop.destinations[-1] == ("room",)


def test_same_seed_same_population_other_seed_other(tmp_path):
    a, _ = _population(tmp_path, seed=5)
    b, _ = _population(tmp_path, seed=5)
    c, _ = _population(tmp_path, seed=6)
    np.testing.assert_array_equal(a.body_height, b.body_height)
    np.testing.assert_array_equal(a.spawn_xy, b.spawn_xy)
    assert not np.array_equal(a.body_height, c.body_height)


def test_with_planner_keeps_the_agents(tmp_path):
    pop, _ = _population(tmp_path, count=20)
    fixed = pop.with_planner("fixed")
    assert set(fixed.planner) == {"fixed"}
    np.testing.assert_array_equal(fixed.body_height, pop.body_height)


def test_gait_relations_follow_the_normative_data():
    # Fukuchi et al. (2018) fits shipped in normative.json: at 1.33 m/s about 0.67 m and
    # 2 steps/s, and speed = step length x cadence within a few per cent
    v = np.array([0.8, 1.33, 1.6])
    assert step_length_at(1.33) == pytest.approx(0.67, abs=0.03)
    assert cadence_at(1.33) == pytest.approx(2.0, abs=0.08)
    np.testing.assert_allclose(step_length_at(v) * cadence_at(v), v, rtol=0.08)


def test_bad_population_is_rejected():
    with pytest.raises(ValueError, match=r"Population.body_height must be in \[0.5, 2.5\] \[m\]"):
        Population(group=np.zeros(1, int), group_names=("g",), planner_names=("fixed",),
                   body_height=np.array([3.0]), free_speed=np.array([1.0]),
                   spawn_time=np.zeros(1), spawn_xy=np.zeros((1, 2)),
                   origin=np.array(["a"], dtype=object),
                   destinations=np.array([("b",)], dtype=object).reshape(1),
                   route_start=np.full((1, 2), np.nan))
