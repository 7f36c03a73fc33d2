"""crowdwalk against JuPedSim on the same geometry and walkers (the issue 16 comparison).

A square room holding the walkers at about 2 /m² empties through a 1 m wide, 2 m long
opening into an outside area. Both simulators get the same walkable area (crowdwalk's
route-graph area, given to JuPedSim as its geometry), the same spawn positions, free
speeds and body radii. crowdwalk runs the scenario end to end with trajectories and
footsteps written at 10 fps and its scenario tick (0.05 s); JuPedSim 1.x runs its
collision-free speed model (Tordeux et al. 2016) at its default time step 0.01 s, without
a trajectory writer, towards an exit stage at the far end of the outside area. Printed:
simulated seconds per wall second of each simulation loop (set-up excluded), median of
``--repeats`` runs done alternately, and the ratio crowdwalk / JuPedSim.

JuPedSim is an optional benchmark dependency (``pip install crowdwalk[bench]``).

Usage: ``python benchmarks/bench_vs_jupedsim.py [--agents 100 1000 10000] [--seconds 15]
[--repeats 2]``
"""

from __future__ import annotations

import argparse
import math
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from crowdwalk.crowd.run import RunOverrides, prepare, run_scenario


def room_scenario(n: int, out: Path) -> Path:
    """The room-door-outside scenario for n walkers (room side √(n / 2) m)."""
    side = max(4.0, math.sqrt(n / 2.0))
    x1, y1 = 0.5 + side, 0.5 + side
    mid = 0.5 + side / 2
    outside = max(10.0, side)
    sc = {
        "name": f"room_{n}",
        "description": f"{n} walkers leave a room through a 1 m opening.",
        "terrain": {"extent": [0, 0, x1 + 2.5 + outside + 1.0, y1 + 0.5], "base": 0.0},
        "routes": {
            "nodes": [
                {"name": "room", "xy": [mid, mid],
                 "area": [[0.5, 0.5], [x1, 0.5], [x1, y1], [0.5, y1]]},
                {"name": "door", "xy": [x1 + 1.0, mid]},
                {"name": "outside", "xy": [x1 + 2.0 + outside / 2, mid],
                 "area": [[x1 + 2.0, mid - outside / 2], [x1 + 2.0 + outside, mid - outside / 2],
                          [x1 + 2.0 + outside, mid + outside / 2],
                          [x1 + 2.0, mid + outside / 2]]},
            ],
            "edges": [{"from": "room", "to": "door", "width": 1.0},
                      {"from": "door", "to": "outside", "width": 1.0}],
        },
        "groups": [{"name": "occupants", "count": n, "spawn": "room",
                    "destinations": ["outside"], "planner": "best_first"}],
        "simulation": {"duration": 15.0, "seed": 1, "dt": 0.05, "fps": 10},
        "outputs": {"poses": False},
    }
    sc["terrain"]["extent"][1] = min(0.0, mid - outside / 2 - 1.0)
    sc["terrain"]["extent"][3] = max(y1 + 0.5, mid + outside / 2 + 1.0)
    path = out / f"room_{n}.yaml"
    path.write_text(yaml.safe_dump(sc, sort_keys=False))
    return path


def run_crowdwalk(path: Path, out: Path, seconds: float) -> float:
    """Simulated s per wall s of crowdwalk's loop (trajectories + footsteps written)."""
    summary = run_scenario(path, out, overrides=RunOverrides(duration=seconds, poses=False))
    tm = summary["timing"]
    return summary["simulated_time_s"] / (tm["wall_s"] - tm["setup_s"])


def run_jupedsim(path: Path, seconds: float) -> float:
    """Simulated s per wall s of JuPedSim's iterate loop for the same walkers."""
    import jupedsim as jps
    import shapely

    _, world, sim, _, _ = prepare(path, RunOverrides(poses=False))
    area = world.routes.walkable_area
    x0, y0, x1, y1 = area.bounds
    exit_area = shapely.box(x1 - 1.0, y0, x1, y1).intersection(area)
    model = jps.Simulation(model=jps.CollisionFreeSpeedModel(), geometry=area, dt=0.01)
    exit_id = model.add_exit_stage(exit_area)
    journey = model.add_journey(jps.JourneyDescription([exit_id]))
    pop = sim.pop
    for xy, v0, r in zip(pop.spawn_xy, pop.free_speed, sim.radius, strict=True):
        model.add_agent(jps.CollisionFreeSpeedModelAgentParameters(
            journey_id=journey, stage_id=exit_id, position=(float(xy[0]), float(xy[1])),
            desired_speed=float(v0), radius=float(r)))
    steps = int(round(seconds / 0.01))
    t0 = time.perf_counter()
    for _ in range(steps):
        model.iterate()
    return model.elapsed_time() / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--agents", type=int, nargs="+", default=[100, 1000, 10000])
    ap.add_argument("--seconds", type=float, default=15.0, help="simulated seconds per run")
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_vs_jupedsim_"))
    rows = []
    try:
        for n in args.agents:
            path = room_scenario(n, tmp)
            cw, jp = [], []
            for k in range(args.repeats):  # alternately, in both orders
                order = ("cw", "jp") if k % 2 == 0 else ("jp", "cw")
                for which in order:
                    if which == "cw":
                        out = tmp / f"run_{n}_{k}"
                        cw.append(run_crowdwalk(path, out, args.seconds))
                        shutil.rmtree(out)
                    else:
                        jp.append(run_jupedsim(path, args.seconds))
            rows.append((n, cw, jp))
            print(f"  done: {n} walkers", flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f"\n{args.seconds:g} s simulated; simulated s per wall s of the loop, median of "
          f"{args.repeats} (all runs in brackets)")
    head = f"{'walkers':>8} {'crowdwalk':>22} {'JuPedSim':>22} {'ratio':>6}"
    print(head)
    print("-" * len(head))
    for n, cw, jp in rows:
        ratio = float(np.median(cw) / np.median(jp))
        print(f"{n:>8} {np.median(cw):>8.2f} {str([round(x, 2) for x in cw]):>13} "
              f"{np.median(jp):>8.2f} {str([round(x, 2) for x in jp]):>13} {ratio:>6.2f}")


if __name__ == "__main__":
    main()
