"""A walker off its route, with the route line behind a wall (pushed through a side door
into a room, as in RiMEA 10's corridor), finds its way back out through the door."""

import numpy as np
import pytest

from crowdwalk.crowd.simulation import CrowdParams, CrowdSimulation, build_parts
from crowdwalk.population import Population
from crowdwalk.scenario import Scenario
from crowdwalk.world import build_world

SCENARIO = {
    "name": "side_room",
    "terrain": {"extent": [-4, -1, 24, 7]},
    "routes": {
        "nodes": [{"name": "west", "xy": [-2.0, 1.0], "area": [[-3.5, 0], [-1, 0], [-1, 2],
                                                                [-3.5, 2]]},
                  {"name": "c", "xy": [10.0, 1.0]},
                  {"name": "room", "xy": [10.0, 4.0], "area": [[8.2, 2.6], [11.8, 2.6],
                                                                [11.8, 5.6], [8.2, 5.6]]},
                  {"name": "east", "xy": [22.0, 1.0], "area": [[21, 0], [23.5, 0], [23.5, 2],
                                                                [21, 2]]}],
        "edges": [{"from": "west", "to": "c", "width": 2.0},
                  {"from": "c", "to": "east", "width": 2.0},
                  {"from": "c", "to": "room", "width": 1.0}]},
    "groups": [{"name": "walker", "count": 1, "spawn": "west", "destinations": ["east"],
                "free_speed": {"mean": 1.3, "sd": 0.0}}],
    "simulation": {"duration": 60.0, "seed": 1, "dt": 0.05, "fps": 10.0},
    "outputs": {"poses": False},
}


@pytest.mark.parametrize("start", [(11.3, 3.0), (8.6, 5.2)])
def test_walker_behind_a_wall_of_its_route_leaves_by_the_door(start):
    """The walker's route runs along the corridor (y = 1); it starts in the side room
    (y > 2.6, the door at 9.5 < x < 10.5), where the wall hides its route line. Before,
    re-routing kept the same nodes (and so the hidden line) and the walker stood in the
    room's corner until the time limit."""
    sc = Scenario.model_validate(SCENARIO)
    world = build_world(sc)
    pop = Population.from_scenario(sc, world.routes, np.random.default_rng(1))
    pop.spawn_xy[0] = start  # in the room, on the corridor's route
    params = CrowdParams()
    sim = CrowdSimulation(world, pop, parts=build_parts(world, pop, params=params),
                          dt=0.05, fps=10.0, duration=60.0, params=params)
    path = []
    while not sim.finished:
        sim.step()
        if sim.active.size:
            path.append(sim.state.pos1[0].copy())
    path = np.array(path)
    assert np.isfinite(sim.state.arrival_time[0]), path[-1]
    # it left the room through the door (between the room and the corridor's wall)
    crossing = path[(path[:, 1] > 2.0) & (path[:, 1] < 2.6)]
    assert crossing.size and np.all(np.abs(crossing[:, 0] - 10.0) < 0.5), crossing
