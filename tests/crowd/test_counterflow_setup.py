"""The counterflow case's setup (``crowdwalk.verify.counterflow_scenario``): the verified
case unchanged by default; a longer corridor and a start at a given density for
measurements (``scripts/verify_with.py --counterflow-length / --counterflow-density``)."""

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


def test_default_groups_start_in_the_end_nodes_of_the_30_m_corridor():
    east, west = _starts(counterflow_scenario(1))
    assert len(east) == len(west) == 50
    assert east[:, 0].max() < 5.0 and west[:, 0].min() > 25.0


@pytest.mark.parametrize("density", [1.0, 2.0])
def test_groups_start_at_the_density_apart_in_a_longer_corridor(density):
    east, west = _starts(counterflow_scenario(2, length=50.0, start_density=density))
    spacing = np.sqrt(2.0 / (np.sqrt(3.0) * density))  # hexagonal lattice at the density
    for g in (east, west):
        d, _ = cKDTree(g).query(g, k=2)
        np.testing.assert_allclose(d[:, 1], spacing, rtol=1e-6)
    assert west[:, 0].min() - east[:, 0].max() > 50.0 - 2 * (50 / (3.1 * density) + 1.0)
    assert east[:, 0].min() > 0.0 and west[:, 0].max() < 50.0
