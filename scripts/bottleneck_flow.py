"""Bottleneck flow against door width: the model against Seyfried et al. (2009).

Runs ``scenarios/bottleneck.yaml`` with its opening (1 m wide, 2 m long) narrowed or
widened, for a few seeds each, and prints the steady flow (persons/s; the middle of the
arrivals, as in ``tests/crowd/test_crowd.py``) and the specific flow (/(m s)). Seyfried
et al. (2009, Transp. Sci. 43:395) measured a flow that grows about linearly with the
width, about 1.9 /(m s) (Kretz et al. 2006 and Rupprecht et al. 2011 similar).

Usage: ``python scripts/bottleneck_flow.py [--widths 0.8 1.0 1.2] [--seeds 4 5 6]``
(about 10 s per run).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import yaml

from crowdwalk.crowd.simulation import CrowdParams, CrowdSimulation, build_parts
from crowdwalk.population import Population
from crowdwalk.scenario import Scenario
from crowdwalk.world import build_world

SCENARIO = Path(__file__).parents[1] / "scenarios" / "bottleneck.yaml"


def scenario_with(width: float, seed: int) -> Scenario:
    """The bottleneck scenario with an opening ``width`` [m] wide and ``seed``."""
    data = yaml.safe_load(SCENARIO.read_text())
    for edge in data["routes"]["edges"]:
        edge["width"] = width
    data["simulation"]["seed"] = seed
    return Scenario.model_validate(data)


def steady_flow(scenario: Scenario) -> tuple[float, int]:
    """Flow [1/s] of the middle arrivals (all but the first and last five) and how many
    arrived."""
    world = build_world(scenario)
    rng = np.random.default_rng(scenario.simulation.seed)
    pop = Population.from_scenario(scenario, world.routes, rng)
    sim = CrowdSimulation(world, pop, parts=build_parts(world, pop, params=CrowdParams()),
                          dt=scenario.simulation.dt, fps=scenario.simulation.fps,
                          duration=scenario.simulation.duration)
    while not sim.finished:
        sim.step()
    arr = np.sort(sim.state.arrival_time[np.isfinite(sim.state.arrival_time)])
    if arr.size < 12:
        return float("nan"), int(arr.size)
    return (arr.size - 11) / (arr[-6] - arr[5]), int(arr.size)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--widths", type=float, nargs="+", default=[0.8, 1.0, 1.2])
    ap.add_argument("--seeds", type=int, nargs="+", default=[4, 5, 6])
    args = ap.parse_args()
    print("| width [m] | flow [1/s] per seed | mean flow [1/s] | specific flow [1/(m s)] |")
    print("|---|---|---|---|")
    for w in args.widths:
        flows = [steady_flow(scenario_with(w, s))[0] for s in args.seeds]
        mean = float(np.nanmean(flows))
        print(f"| {w:.2f} | {' '.join(f'{f:.2f}' for f in flows)} | {mean:.2f} | "
              f"{mean / w:.2f} |")


if __name__ == "__main__":
    main()
