"""Walker styles: attributes, presets and locomotion parameters from the scenario file."""

import math

import numpy as np
import pytest
import yaml

from crowdwalk.errors import InputError
from crowdwalk.population import Population
from crowdwalk.scenario import parse_scenario
from crowdwalk.style import (
    ATTRIBUTES,
    LOCKS,
    PRESET_NAMES,
    PRESETS,
    Style,
    normal_step_length,
)
from crowdwalk.world import build_world

BASE = {
    "terrain": {"extent": [-2, -1, 22, 7]},
    "routes": {"nodes": [{"name": "a", "xy": [1, 3], "area": [[0, 0], [4, 0], [4, 6], [0, 6]]},
                         {"name": "b", "xy": [19, 3]}],
               "edges": [{"from": "a", "to": "b", "width": 5}]},
    "simulation": {"duration": 5, "seed": 3},
}


def _population(groups, seed=3):
    data = dict(BASE, groups=[dict({"count": 4, "spawn": "a", "destinations": ["b"]}, **g)
                              for g in groups])
    data["simulation"] = dict(BASE["simulation"], seed=seed)
    sc = parse_scenario(yaml.safe_dump(data), "styles.yaml")
    world = build_world(sc)
    return sc, Population.from_scenario(sc, world.routes, np.random.default_rng(seed))


def test_presets_round_trip_through_the_scenario_file():
    groups = [{"name": p, "style": {"preset": p}} for p in PRESET_NAMES]
    _, pop = _population(groups)
    for gi, name in enumerate(PRESET_NAMES):
        s = pop.style.take(pop.group == gi)
        assert set(s.preset_name) == {name}
        for a in ATTRIBUTES:
            expected = PRESETS[name].get(a.name, a.default)
            got = getattr(s, a.name) / a.to_si
            np.testing.assert_allclose(got, expected, atol=1e-12, err_msg=f"{name}.{a.name}")
        lock = PRESETS[name].get("lock")
        assert set(LOCKS[c] for c in s.lock) == {next(iter(lock)) if lock else "none"}
    proud = pop.style.take(pop.group == PRESET_NAMES.index("proud"))
    np.testing.assert_allclose(proud.velocity, 1.11)  # 4 km/h, rounded to 1 cm/s
    np.testing.assert_allclose(proud.step_length, 0.75)
    tired = pop.free_speed[pop.group == PRESET_NAMES.index("tired")]
    np.testing.assert_allclose(tired, 0.83)  # 3 km/h


def test_attribute_overrides_preset_and_spreads_are_seeded():
    g = [{"name": "t", "count": 300, "spawn": "a",
          "style": {"preset": "tired", "arm_swing": {"mean": 20, "sd": 4}, "torso_tilt": 2}}]
    _, pop = _population(g)
    arm = np.rad2deg(pop.style.arm_swing)
    assert arm.mean() == pytest.approx(20, abs=0.7) and arm.std() == pytest.approx(4, abs=0.6)
    np.testing.assert_allclose(np.rad2deg(pop.style.torso_tilt), 2.0)
    np.testing.assert_allclose(np.rad2deg(pop.style.torso_sway), PRESETS["tired"]["torso_sway"])
    _, again = _population(g)
    np.testing.assert_array_equal(again.style.arm_swing, pop.style.arm_swing)
    _, other = _population(g, seed=4)
    assert not np.array_equal(other.style.arm_swing, pop.style.arm_swing)


def test_styles_do_not_change_the_draws_of_plain_scenarios():
    _, plain = _population([{"name": "g", "count": 20}])
    _, styled = _population([{"name": "g", "count": 20, "gait": "klaw",
                              "style": {"preset": "loose"}}])
    np.testing.assert_array_equal(plain.body_height, styled.body_height)
    np.testing.assert_array_equal(plain.spawn_xy, styled.spawn_xy)
    assert list(styled.gait) == ["klaw"] * 20 and list(plain.gait) == ["elevation_angles"] * 20


@pytest.mark.parametrize("style, lock, text", [
    ({"arm_swing": 100}, None, "groups[0].style.arm_swing: must be in [0, 45] [deg]; got 100."),
    ({"preset": "sad"}, None, "groups[0].style.preset must be one of"),
    ({"bouncy": 1}, None, "groups[0].style.bouncy is not a known key."),
    (None, {"step_length": 0.7, "velocity": 1.0, "step_frequency": 1.5}, "groups[0].lock"),
    (None, {}, "groups[0].lock"),
])
def test_bad_styles_name_the_field(style, lock, text):
    g = {"name": "g"}
    if style is not None:
        g["style"] = style
    if lock is not None:
        g["lock"] = lock
    with pytest.raises(InputError) as err:
        _population([g])
    assert text in str(err.value) and "styles.yaml:" in str(err.value)


def test_normal_mode_follows_the_relation_and_locks_hold():
    h = np.full(5, 1.75)
    speed = np.linspace(0.6, 1.8, 5)
    normal = Style.default(h, 1.34)
    sl, f = normal.locomotion(speed, h)
    np.testing.assert_allclose(sl, normal_step_length(speed, h))
    np.testing.assert_allclose(sl * f, speed)
    assert np.all(np.diff(sl) > 0) and np.all(np.diff(f) > 0)  # both grow with speed
    locked = normal.with_values(step_length=0.75, lock=LOCKS.index("step_length"))
    sl, f = locked.locomotion(speed, h)
    np.testing.assert_allclose(sl, 0.75)
    np.testing.assert_allclose(f, speed / 0.75)
    cadence = normal.with_values(step_frequency=2.0, lock=LOCKS.index("step_frequency"))
    sl, f = cadence.locomotion(speed, h)
    np.testing.assert_allclose(f, 2.0)
    np.testing.assert_allclose(sl, speed / 2.0)


def test_style_rejects_values_out_of_range():
    s = Style.default(np.ones(2) * 1.7, 1.3)
    with pytest.raises(InputError, match="Style.pelvic_list must be in"):
        s.with_values(pelvic_list=math.radians(30))
    with pytest.raises(InputError, match="elbow_max"):
        s.with_values(elbow_min=math.radians(50), elbow_max=math.radians(40))


def test_summary_and_compare_report_per_style():
    from crowdwalk.compare import _style_lines
    from crowdwalk.style import summary_by_style

    def agent(style, energy, dist, travel, steps=10):
        return {"style": style, "gait": "klaw", "steps": steps, "travel_time_s": travel,
                "distance_m": dist, "energy_J_per_kg": energy, "mean_step_length_m": 0.7,
                "cadence_steps_per_s": 1.8}

    agents = [agent("proud", 30.0, 10.0, 9.0), agent("proud", 50.0, 10.0, None),
              agent("tired", 40.0, 5.0, 12.0), agent("tired", 0.0, 0.0, None, steps=0)]
    table = summary_by_style(agents)
    assert table["proud"]["energy_per_metre_J_per_kg_m"] == pytest.approx(4.0)
    assert table["proud"]["arrived"] == 1 and table["proud"]["travel_time_s"] == 9.0
    assert table["tired"]["agents"] == 1  # the walker that never stepped is left out
    lines = _style_lines(["best_first"], {"best_first": {"agents": agents}})
    assert "| best_first | proud | klaw | 2 | 1 | 9 | 4 | 0.7 | 1.8 |" in lines
