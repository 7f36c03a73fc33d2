"""Overtaking under the headway model (issue 14 item 3): ``headway_route_lane`` (the
leader is sought in the route lane a step goes into, and Seyfried's relation limits the
speed along the route only), ``headway_same_time`` (directions scored by speed),
``headway_overtake`` (scored against the followed same-way leaders only) and
``headway_overtake_open_lanes`` (no overtaking where the lane runs into a wall)."""

from dataclasses import replace

import numpy as np

from crowdwalk.crowd.neighbours import gather_neighbours
from crowdwalk.crowd.params import crowd_model
from crowdwalk.crowd.routing import lane_runs_into_wall
from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.crowd.simulation import CrowdParams, CrowdSimulation, build_parts
from crowdwalk.crowd.speed import GapSteps, headway_speed
from crowdwalk.crowd.steering import Neighbours, choose_steps
from crowdwalk.population import Population
from crowdwalk.record import open_run
from crowdwalk.scenario import Scenario
from crowdwalk.verify import _bottleneck, _group, _rect, _scenario, counterflow_scenario

_B = 1.06


def _lead(directions, *, lane, route=None, shift=None, leader=(1.0, 0.0)):
    """Headway speeds (C,) of a walker at the origin (1.34 m/s, radius 0.18 m) along
    ``directions`` (C, 2) with one neighbour at ``leader``."""
    d = np.asarray(directions, float)[None]
    kw = {} if route is None else {"lane_direction": np.array([route], float),
                                   "shift": np.array([shift], float)}
    return headway_speed(position=np.zeros((1, 2)), direction=d, radius=np.array([0.18]),
                         others=np.array([[leader]], float), others_radius=np.full((1, 1), 0.18),
                         valid=np.ones((1, 1), bool), free_speed=np.array([1.34]),
                         time_gap=_B, lane=np.array([lane]), **kw)[0]


def test_route_lane_headway_follows_the_leader_of_the_lane_the_step_goes_into():
    a = np.deg2rad([0.0, 15.0, 40.0, 90.0, 180.0])
    d = np.stack([np.cos(a), np.sin(a)], -1)
    v = _lead(d, lane=0.36, route=(1.0, 0.0), shift=0.7)
    # straight on: Seyfried's v = (s - a) / b to the leader 1 m ahead
    assert np.isclose(v[0], (1.0 - 0.36) / _B)
    # 15°: the step ends 0.18 m across, still in the leader's lane: limited along the
    # route, so the step's own speed is that over cos 15°
    assert np.isclose(v[1], (1.0 - 0.36) / _B / np.cos(a[1]))
    # 40°: the step ends 0.45 m across, out of the leader's lane (0.36): free; so are a
    # step across and a step back, which Seyfried's single-file relation does not limit
    assert np.allclose(v[2:], 1.34)
    # the step's own line (the model without the route lane) follows the leader at 15°
    # and 40° alike (lateral 0.26 / 0.64 m at 1 m along the line: 15° only) and limits
    # a step across to nothing when a neighbour is beside
    line = _lead(d, lane=0.36)
    assert line[1] < 1.34 and np.isclose(line[2], 1.34)
    beside = _lead(d[3:4], lane=0.36, leader=(0.0, 0.5))
    assert beside[0] < 0.2
    assert np.isclose(_lead(d[3:4], lane=0.36, leader=(0.0, 0.5), route=(1.0, 0.0),
                            shift=0.7)[0], 1.34)


def test_same_time_scoring_compares_directions_by_speed():
    g = GapSteps(position=np.zeros((1, 2)), radius=np.array([0.18]),
                 others=np.array([[[1.2, 0.0]]]), others_radius=np.full((1, 1), 0.18),
                 valid=np.ones((1, 1), bool), followed=np.ones((1, 1), bool),
                 free_speed=np.array([1.56]), leg_length=np.array([0.9]), time_gap=_B,
                 lane=np.array([0.27]))
    d = np.array([[[1.0, 0.0], [np.cos(0.6), np.sin(0.6)]]])
    v, length = g.along(d)
    v2, same = g.along(d, same_time=True)
    assert np.allclose(v, v2) and v[0, 0] < 0.9 * 1.56
    # per step at the slow speed's own cadence a slow step is shorter by less than its
    # speed; at the free cadence the lengths are in the ratio of the speeds
    free_step = same[0, 0] * 1.56 / v[0, 0]
    assert length[0, 0] > same[0, 0]
    assert np.isclose(same[0, 0] / free_step, v[0, 0] / 1.56)


def _counterflow_sim(params):
    # 30 m: oncoming walkers are neighbours by 8 s
    sc = Scenario.model_validate(counterflow_scenario(1, length=30.0))
    from crowdwalk.world import build_world

    world = build_world(sc)
    pop = Population.from_scenario(sc, world.routes, np.random.default_rng(1))
    return CrowdSimulation(world, pop, parts=build_parts(world, pop, params=params),
                           dt=0.05, fps=10.0, duration=30.0, params=params)


def test_oncoming_walkers_are_not_scored_as_leaders():
    # the free model's switches (no overtaking, no route lane) with route-direction leaders
    base = replace(crowd_model("free"), speed_model="headway", headway_same_way="route")
    sim = _counterflow_sim(replace(base, headway_steer=True))
    while sim.time < 8.0:
        sim.step()
    idx = sim.active
    nbs = gather_neighbours(sim.state, idx, t=sim.time, walkers=sim.active, shape=sim.shape,
                            count=base.neighbours, reach=base.neighbour_range,
                            threads=sim.threads)
    pos = sim.state.pos1[idx]
    steer = sim._gap_steps(idx, pos, nbs)
    sim.params = replace(sim.params, headway_steer=False, headway_overtake=True)
    over = sim._gap_steps(idx, pos, nbs)
    east = np.array([sim.pop.group_names[g] == "eastward" for g in sim.pop.group])
    oncoming = nbs.valid & (east[idx][:, None] != east[nbs.agent])
    assert oncoming.any()
    # headway_steer scores against every neighbour, oncoming ones too; headway_overtake
    # against the followed same-way walkers only
    assert steer.valid[oncoming].all()
    assert not over.valid[oncoming].any()
    assert np.array_equal(over.valid, over.followed)


def test_no_overtaking_where_the_lane_runs_into_a_wall():
    sc = Scenario.model_validate(_bottleneck(0.8, 4, 30))
    from crowdwalk.world import build_world

    world = build_world(sc)
    params = replace(crowd_model("free"), speed_model="headway", headway_same_way="route",
                     headway_overtake=True, headway_overtake_open_lanes=True)
    pop = Population.from_scenario(sc, world.routes, np.random.default_rng(1))
    sim = CrowdSimulation(world, pop, parts=build_parts(world, pop, params=params),
                          dt=0.05, fps=10.0, duration=10.0, params=params)
    table, st = sim.routes.table, sim.state
    while sim.active.size < 10:
        sim.step()
    a = sim.active[:2]
    # two walkers put 1 m in front of the 0.8 m opening (x = 8 m) 0.6 m off its axis
    # (y = 5 m), and on the axis 6 m before it
    xy = np.array([[7.0, 5.6], [2.0, 5.0]])
    _, prog, _ = table.project(st.route[a], table.start[st.route[a]], xy)
    walled = lane_runs_into_wall(table, route=st.route[a], progress=prog, xy=xy,
                                 radius=sim.radius[a], clearance=sim.clearance, params=params)
    assert walled.tolist() == [True, False]
    # a walker whose lane runs into the wall is scored at no headway step
    idx = sim.active
    nbs = gather_neighbours(st, idx, t=sim.time, walkers=sim.active, shape=sim.shape,
                            count=params.neighbours, reach=params.neighbour_range,
                            threads=sim.threads)
    assert nbs.valid.any()
    every = np.ones(idx.size, bool)
    g = sim._gap_steps(idx, st.pos1[idx], nbs, every)
    assert not g.valid.any()
    assert np.array_equal(sim._gap_steps(idx, st.pos1[idx], nbs, ~every).valid, g.followed)


def _corridor():
    return _scenario("overtake", (-2, -1, 42, 4),
                     [{"name": "start", "xy": [0.5, 1.5]}, {"name": "end", "xy": [40.0, 1.5]}],
                     [{"from": "start", "to": "end", "width": 3.0}],
                     [_group("slow", 1, _rect(3.4, 1.4, 3.6, 1.6), ["end"], speed=(0.9, 0.01)),
                      _group("fast", 1, _rect(0.4, 1.4, 0.6, 1.6), ["end"], speed=(1.6, 0.01))],
                     60.0)


def test_a_walker_behind_a_slower_one_steps_out_when_directions_compare_by_speed():
    """The free-speed case's failure (a 1.56 m/s walker 1.33 m behind a 0.95 m/s one, 5 cm
    to its right, kept behind it for 4 s): scored by step length the straight step (short
    but at a lower cadence) beats the side step into the free lane; by speed it does not."""
    from crowdwalk.world import build_world

    sc = Scenario.model_validate(_corridor())
    world = build_world(sc)
    params = CrowdParams()
    pop = Population.from_scenario(sc, world.routes, np.random.default_rng(1))
    sim = CrowdSimulation(world, pop, parts=build_parts(world, pop, params=params),
                          dt=0.05, fps=10.0, duration=1.0, params=params)
    me, leader = np.array([[10.0, 1.5]]), np.array([[[11.33, 1.45]]])
    nbs = Neighbours(valid=np.ones((1, 1), bool), now=leader, end=leader + [0.3, 0.0],
                     velocity=np.array([[[0.95, 0.0]]]), radius=np.full((1, 1), 0.18),
                     heading=np.zeros((1, 1)))
    e = np.array([[1.0, 0.0]])
    gap = GapSteps(position=me, radius=np.array([0.18]), others=nbs.end,
                   others_radius=nbs.radius, valid=nbs.valid, followed=nbs.valid,
                   free_speed=np.array([1.56]), leg_length=np.array([0.9]), time_gap=_B,
                   lane=np.array([0.27]), lane_direction=e, shift=np.array([0.74]))
    angle = {}
    for same in (False, True):
        ch = choose_steps(me, me, heading=np.zeros(1), radius=np.array([0.18]),
                          route_direction=e, target=np.array([[12.0, 1.5]]),
                          nominal_step=np.array([0.74]), neighbours=nbs,
                          clearance=sim.clearance, speed=np.array([1.56]), gap=gap,
                          score_same_time=same)
        assert ch.move[0]
        angle[same] = abs(np.degrees(np.arctan2(ch.direction[0, 1], ch.direction[0, 0])))
    assert angle[False] < 5.0 and angle[True] > 15.0, angle


def test_a_fast_walker_overtakes_a_slow_one_in_a_free_corridor(tmp_path):
    """In an empty 3 m corridor a 1.6 m/s walker starting 3 m behind a 0.9 m/s one passes
    it and keeps its free speed with the route lane, same-time scoring and overtaking."""
    params = replace(crowd_model("free"), speed_model="headway", headway_same_way="route",
                     headway_lane=2.0, headway_overtake=True, headway_route_lane=True,
                     headway_same_time=True)
    s = run_scenario(Scenario.model_validate(_corridor()), tmp_path / "run", params=params,
                     overrides=RunOverrides(poses=False))
    times = {a["group"]: a["travel_time_s"] for a in s["agents"]}
    assert len(np.unique(open_run(tmp_path / "run").trajectories().id)) == 2
    # within 10 % of its free walk (39.5 m at 1.6 m/s), well before the slow one
    assert times["fast"] < 1.1 * 39.5 / 1.6 < 0.8 * times["slow"]
