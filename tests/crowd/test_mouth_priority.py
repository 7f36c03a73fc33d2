"""``mouth_priority``: in front of a narrow opening's mouth the walker nearer the mouth
point has priority (ties by index), a strict order; the reservations only add hard
constraints, so bodies never overlap."""

from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from crowdwalk.crowd.mouth_priority import MouthPriority
from crowdwalk.crowd.run import RunOverrides, prepare
from crowdwalk.crowd.simulation import ARRIVED, CrowdParams
from crowdwalk.crowd.steering import Neighbours
from crowdwalk.scenario import Scenario
from crowdwalk.sinks import OverlapMonitor
from crowdwalk.verify import _bottleneck
from crowdwalk.world import build_world

# the bottleneck's mouth point is (8, 5): the opening runs from x = 8 to 10 m on y = 5 m
_WALKERS = np.array([[7.85, 4.75],   # 0: at the lower wall corner, 0.29 m from the mouth
                     [7.85, 5.25],   # 1: at the upper corner, as near
                     [7.55, 5.0],    # 2: behind them on the axis, 0.45 m
                     [9.0, 5.0],     # 3: inside the opening
                     [5.0, 5.0]])    # 4: far back in the room


def _all_pairs(direction):
    """Every walker a decider, every other one its neighbour."""
    n = len(_WALKERS)
    others = np.array([[j for j in range(n) if j != i] for i in range(n)])
    now = _WALKERS[others]
    nbs = Neighbours(valid=np.ones(others.shape, bool), now=now, end=now,
                     velocity=np.zeros(now.shape), radius=np.full(others.shape, 0.18),
                     agent=others)
    return others, nbs, np.broadcast_to(direction, now.shape)


def test_priority_is_a_strict_order_by_distance_to_the_mouth_point():
    mp = MouthPriority(build_world(Scenario.model_validate(_bottleneck(0.8, 1, 10))).routes,
                       1.25)
    east = np.tile([1.0, 0.0], (len(_WALKERS), 1))
    others, nbs, nb_east = _all_pairs(east[0])
    first = mp.priority(np.arange(len(_WALKERS)), _WALKERS, east, nbs, nb_east)
    over = np.zeros((5, 5), bool)  # over[i, j]: j has priority over i
    for i in range(5):
        over[i, others[i]] = first[i]
    assert not (over & over.T).any()  # of two walkers one at most gives way
    # the corner walkers tie: the lower index goes first; both go before the axis walker
    assert over[1, 0] and not over[0, 1]
    assert over[2, 0] and over[2, 1] and not over[0, 2] and not over[1, 2]
    # nobody inside the opening or far from the mouth takes part
    assert not over[3].any() and not over[:, 3].any()
    assert not over[4].any() and not over[:, 4].any()
    # nor do walkers going the other way
    west = mp.priority(np.arange(5), _WALKERS, east, nbs, -nb_east)
    assert not west.any()
    # nor walkers passing the mouth rather than heading into it (walking along the wall)
    north = np.tile([0.0, 1.0], (5, 1))
    assert not mp.priority(np.arange(5), _WALKERS, north, nbs,
                           np.broadcast_to(north[0], nb_east.shape)).any()
    assert mp.approach(_WALKERS, east).tolist() == [True, True, True, False, False]
    d = mp.mouth_distance(_WALKERS[:3])
    np.testing.assert_allclose(d, [np.hypot(0.15, 0.25)] * 2 + [0.45], atol=1e-6)


def test_reservations_are_made_and_bodies_stay_apart_in_a_run():
    """The 0.8 m bottleneck (20 walkers, 40 s, with ``wake_on_step``): reservations are
    made in front of the mouth, everybody arrives, and no two bodies overlap."""
    sc = Scenario.model_validate(_bottleneck(0.8, 5, 20))
    params = replace(CrowdParams(), mouth_priority=True, wake_on_step=True)
    _, _, sim, _, _ = prepare(sc, RunOverrides(poses=False, duration=40.0), params=params)
    made = []
    plain = sim.mouth_priority.reservations

    def counted(*args, **kw):
        out = plain(*args, **kw)
        made.append(int(out.valid.sum()))
        return out

    sim.mouth_priority.reservations = counted
    overlap = OverlapMonitor()  # the run summary's max_overlap_m
    overlap.begin(SimpleNamespace(shape=sim.shape))
    while not sim.finished:
        if sim.step():
            overlap.frame(sim.time, sim.snapshot(), None)
    assert sum(made) > 20, sum(made)
    assert (sim.state.status == ARRIVED).all()
    assert overlap.max_overlap <= 0.01
