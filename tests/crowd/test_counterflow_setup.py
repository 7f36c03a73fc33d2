"""The counterflow case's setup (``crowdwalk.verify.counterflow_scenario``): the verified
case (50 m) by default; another length and a start at a given density for measurements
(``scripts/verify_with.py --counterflow-length / --counterflow-density``)."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from crowdwalk.population import Population
from crowdwalk.scenario import Scenario
from crowdwalk.verify import counterflow_scenario
from crowdwalk.world import build_world


def _starts(data):
    sc = Scenario.model_validate(data)
    pop = Population.from_scenario(sc, build_world(sc).routes, np.random.default_rng(1))
    return pop.spawn_xy[pop.group == 0], pop.spawn_xy[pop.group == 1]


def test_default_groups_start_in_the_end_nodes_of_the_50_m_corridor():
    data = counterflow_scenario(1)
    assert data["terrain"]["extent"][2] == 50.0
    east, west = _starts(data)
    assert len(east) == len(west) == 50
    assert east[:, 0].max() < 5.0 and west[:, 0].min() > 45.0
    # the former 30 m case: the same start areas at its ends
    east30, west30 = _starts(counterflow_scenario(1, length=30.0))
    assert east30[:, 0].max() < 5.0 and 25.0 < west30[:, 0].min() < 30.0


@pytest.mark.parametrize("density", [1.0, 2.0])
def test_groups_start_at_the_density_apart_in_a_longer_corridor(density):
    east, west = _starts(counterflow_scenario(2, length=50.0, start_density=density))
    spacing = np.sqrt(2.0 / (np.sqrt(3.0) * density))  # hexagonal lattice at the density
    for g in (east, west):
        d, _ = cKDTree(g).query(g, k=2)
        np.testing.assert_allclose(d[:, 1], spacing, rtol=1e-6)
    assert west[:, 0].min() - east[:, 0].max() > 50.0 - 2 * (50 / (3.1 * density) + 1.0)
    assert east[:, 0].min() > 0.0 and west[:, 0].max() < 50.0


def test_weidmann_trip_ratio_is_the_path_mean_of_free_over_weidmann_speed():
    from crowdwalk.verify import WalkerFrames, weidmann_speed, weidmann_trip_ratio

    # walker 1: 1 m at 0.5 /m², 3 m at 2 /m²; walker 2: at 5 /m² (clipped at 3.5); 3 not arrived
    ids = np.array([1] * 4 + [2] * 2 + [3] * 2)
    rho = np.array([0.5, 2.0, 2.0, 2.0, 5.0, 5.0, 1.0, 1.0])
    step = np.ones(ids.size)
    frames = WalkerFrames(ids, np.full(ids.size, 1.2), rho, step, step, np.zeros(ids.size))
    agents = [{"id": k, "arrived": k != 3, "distance_m": 4.0} for k in (1, 2, 3)]
    got = weidmann_trip_ratio(frames, agents)
    slow = 1.34 / weidmann_speed(np.array([0.5, 2.0, 3.5]))
    np.testing.assert_allclose(got, [(slow[0] + 3 * slow[1]) / 4, slow[2]])
    assert got[1] > got[0] > 1.0


def test_walkers_alone_meet_the_voronoi_cut_off_density_and_walk_at_weidmann(tmp_path):
    from crowdwalk.verify import _run, walker_frames, weidmann_trip_ratio

    run = _run(counterflow_scenario(1, n=1, length=30.0), tmp_path / "two")
    frames = walker_frames(run.folder, run.summary, (0.0, 0.0, 30.0, 4.0))
    assert set(np.unique(frames.id)) == {a["id"] for a in run.summary["agents"]}
    # until they pass each other each cell is the 1 m cut-off disc (the walls 2 m away),
    # a 16-gon in PedPy (4 segments a quarter)
    assert np.median(frames.density) == pytest.approx(1 / (8 * np.sin(np.pi / 8)), rel=0.01)
    ratio = weidmann_trip_ratio(frames, run.summary["agents"])
    assert ratio.shape == (2,) and np.all((ratio >= 1.0) & (ratio < 1.05))
