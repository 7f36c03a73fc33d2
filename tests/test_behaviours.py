"""Behaviours other simulators offer: obstacles, exit choice, start density, arrivals,
measurement lines and areas (PedPy), the verification suite's fast subset."""

from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.errors import InputError
from crowdwalk.population import Population
from crowdwalk.record import open_run
from crowdwalk.routes import lattice_points
from crowdwalk.scenario import SpawnTimes, load_scenario, parse_scenario
from crowdwalk.world import build_world

SCENARIOS = Path(__file__).parents[1] / "scenarios"


def _text(name: str) -> str:
    return (SCENARIOS / f"{name}.yaml").read_text()


def _with(name: str, edit) -> str:
    data = yaml.safe_load(_text(name))
    edit(data)
    return yaml.safe_dump(data, sort_keys=False)


# --- obstacles ----------------------------------------------------------------------


def test_obstacles_are_holes_and_routes_go_round_them():
    world = build_world(load_scenario(SCENARIOS / "obstacles.yaml"))
    area = world.routes.walkable_area
    pillar = shapely.box(9, 3, 11, 5)
    wall = shapely.box(14.9, 4.5, 15.1, 7.0)  # the WKT line, 0.2 m thick
    assert area.intersection(pillar).area < 1e-9 and area.intersection(wall).area < 1e-9
    assert area.covers(shapely.Point(10, 2.5)) and area.covers(shapely.Point(15, 4.3))
    path = shapely.LineString(world.routes.path("west", "east"))
    assert path.distance(pillar) >= 0.3 and path.distance(wall) >= 0.3
    assert area.buffer(1e-6).covers(path)


def test_shortest_walk_inside_the_walkable_area():
    routes = build_world(load_scenario(SCENARIOS / "obstacles.yaml")).routes
    straight = routes.shortest_walk((7.0, 2.0), (7.0, 6.0))
    assert straight.shape == (2, 2)  # in sight: one straight leg
    walk = shapely.LineString(routes.shortest_walk((7.0, 4.0), (13.0, 4.0)))
    assert routes.walkable_area.buffer(1e-6).covers(walk)
    # legs from the two ends may cut a corner of the 0.25 m offset a little
    assert walk.distance(shapely.box(9, 3, 11, 5)) >= 0.2
    # round the 2 m pillar's corners, 0.25 m off: 2 (sqrt(2^2 + 1.25^2)) = 4.72 m + 2 m
    assert 6.0 < walk.length < 7.0


def test_obstacle_run_keeps_bodies_out(tmp_path):
    summary = run_scenario(SCENARIOS / "obstacles.yaml", tmp_path,
                           overrides=RunOverrides(max_agents=10, poses=False))
    assert summary["agents_arrived"] == 10 and summary["max_overlap_m"] <= 1e-6
    t = open_run(tmp_path).trajectories()
    holes = shapely.union_all([shapely.box(9, 3, 11, 5), shapely.box(14.9, 4.5, 15.1, 7.0)])
    assert shapely.distance(holes, shapely.points(t.x, t.y)).min() >= 0.15  # a body radius


@pytest.mark.parametrize("obstacle, message", [
    ({"wkt": "POLYGON ((0 0, 1 0"}, "not valid WKT"),
    ({"wkt": "POINT (1 1)"}, "polygon or a line"),
    ({"polygon": [[0, 0], [1, 0], [2, 0]]}, "positive area"),
    ({"polygon": [[0, 0], [1, 0], [1, 1]], "wkt": "POINT (1 1)"}, "either polygon or wkt"),
])
def test_bad_obstacles_name_the_line(obstacle, message):
    text = _with("obstacles", lambda d: d.update(obstacles=[obstacle]))
    with pytest.raises(InputError, match=message) as err:
        parse_scenario(text, "o.yaml")
    assert str(err.value).startswith("o.yaml:") and "obstacles[0]" in str(err.value)


# --- exit choice --------------------------------------------------------------------


def _population(text: str):
    sc = parse_scenario(text)
    world = build_world(sc)
    return sc, Population.from_scenario(sc, world.routes, np.random.default_rng(sc.simulation.seed))


def _exits(pop, group: str) -> np.ndarray:
    gi = pop.group_names.index(group)
    return np.array([d[-1] for d in pop.destinations[pop.group == gi]])


def test_nearest_exit_by_route_cost_from_where_each_stands():
    _, pop = _population(_text("exit_choice"))
    gi = pop.group_names.index("near")
    xy = pop.spawn_xy[pop.group == gi]
    exits = _exits(pop, "near")
    # the near group stands along the south wall: west of x = 10 the west door is nearer
    # (by the straight line to the door, then 2.5 m out), east of it the east door; the
    # north door (at x = 14, 8-11 m away) is never the nearest
    doors = {"west": (0.0, 6.0), "east": (20.0, 6.0), "north": (14.0, 12.0)}
    cost = {k: np.hypot(*(xy - v).T) for k, v in doors.items()}
    expect = np.array(list(doors))[np.argmin(np.column_stack(list(cost.values())), axis=1)]
    assert (exits == expect).all() and {"west", "east"} <= set(exits)


def test_least_congested_spreads_over_the_exits_and_weights_follow_their_shares():
    text = _with("exit_choice", lambda d: d["groups"][2].update(count=600))
    _, pop = _population(text)
    queue = _exits(pop, "queue")
    counts = {e: int((queue == e).sum()) for e in ("west", "east", "north")}
    # 30 walkers along the north wall: the north door is nearest for most, but with
    # the queue of those who chose it before over 1.56 /s, some go elsewhere
    assert counts["north"] < 30 and counts["north"] > max(counts["west"], counts["east"])
    signs = _exits(pop, "signs")
    share = np.array([(signs == e).mean() for e in ("east", "north", "west")])
    np.testing.assert_allclose(share, [0.6, 0.3, 0.1], atol=0.05)


def test_exit_choice_schema_errors():
    def bad(d):
        d["groups"][2]["exit_choice"] = {"among": ["east", "north"], "rule": "weights",
                                         "weights": [1.0]}
    with pytest.raises(InputError, match="one weight per exit"):
        parse_scenario(_with("exit_choice", bad), "e.yaml")

    def unknown(d):
        d["groups"][0]["exit_choice"]["among"][1] = "roof"
    with pytest.raises(InputError, match=r"groups\[0\].exit_choice.among\[1\] must be one of"):
        parse_scenario(_with("exit_choice", unknown), "e.yaml")


# --- start density and arrivals -----------------------------------------------------


def test_lattice_points_have_the_density_asked_for():
    rng = np.random.default_rng(1)
    area = shapely.box(0, 0, 10, 10)
    for density in (0.5, 2.0, 5.0):
        pts = lattice_points(area, 40, density, rng, front=(10, 5))
        a = np.sqrt(2 / (np.sqrt(3) * density))
        from scipy.spatial import cKDTree

        d, _ = cKDTree(pts).query(pts, k=2)
        np.testing.assert_allclose(d[:, 1], a, rtol=1e-9)  # every point's nearest: a
        # the points form one block: its hull holds about 40 / density m²
        hull = shapely.MultiPoint(pts).convex_hull.buffer(a / 2).area
        assert 0.8 < 40 / hull / density < 1.25
    with pytest.raises(InputError, match="density"):
        lattice_points(area, 100, 0.5, rng)  # 200 m² would be needed


def test_group_density_starts_the_block_at_that_density():
    _, pop = _population(_text("arrivals_density"))
    xy = pop.spawn_xy[pop.group == pop.group_names.index("block")]
    assert xy[:, 0].min() > 5.0  # next to the side the group walks to (east)
    from scipy.spatial import cKDTree

    d, _ = cKDTree(xy).query(xy, k=2)
    np.testing.assert_allclose(d[:, 1], np.sqrt(2 / (np.sqrt(3) * 2.0)), rtol=1e-9)


def test_poisson_arrivals():
    rng = np.random.default_rng(7)
    t = SpawnTimes(start=5.0, rate=2.0, process="poisson").times(4000, rng)
    gaps = np.diff(t)
    assert t[0] == 5.0 and (gaps >= 0).all()
    assert gaps.mean() == pytest.approx(0.5, rel=0.05)
    assert gaps.std() / gaps.mean() == pytest.approx(1.0, rel=0.05)  # exponential: CV 1
    regular = SpawnTimes(start=5.0, rate=2.0).times(5)
    np.testing.assert_allclose(regular, [5.0, 5.5, 6.0, 6.5, 7.0])
    again = SpawnTimes(start=5.0, rate=2.0, process="poisson").times(4000,
                                                                     np.random.default_rng(7))
    np.testing.assert_array_equal(t, again)
    with pytest.raises(ValueError, match="poisson"):
        SpawnTimes(process="poisson")


# --- measurement --------------------------------------------------------------------


def test_measurement_lines_and_areas_analysed_with_pedpy(tmp_path):
    from crowdwalk.analysis import analyse_run

    summary = run_scenario(SCENARIOS / "arrivals_density.yaml", tmp_path,
                           overrides=RunOverrides(max_agents=25, poses=False, duration=30.0))
    result = summary["measurement"]  # a run with measurement lines or areas analyses them
    assert analyse_run(tmp_path, plots=False) == result
    out = tmp_path / "analysis"
    for name in ("area_middle.csv", "area_middle.png", "line_gate.csv", "line_gate.png"):
        assert (out / name).stat().st_size > 0
    # independent count: trajectories that go from x < 33 to x >= 33
    t = open_run(tmp_path).trajectories()
    crossed = 0
    for i in np.unique(t.id):
        x = t.x[t.id == i]
        crossed += int(np.any((x[:-1] < 33.0) & (x[1:] >= 33.0)))
    line = result["lines"][0]
    assert line["crossings"] == crossed > 15
    rows = np.genfromtxt(out / "line_gate.csv", delimiter=",", names=True)
    assert rows["crossed"][-1] == crossed
    area = result["areas"][0]
    # classic density: walkers inside the 4 x 3.6 m area over its 14.4 m², per frame
    inside = (t.x >= 18) & (t.x <= 22) & (t.y >= 1.2) & (t.y <= 4.8)
    frames = np.unique(t.frame)
    per_frame = np.bincount(t.frame[inside], minlength=frames.max() + 1)[frames] / 14.4
    assert area["peak_density_per_m2"] == pytest.approx(per_frame.max(), abs=1e-9)
    assert 0.3 < area["speed_m_s"] < 1.6
    assert open_run(tmp_path).summary["measurement"] == result


def test_verify_fast_subset(tmp_path):
    from crowdwalk.verify import FAST, run_verification

    out = tmp_path / "verification.md"
    checks = run_verification(only=FAST, out=out, echo=lambda s: None)
    assert [c.passed for c in checks] == [True] * len(checks)
    assert "| RiMEA 1 |" in out.read_text()


def test_verify_cli_runs_and_names_the_crowd_model(tmp_path):
    from typer.testing import CliRunner

    from crowdwalk.cli import app

    out = tmp_path / "verification.md"
    result = CliRunner().invoke(app, ["verify", "--only", "rimea1", "--crowd-model",
                                      "headway_s175", "--out", str(out)])
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert "`crowdwalk verify --only rimea1 --crowd-model headway_s175`" in text
    assert "| RiMEA 1 |" in text and "| pass |" in text
    bad = CliRunner().invoke(app, ["verify", "--only", "rimea1", "--crowd-model", "fast",
                                   "--out", str(out)])
    assert bad.exit_code == 2 and "crowd.model must be one of" in bad.output


def test_rimea_15_corner_edges_have_the_straights_lengths(monkeypatch, tmp_path):
    """RiMEA 15's corner corridor: its inner edge is as long as the short straight and its
    outer edge as the long one (from the start area to the end area)."""
    from crowdwalk import verify

    built = {}

    def fake_run(data, folder, params=None):
        built[data["name"]] = data
        summary = {"agents": [{"arrived": True, "start_time_s": 0.0, "travel_time_s": 1.0}]}
        return verify._Run(folder, summary, None)

    monkeypatch.setattr(verify, "_run", fake_run)
    verify.rimea_15(True, tmp_path)

    def area(data, name):
        node = next(n for n in data["routes"]["nodes"] if n["name"] == name)
        return shapely.Polygon(node["area"]).bounds  # (x0, y0, x1, y1)

    def straight_length(data):
        return area(data, "end")[0] - area(data, "start")[2]

    corner = built["rimea15_corner"]
    w = corner["routes"]["edges"][0]["width"]
    turn = next(n["xy"] for n in corner["routes"]["nodes"] if n["name"] == "turn")
    x_start, y_end = area(corner, "start")[2], area(corner, "end")[1]
    outer = (turn[0] + w / 2 - x_start) + (y_end - (turn[1] - w / 2))
    inner = (turn[0] - w / 2 - x_start) + (y_end - (turn[1] + w / 2))
    assert inner == pytest.approx(straight_length(built["rimea15_short"]))
    assert outer == pytest.approx(straight_length(built["rimea15_long"]))
