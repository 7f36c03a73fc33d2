"""Scenario files: every bundled file is valid; bad files get one clear line with the line."""

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.errors import InputError
from crowdwalk.scenario import (
    DEFAULT_BODY_HEIGHT,
    DEFAULT_FREE_SPEED,
    Normal,
    SpawnTimes,
    load_scenario,
    parse_scenario,
    scenario_json_schema,
)
from crowdwalk.terrain import TerrainKind
from crowdwalk.world import build_world

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = sorted((ROOT / "scenarios").glob("*.yaml"))
runner = CliRunner()

MINIMAL = """\
terrain:
  extent: [0, 0, 20, 10]
  features:
    - type: stairs
      start: [5, 2]
      heading: 90
      width: 2
      going: 0.3
      rise: 0.15
      steps: 3
routes:
  nodes:
    - {name: a, xy: [1, 5]}
    - {name: b, xy: [18, 5]}
  edges:
    - {from: a, to: b, width: 2}
groups:
  - name: g
    count: 3
    spawn: a
    destinations: [b]
simulation:
  duration: 10
"""


def test_there_are_bundled_scenarios():
    assert any(p.name == "quickstart.yaml" for p in SCENARIOS)


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.name)
def test_bundled_scenario_is_valid_and_builds(path):
    sc = load_scenario(path)
    world = build_world(sc)
    for g in sc.groups:
        spawn = g.spawn if isinstance(g.spawn, str) else None
        for dest in g.destinations:
            if spawn is not None and spawn != dest:
                assert len(world.routes.route(spawn, dest)) >= 2
            spawn = dest
    assert world.terrain.mesh().area > 0
    result = runner.invoke(app, ["validate", str(path)])
    assert result.exit_code == 0, result.output
    assert "valid" in result.output


def test_quickstart_has_the_promised_features():
    sc = load_scenario(ROOT / "scenarios" / "quickstart.yaml")
    kinds = {f.type for f in sc.terrain.features}
    assert {"stairs", "block", "slope", "ramp"} <= kinds
    assert {g.planner for g in sc.groups} >= {"best_first_multistart", "fixed"}
    assert 20 <= sum(g.count for g in sc.groups) <= 200


def test_degrees_in_file_radians_in_world():
    world = build_world(parse_scenario(MINIMAL))
    ter = world.terrain
    # heading 90 deg: the flight climbs along +y from y = 2
    z = ter.height([[5, 1.9], [5, 2.1], [5, 2.85], [5.0, 2.4]])
    np.testing.assert_allclose(z, [0, 0.15, 0.45, 0.3], atol=1e-12)
    assert ter.kind([[5, 2.1]])[0] == TerrainKind.STAIRS


def test_defaults_cite_body_height_and_free_speed():
    sc = parse_scenario(MINIMAL)
    g = sc.groups[0]
    assert g.body_height == DEFAULT_BODY_HEIGHT and g.body_height.mean == 1.71
    assert g.free_speed == DEFAULT_FREE_SPEED and g.free_speed.mean == 1.34
    assert g.free_speed.sd == 0.26 and g.planner == "best_first_multistart"
    assert sc.simulation.seed == 0 and sc.outputs.poses is True


def test_normal_sampling_is_seeded_and_bounded():
    n = Normal(mean=1.34, sd=0.26, min=0.8, max=1.8)
    a = n.sample(np.random.default_rng(3), 5000)
    b = n.sample(np.random.default_rng(3), 5000)
    np.testing.assert_array_equal(a, b)
    assert a.min() >= 0.8 and a.max() <= 1.8
    assert abs(a.mean() - 1.34) < 0.02


def test_spawn_times():
    np.testing.assert_allclose(SpawnTimes(start=1, interval=0.5).times(3), [1, 1.5, 2])
    np.testing.assert_allclose(SpawnTimes(rate=4).times(3), [0, 0.25, 0.5])
    np.testing.assert_allclose(SpawnTimes().times(2), [0, 0])


def mutate(text, old, new):
    assert old in text
    return text.replace(old, new, 1)


def line_of(text, needle):
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


@pytest.mark.parametrize("old,new,pattern,needle", [
    ("count: 3", "count: 0", r"groups\[0\]\.count must be ≥ 1; got 0\.", "count: 0"),
    ("count: 3", "count: 2.5", r"groups\[0\]\.count must be an integer; got 2\.5\.", "count"),
    ("count: 3", "count: 3\n    colour: red", r"groups\[0\]\.colour is not a known key\.",
     "colour"),
    ("destinations: [b]", "destinations: [c]",
     r"groups\[0\]\.destinations\[0\] must be one of the route nodes \['a', 'b'\]; got 'c'\.",
     "destinations"),
    ("spawn: a", "spawn: z", r"groups\[0\]\.spawn must be one of the route nodes", "spawn: z"),
    ("rise: 0.15", "rise: -0.15", r"terrain\.features\[0\]\.rise must be > 0\.0 \[m\]; "
     r"got -0\.15\.", "rise:"),
    ("type: stairs", "type: stair", r"terrain\.features\[0\] must be a known type, one of "
     r"'block', 'stairs', .*; got 'stair'\.", "type: stair"),
    ("duration: 10", "duration: ten", r"simulation\.duration must be a number \[s\]; got 'ten'",
     "duration"),
    ("destinations: [b]", "destinations: [b]\n    free_speed: {mean: 1.3, sd: -1}",
     r"groups\[0\]\.free_speed\.sd must be ≥ 0\.0 \[m/s\]; got -1\.", "free_speed"),
    ("destinations: [b]", "destinations: [b]\n    planner: smart",
     r"groups\[0\]\.planner must be one of 'best_first', 'best_first_multistart', 'fixed' "
     r"or 'optimal'; got 'smart'",
     "planner"),
    ("    count: 3\n", "", r"groups\[0\]\.count is required\.", "- name: g"),
    ("width: 2}", "width: 2, oneway: maybe}", r"routes\.edges\[0\]\.oneway must be true or "
     r"false; got 'maybe'", "oneway"),
    ("{from: a, to: b, width: 2}", "{from: a, to: q, width: 2}",
     r"routes\.edges\[0\]\.to must be one of the route nodes", "to: q"),
])
def test_bad_file_names_field_and_line(old, new, pattern, needle):
    text = mutate(MINIMAL, old, new)
    with pytest.raises(InputError, match=pattern) as info:
        parse_scenario(text, "s.yaml")
    line = line_of(text, needle)
    assert str(info.value).startswith(f"s.yaml:{line}: "), str(info.value)
    assert "\n" not in str(info.value)


def test_yaml_errors_and_duplicates():
    with pytest.raises(InputError, match=r"s\.yaml:\d+: not valid YAML"):
        parse_scenario("terrain: [1, 2\nroutes: {", "s.yaml")
    with pytest.raises(InputError, match=r"s\.yaml:1: scenario must be a mapping"):
        parse_scenario("- 1\n- 2\n", "s.yaml")
    dup = MINIMAL + "simulation:\n  duration: 5\n"
    with pytest.raises(InputError, match=r"simulation is given twice"):
        parse_scenario(dup, "s.yaml")
    with pytest.raises(InputError, match="could not determine a constructor"):
        parse_scenario("!!python/object:os.system {}\n", "s.yaml")


def test_world_geometry_errors_are_input_errors():
    text = mutate(MINIMAL, "xy: [18, 5]", "xy: [25, 5]")
    with pytest.raises(InputError, match=r"RouteGraph\.nodes\['b'\]\.xy must be inside"):
        build_world(parse_scenario(text))
    text = mutate(MINIMAL, "spawn: a", "spawn: [[0, 0], [30, 0], [30, 3]]")
    with pytest.raises(InputError, match=r"groups\[0\]\.spawn must be inside the terrain"):
        build_world(parse_scenario(text))


def test_unreachable_destination_is_an_input_error():
    text = mutate(MINIMAL, "width: 2}", "width: 2, oneway: true}")
    text = mutate(text, "spawn: a", "spawn: b").replace("destinations: [b]", "destinations: [a]")
    with pytest.raises(InputError, match=r"groups\[0\]\.destinations\[0\] must be reachable "
                                         r"from 'b' .*; got 'a'\."):
        build_world(parse_scenario(text))


def test_graphml_routes_relative_to_file(tmp_path):
    sc = build_world(parse_scenario(MINIMAL))
    sc.routes.to_graphml(tmp_path / "routes.graphml")
    text = MINIMAL.split("routes:")[0] + "routes:\n  graphml: routes.graphml\n" + \
        "groups:" + MINIMAL.split("groups:")[1]
    (tmp_path / "s.yaml").write_text(text)
    world = build_world(load_scenario(tmp_path / "s.yaml"))
    assert set(world.routes.graph.edges) == {("a", "b"), ("b", "a")}
    bad = text.replace("destinations: [b]", "destinations: [zz]")
    (tmp_path / "bad.yaml").write_text(bad)
    with pytest.raises(InputError, match="destinations"):
        load_scenario(tmp_path / "bad.yaml")


def test_cli_bad_file_exit_2_one_line(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(mutate(MINIMAL, "count: 3", "count: -2"))
    result = runner.invoke(app, ["validate", str(path)])
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "groups[0].count" in lines[0] and ":19:" in lines[0]


def test_schema_command_prints_json_schema():
    schema = scenario_json_schema()
    assert schema["additionalProperties"] is False
    assert {"terrain", "routes", "groups", "simulation"} <= set(schema["required"])
    result = runner.invoke(app, ["schema"])
    assert result.exit_code == 0
    printed = yaml.safe_load(result.output)
    assert printed["properties"].keys() == schema["properties"].keys()
    edge = printed["$defs"]["EdgeSpec"]["properties"]
    assert "from" in edge and math.isfinite(len(edge))


def test_rough_ground_from_noise_inline_and_file(tmp_path):
    np.save(tmp_path / "h.npy", np.array([[0.0, 0.1], [0.2, 0.3]]))
    (tmp_path / "h.csv").write_text("0,0.1\n0.2,0.3\n")
    feats = {
        "noise": "{type: rough, origin: [8, 6], cell: 0.25, size: [2, 2], amplitude: 0.02, "
                 "seed: 4}",
        "inline": "{type: rough, origin: [8, 6], cell: 1.0, heights: [[0, 0.1], [0.2, 0.3]]}",
        "npy": "{type: rough, origin: [8, 6], cell: 1.0, heights_file: h.npy}",
        "csv": "{type: rough, origin: [8, 6], cell: 1.0, heights_file: h.csv}",
    }
    for name, feat in feats.items():
        text = mutate(MINIMAL, "  features:\n", f"  features:\n    - {feat}\n")
        (tmp_path / f"{name}.yaml").write_text(text)
        ter = build_world(load_scenario(tmp_path / f"{name}.yaml")).terrain
        assert ter.kind([[8.5, 6.5]])[0] == TerrainKind.ROUGH
        if name != "noise":
            assert ter.height([[9.0, 7.0]])[0] == pytest.approx(0.3)
    text = mutate(MINIMAL, "  features:\n", "  features:\n    - {type: rough, origin: [8, 6], "
                  "cell: 1.0}\n")
    with pytest.raises(InputError, match="give exactly one of amplitude"):
        parse_scenario(text, "s.yaml")
