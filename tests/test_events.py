"""Timed events (close / open a corridor, redirect a group) and waiting areas / queues,
measured on what ``crowdwalk run`` writes (trajectories and summary)."""

import re
import sqlite3
from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml
from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.events import door_wall, with_walls
from crowdwalk.crowd.holding import SLOT_SPACING, waiting_positions
from crowdwalk.crowd.run import run_scenario
from crowdwalk.errors import InputError
from crowdwalk.record import open_run
from crowdwalk.scenario import load_scenario, parse_scenario
from crowdwalk.world import build_world

SCENARIOS = Path(__file__).parents[1] / "scenarios"
DOOR_X = 14.75  # the east corridor's door in events.yaml (halfway from x = 12 to 17.5)


def _edited(name: str, edit, tmp_path: Path):
    data = yaml.safe_load((SCENARIOS / f"{name}.yaml").read_text())
    edit(data)
    return parse_scenario(yaml.safe_dump(data, sort_keys=False), str(tmp_path / "s.yaml"))


def _crossings(run: Path, x0: float, *, sign: float = 1.0) -> dict[int, float]:
    """The first time [s] each walker crosses x = x0 going +x (``sign`` -1: going -x)."""
    t = open_run(run).trajectories()
    out = {}
    for i in np.unique(t.id):
        a = t.agent(int(i))
        x = sign * a.x
        k = np.flatnonzero((x[:-1] < sign * x0) & (x[1:] >= sign * x0))
        if k.size:
            out[int(i)] = float(a.time[k[0] + 1])
    return out


# --- events -------------------------------------------------------------------------


def test_closed_door_blocks_and_walkers_turn_to_the_other_exit(tmp_path):
    summary = run_scenario(SCENARIOS / "events.yaml", tmp_path)
    assert summary["complete"] and summary["agents_remaining"] == 0
    assert summary["max_overlap_m"] == 0.0
    close, redirect, reopen = summary["events"]
    assert close["action"] == "close" and 4.0 <= close["time_s"] < 6.0
    east = _crossings(tmp_path, DOOR_X)
    west = _crossings(tmp_path, -2.0, sign=-1.0)
    # nobody passes the door while it is shut; most of the crowd leaves by the west exit
    assert not [t for t in east.values() if close["time_s"] <= t < reopen["time_s"]]
    assert sum(1 for i in west if i < 24) >= 18
    # the staff, redirected at 6 s, end in the office (unless they had left before)
    office = shapely.box(1.5, 9.0, 4.5, 11.5)
    t = open_run(tmp_path).trajectories()
    agents = summary["agents"]
    for i in range(24, 28):
        a = t.agent(i)
        gone = agents[i]["start_time_s"] + agents[i]["travel_time_s"] <= redirect["time_s"]
        assert gone or office.covers(shapely.Point(a.x[-1], a.y[-1]))
    assert close["walkers_rerouted"] >= 15 and redirect["walkers_rerouted"] >= 3


def test_reopened_door_lets_the_waiting_walkers_through(tmp_path):
    def edit(d):
        d["groups"] = [{"name": "crowd", "count": 12, "spawn": d["groups"][0]["spawn"],
                        "destinations": ["east"]}]
        d["events"] = [{"time": 0.0, "action": "close", "corridor": ["east_door", "east"]},
                       {"time": 8.0, "action": "open", "corridor": ["east_door", "east"]}]
        d["simulation"]["duration"] = 40.0
    summary = run_scenario(_edited("events", edit, tmp_path), tmp_path)
    east = _crossings(tmp_path, DOOR_X)
    assert len(east) == 12 and min(east.values()) >= 8.0  # all through, none before 8 s
    assert summary["agents_arrived"] == 12 and summary["max_overlap_m"] == 0.0
    # they stood at the door: without the events the first is through within 4 s
    assert summary["agents"][0]["waiting_s"] > 0.0
    # the trajectory file names each frame's walkable area (JuPedSim v2 frame_data)
    with sqlite3.connect(tmp_path / "trajectories.sqlite") as con:
        rows = con.execute("SELECT f.frame, g.wkt FROM frame_data f JOIN geometry g "
                           "ON f.geometry_hash = g.hash ORDER BY f.frame").fetchall()
    door = shapely.Point(DOOR_X, 4.0)
    shut = [f / 10 for f, wkt in rows if not shapely.from_wkt(wkt).covers(door)]
    assert shut[0] <= 0.1 and shut[-1] == pytest.approx(7.9)  # frames 0.1-7.9 s (10 fps)
    assert len(shut) == 79 and shapely.from_wkt(rows[-1][1]).covers(door)


def test_event_schema_errors_name_file_line_and_field(tmp_path):
    def bad(events):
        data = yaml.safe_load((SCENARIOS / "events.yaml").read_text())
        data["events"] = events
        path = tmp_path / "bad.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path

    cases = [
        ([{"time": 3, "action": "open", "corridor": ["east_door", "east"]}],
         r"bad.yaml:\d+: Scenario.events\[0\].action must be for a corridor that is closed"),
        ([{"time": 3, "action": "close", "corridor": ["east_door", "east"], "at": 0.02}],
         r"bad.yaml:\d+: Scenario.events\[0\].at must be where the door blocks"),
        ([{"time": 3, "action": "close", "corridor": ["east_door", "east"], "at": 1.5}],
         r"bad.yaml:\d+: events\[0\].at must be < 1"),
        ([{"time": 3, "action": "redirect", "group": "staff"}],
         r"redirect needs group and destinations"),
        ([{"time": 3, "action": "close", "corridor": ["west", "east"]}],
         r"events\[0\].corridor must be two nodes joined by a corridor"),
        ([{"time": 3, "action": "close", "corridor": ["west", "nowhere"]}],
         r"bad.yaml:\d+: events\[0\].corridor\[1\] must be one of the route nodes"),
    ]
    runner = CliRunner()
    for events, message in cases:
        result = runner.invoke(app, ["validate", str(bad(events))])
        assert result.exit_code == 2, result.output
        assert "Traceback" not in result.output
        assert len(result.output.strip().splitlines()) == 1
        assert re.search(message, result.output), result.output


# --- waiting areas and queues -------------------------------------------------------


def test_waiting_area_holds_until_its_time_and_the_queue_lets_go_at_its_rate(tmp_path):
    summary = run_scenario(SCENARIOS / "waiting_areas.yaml", tmp_path)
    assert summary["complete"] and summary["agents_arrived"] == 16
    assert summary["max_overlap_m"] == 0.0
    lobby, gate = summary["waiting_areas"]
    assert lobby["entered"] == lobby["released"] == 16 and lobby["first_release_s"] == 15.0
    out_of_lobby = _crossings(tmp_path, 8.0)
    assert len(out_of_lobby) == 16 and min(out_of_lobby.values()) >= 15.0
    through = np.sort(list(_crossings(tmp_path, 16.0).values()))
    assert len(through) == 16
    # 0.5 persons/s: 2 s between releases; without the queue they pass about 0.6 s apart
    rate = (len(through) - 1) / (through[-1] - through[0])
    assert 0.42 <= rate <= 0.52
    assert np.median(np.diff(through)) >= 1.6


def test_without_the_queue_walkers_pass_much_faster(tmp_path):
    def edit(d):
        d["waiting_areas"] = [d["waiting_areas"][0]]  # the lobby only
        d["groups"][0]["count"] = 8
    run_scenario(_edited("waiting_areas", edit, tmp_path), tmp_path)
    through = np.sort(list(_crossings(tmp_path, 16.0).values()))
    assert len(through) == 8
    assert (len(through) - 1) / (through[-1] - through[0]) > 0.8


def test_waiting_positions_fill_from_the_node_and_keep_bodies_apart():
    area = shapely.box(0, 0, 8, 6)
    pts = waiting_positions(area, np.array([4.0, 3.0]))
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2) + np.eye(len(pts)) * 9
    assert d.min() == pytest.approx(SLOT_SPACING)
    r = np.linalg.norm(pts - [4.0, 3.0], axis=1)
    assert np.all(np.diff(r) >= -1e-12) and r[0] == 0.0
    assert shapely.contains_xy(area.buffer(-0.29), pts[:, 0], pts[:, 1]).all()
    lane = waiting_positions(shapely.box(10, 2.4, 15, 3.6), np.array([14.5, 3.0]))
    np.testing.assert_allclose(lane[:, 1], 3.0)  # a queue lane: one file, from the front
    np.testing.assert_allclose(lane[:, 0], 14.5 - SLOT_SPACING * np.arange(len(lane)))


def test_waiting_area_schema_errors():
    text = (SCENARIOS / "waiting_areas.yaml").read_text()
    bad = text.replace("{node: gate, release_rate: 0.5}", "{node: gate, release_rate: 0}")
    with pytest.raises(InputError, match=r"waiting_areas\[1\].release_rate must be > 0"):
        parse_scenario(bad, "w.yaml")
    bad = text.replace("{node: gate, release_rate: 0.5}", "{node: nowhere, release_rate: 1}")
    with pytest.raises(InputError, match=r"waiting_areas\[1\].node must be one of"):
        parse_scenario(bad, "w.yaml")
    assert build_world(load_scenario(SCENARIOS / "waiting_areas.yaml"))


def test_clearance_round_a_shut_door_matches_the_area_rasterised_again():
    world = build_world(load_scenario(SCENARIOS / "events.yaml"))
    routes = world.routes
    door = door_wall(routes, ("east_door", "east"), 0.5)
    shut = routes.with_closed({frozenset(("east_door", "east")): door})
    assert not shut.graph.has_edge("east_door", "east") and not shut.sees((14, 4), (15.5, 4))
    assert routes.sees((14, 4), (15.5, 4))  # the open graph is unchanged
    field = ClearanceField.from_area(routes.walkable_area)
    fast, full = with_walls(field, [door]), ClearanceField.from_area(shut.walkable_area)
    xy = np.column_stack([np.linspace(12.5, 17.0, 200), np.full(200, 4.2)])
    np.testing.assert_allclose(fast(xy), full(xy), atol=0.01)  # along the corridor
    assert fast(np.array([[14.75, 4.0]]))[0] < 0 < field(np.array([[14.75, 4.0]]))[0]
