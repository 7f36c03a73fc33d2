"""What timed events cost at scale: the stadium egress with gate 0 shut and opened again.

Section 0 chooses between gates 0 and 1 (``exit_choice: nearest``). The corridor from the
foot of its stairs to gate 0 is closed at ``--close`` s and opened at ``--open`` s. The
table shows, per event, the walkers given a new route and the wall time the event took
(``summary.json`` ``events``), then the run's simulated seconds per wall second. It also
shows how many walkers passed the closed door while it was shut, counted from the
trajectories.

Usage: ``python benchmarks/bench_events.py [--agents 400] [--close 12] [--open 24]``
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import yaml

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.record import open_run
from crowdwalk.scenario import parse_scenario

ROOT = Path(__file__).parents[1]
STADIUM = ROOT / "scenarios" / "stadium_egress.yaml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--agents", type=int, default=400)
    ap.add_argument("--close", type=float, default=12.0)
    ap.add_argument("--open", type=float, default=24.0)
    args = ap.parse_args()
    sc = yaml.safe_load(STADIUM.read_text())
    for g in sc["groups"]:
        g["count"] = args.agents // 4
    sc["groups"][0].pop("destinations")
    sc["groups"][0]["exit_choice"] = {"among": ["gate_0", "gate_1"], "rule": "nearest"}
    door = ["foot_0", "gate_0"]
    sc["events"] = [{"time": args.close, "action": "close", "corridor": door},
                    {"time": args.open, "action": "open", "corridor": door}]
    sc["simulation"]["duration"] = args.open + 6.0
    scenario = parse_scenario(yaml.safe_dump(sc, sort_keys=False), "stadium_events.yaml",
                              STADIUM.parent)
    with tempfile.TemporaryDirectory() as tmp:
        s = run_scenario(scenario, Path(tmp), overrides=RunOverrides(poses=False))
        t = open_run(tmp).trajectories()
        # the door: halfway from foot_0 (10, 19.5) to gate_0 (10, 5), across x in [7, 13]
        y0 = 12.25
        shut = [e["time_s"] for e in s["events"]]
        through = 0
        for i in np.unique(t.id):
            a = t.agent(int(i))
            k = np.flatnonzero((a.y[:-1] > y0) & (a.y[1:] <= y0) & (np.abs(a.x[1:] - 10) < 3))
            through += int(np.any((a.time[k + 1] > shut[0]) & (a.time[k + 1] < shut[1])))
    print(f"stadium, {args.agents} agents, poses off")
    print(f"{'time [s]':>9} {'action':>7} {'rerouted':>9} {'wall [s]':>9}")
    for e in s["events"]:
        print(f"{e['time_s']:9.2f} {e['action']:>7} {e['walkers_rerouted']:9d} "
              f"{e['wall_s']:9.3f}")
    print(f"walkers through the door while shut: {through}")
    print(f"simulated s per wall s: {s['timing']['simulated_s_per_wall_s']:.2f}; "
          f"max overlap {s['max_overlap_m']:.4f} m")


if __name__ == "__main__":
    main()
