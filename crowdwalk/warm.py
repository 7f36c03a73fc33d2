"""Compile (or load) every numba kernel a run uses, ahead of the first run.

The kernels are compiled with ``cache=True`` next to their modules; ``install.sh`` runs
this once, so the first ``crowdwalk run`` loads them instead of compiling (about 25 s of
CPU otherwise), and every sweep worker runs it before it takes work. It walks two
walkers (``best_first`` and ``fixed``) for two simulated seconds up a short stair flight,
with poses: the planners, the crowd and the gait kernels all run once; then every planner
plans a batch large enough for the kernels to run on every core, and plans that fail (a
wall: the lazy tables are completed for the diagnosis); then, at install
(``python -m crowdwalk.warm``, in a checkout), the README's quickstart runs for 15
simulated seconds (its crowd calls three kernels with
array layouts the two walkers do not: without it, the first quickstart compiled them,
11 of its 25 CPU seconds).

Usage: ``python -m crowdwalk.warm`` (prints the seconds it took).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

__all__ = ["QUICKSTART", "WARM_SCENARIO", "warm_kernels"]

#: The README's first run (in a checkout; absent from an installed wheel).
QUICKSTART = Path(__file__).resolve().parents[1] / "scenarios" / "quickstart.yaml"

WARM_SCENARIO = {
    "name": "warm",
    "description": "Two walkers up two stair steps and down a curb (kernel warm-up).",
    "terrain": {"extent": [0, -1, 8, 3], "base": 0.0,
                "features": [{"type": "stairs", "start": [2.0, 1.0], "heading": 0,
                              "width": 2.0, "going": 0.30, "rise": 0.17, "steps": 2}]},
    "routes": {"nodes": [{"name": "start", "xy": [1.0, 1.0],
                          "area": [[0.2, 0.2], [1.8, 0.2], [1.8, 1.8], [0.2, 1.8]]},
                         {"name": "end", "xy": [7.0, 1.0]}],
               "edges": [{"from": "start", "to": "end", "width": 2.0}]},
    "groups": [{"name": "planned", "count": 1, "spawn": "start", "destinations": ["end"],
                "planner": "best_first"},
               {"name": "unplanned", "count": 1, "spawn": "start", "destinations": ["end"],
                "planner": "fixed", "spawn_times": {"start": 0.5}}],
    "simulation": {"duration": 2.0, "seed": 0, "dt": 0.05, "fps": 10},
    "outputs": {"poses": True},
}


def warm_kernels(quickstart: bool = False) -> float:
    """Run :data:`WARM_SCENARIO` once (into a temporary folder), and with ``quickstart``
    the first 15 s of :data:`QUICKSTART` where it exists; the seconds it took."""
    import yaml

    from crowdwalk.crowd.run import RunOverrides, run_scenario
    from crowdwalk.scenario import parse_scenario
    from planners import PLANNERS, GroundProfile, Leg, plan_batch
    from planners.lattice import PARALLEL_AGENTS

    t0 = time.perf_counter()
    scenario = parse_scenario(yaml.safe_dump(WARM_SCENARIO), source="<warm>")
    with tempfile.TemporaryDirectory() as tmp:
        run_scenario(scenario, tmp)
    # the batch kernels (every core) and every search, as crowds of walkers use them
    stairs = GroundProfile.stairs(0.17, 0.30, 3, first_edge=0.6)
    # and a wall no plan passes: a failed plan completes its lazy tables
    # (lattice_kernel.complete_agents) before the diagnosis; alone and in a batch
    wall = GroundProfile([-2.0, 0.6, 0.6, 6.0], [0.0, 0.0, 0.6, 0.6])
    leg = Leg.from_body_height(1.75)
    for planner in sorted(PLANNERS):
        plan_batch([stairs] * PARALLEL_AGENTS, leg, 1.34, planner)
        plan_batch([wall], leg, 1.34, planner)
        plan_batch([wall, stairs] * (PARALLEL_AGENTS // 2), leg, 1.34, planner)
    if quickstart and QUICKSTART.exists():
        with tempfile.TemporaryDirectory() as tmp:
            run_scenario(QUICKSTART, tmp, overrides=RunOverrides(duration=15.0))
    return time.perf_counter() - t0


if __name__ == "__main__":
    print(f"crowdwalk kernels ready ({warm_kernels(quickstart=True):.1f} s)")
