"""``headway_steer`` with ``headway_free_margin``: inside the free zone at an opening the
headway model is off for the step's speed, and steering does not score its candidate
directions at a headway step there either (``CrowdSimulation._gap_steps``)."""

from dataclasses import replace

import numpy as np

from crowdwalk.crowd.neighbours import gather_neighbours
from crowdwalk.crowd.params import crowd_model
from crowdwalk.crowd.simulation import CrowdSimulation, build_parts
from crowdwalk.population import Population
from crowdwalk.scenario import Scenario
from crowdwalk.verify import _bottleneck
from crowdwalk.world import build_world


def test_no_headway_step_is_scored_inside_the_free_zone():
    sc = Scenario.model_validate(_bottleneck(0.8, 4, 30))
    world = build_world(sc)
    pop = Population.from_scenario(sc, world.routes, np.random.default_rng(1))
    params = replace(crowd_model("free"), speed_model="headway", headway_free_margin=1.0,
                     headway_steer=True)
    sim = CrowdSimulation(world, pop, parts=build_parts(world, pop, params=params),
                          dt=0.05, fps=10.0, duration=10.0, params=params)
    while sim.active.size < 20:
        sim.step()
    idx = sim.active
    nbs = gather_neighbours(sim.state, idx, t=sim.time, walkers=sim.active,
                            shape=sim.shape, count=params.neighbours,
                            reach=params.neighbour_range, threads=sim.threads)
    assert nbs.valid.any()
    # the same walkers and neighbours, decided as if in the 2 m opening (x 8-10 m) or
    # deep in the room (x = 2 m, beyond the 1 m margin)
    inside = sim._gap_steps(idx, np.tile([9.0, 5.0], (idx.size, 1)), nbs)
    room = sim._gap_steps(idx, np.tile([2.0, 5.0], (idx.size, 1)), nbs)
    assert not inside.valid.any() and not inside.followed.any()
    assert np.array_equal(room.valid, nbs.valid)
    # every candidate direction goes at the free speed inside
    fan = np.stack([np.cos(np.linspace(-1.5, 1.5, 7)), np.sin(np.linspace(-1.5, 1.5, 7))], -1)
    v, _ = inside.along(np.broadcast_to(fan, (idx.size, 7, 2)), everyone=True)
    assert np.allclose(v, sim.pop.free_speed[idx][:, None])
