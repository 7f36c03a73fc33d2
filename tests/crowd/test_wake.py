"""``wake_on_step``: a walker standing near a narrow opening decides again at the tick
after a walking neighbour in its way takes its next step (not only after ``wait_time``);
the hard tests are unchanged, so bodies never overlap."""

from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from crowdwalk.crowd.run import RunOverrides, prepare
from crowdwalk.crowd.simulation import ACTIVE, CrowdParams
from crowdwalk.crowd.steering import Neighbours
from crowdwalk.crowd.wake import WakeOnStep
from crowdwalk.scenario import Scenario
from crowdwalk.sinks import OverlapMonitor
from crowdwalk.verify import _bottleneck
from crowdwalk.world import build_world


def _neighbours(now, velocity, remaining):
    """One neighbour per decider: positions, velocities (k, 2), remaining times (k,)."""
    now = np.asarray(now, float)[:, None, :]
    k = now.shape[0]
    return Neighbours(valid=np.ones((k, 1), bool), now=now, end=now,
                      velocity=np.asarray(velocity, float)[:, None, :],
                      radius=np.full((k, 1), 0.18),
                      remaining=np.asarray(remaining, float)[:, None])


def test_a_standing_walker_wakes_the_tick_after_a_near_walking_neighbours_step():
    world = build_world(Scenario.model_validate(_bottleneck(0.8, 1, 10)))
    wake = WakeOnStep(world.routes, 1.25)
    t, dt = 12.0, 0.05
    pos = np.array([[7.5, 5.0], [7.5, 5.0], [7.5, 5.0], [4.0, 5.0]])
    nbs = _neighbours([[7.9, 5.1], [7.9, 5.1], [9.5, 5.0], [4.4, 5.1]],
                      [[1.0, 0.0], [0.0, 0.0], [1.0, 0.0], [1.0, 0.0]],
                      [0.12, 0.12, 0.12, 0.12])
    east = np.tile([1.0, 0.0], (4, 1))
    kw = dict(bound=np.full(4, 0.18), nb_bound=np.full((4, 1), 0.18), step=np.full(4, 0.65),
              direction=east)
    got = wake.times(t, dt, pos, nbs, nb_direction=east[:, None, :], **kw)
    # the neighbour's heel strike at 12.12 s falls in the tick ending at 12.15 s, where it
    # decides; the walker decides in the next tick, when the new step is committed
    np.testing.assert_allclose(got[0], 12.2, atol=1e-9)
    assert got[0] > t + 0.12 + dt - 1e-9
    # a standing neighbour frees no room; a far one is not in the way; away from the
    # opening nobody is woken
    assert np.isinf(got[1:]).all()
    # nor does a neighbour going the other way (an oncoming walker's step)
    west = wake.times(t, dt, pos, nbs, nb_direction=-east[:, None, :], **kw)
    assert np.isinf(west).all()


def _woken_stands(on: bool):
    """Run the 0.8 m bottleneck (20 walkers, 25 s) tick by tick: (the stands that end
    before ``wait_time``, as (agent, end tick, position)), the walking deciders of each
    tick (tick -> positions), the stand count, and the largest overlap of two body
    outlines over the frames [m] (the run summary's ``max_overlap_m``)."""
    sc = Scenario.model_validate(_bottleneck(0.8, 5, 20))
    params = replace(CrowdParams(), wake_on_step=on, zipper=True)
    _, _, sim, _, _ = prepare(sc, RunOverrides(poses=False, duration=25.0), params=params)
    st, dt, wait = sim.state, sim.dt, params.wait_time
    woken, walking, stands = [], {}, 0
    overlap = OverlapMonitor()
    overlap.begin(SimpleNamespace(shape=sim.shape))
    while not sim.finished:
        t = (sim.tick + 1) * dt
        deciding = np.flatnonzero((st.status == ACTIVE) & (st.t1 <= t + 1e-9))
        was_walking = deciding[np.linalg.norm(st.pos1[deciding] - st.pos0[deciding], axis=1)
                               > 0]
        walking[sim.tick + 1] = st.pos1[was_walking].copy()
        if sim.step():
            overlap.frame(sim.time, sim.snapshot(), None)
        stood = deciding[(st.status[deciding] == ACTIVE) & (st.t0[deciding] <= t + 1e-9)
                         & (np.linalg.norm(st.pos1[deciding] - st.pos0[deciding], axis=1)
                            == 0) & (st.t1[deciding] > t + 1e-9)]
        stands += stood.size
        for a in stood[st.t1[stood] < t + wait - 1e-9]:
            woken.append((int(a), int(round(st.t1[a] / dt)), st.pos1[a].copy(), t))
    return woken, walking, stands, overlap.max_overlap


def test_woken_walkers_decide_one_tick_after_a_near_neighbour_steps_and_never_overlap():
    woken_off, _, stands_off, over_off = _woken_stands(False)
    assert stands_off > 0 and not woken_off  # off: every stand lasts wait_time
    woken, walking, stands, over = _woken_stands(True)
    assert len(woken) > 0.1 * stands, (len(woken), stands)
    for agent, tick, xy, t in woken:
        assert tick * 0.05 >= t + 0.05 - 1e-9  # never in the tick it stood
        # in the tick before it decides again a walking neighbour near it stepped
        near = walking.get(tick - 1, np.zeros((0, 2)))
        assert (np.linalg.norm(near - xy, axis=1) < 0.18 + 0.18 + 0.65 + 0.6).any(), (agent, tick)
    assert over <= 0.01 and over_off <= 0.01


def test_the_door_rules_are_on_by_default_and_left_out_where_there_is_no_opening():
    """Since session 21 ``wake_on_step`` and ``mouth_priority`` are the default (the
    ``free`` model keeps both off); a world without an opening (corner.yaml: 3 m
    corridors) runs without them, a bottleneck with them."""
    from pathlib import Path

    from crowdwalk.crowd.params import crowd_model

    on = CrowdParams()
    assert on.wake_on_step and on.mouth_priority
    free = crowd_model("free")
    assert not free.wake_on_step and not free.mouth_priority
    door = Scenario.model_validate(_bottleneck(0.8, 1, 10))
    _, _, sim, _, _ = prepare(door, RunOverrides(poses=False, duration=1.0))
    assert isinstance(sim.wake, WakeOnStep) and sim.mouth_priority is not None
    _, _, sim, _, _ = prepare(door, RunOverrides(poses=False, duration=1.0), params=free)
    assert sim.wake is None and sim.mouth_priority is None
    corner = Path(__file__).parents[2] / "scenarios" / "corner.yaml"
    _, _, sim, _, _ = prepare(corner, RunOverrides(poses=False, duration=1.0))
    assert sim.wake is None and sim.mouth_priority is None
