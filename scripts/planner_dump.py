"""Dump many plans of every planner to a file, or compare a dump with the current code.

``python scripts/planner_dump.py dump OUT.npz`` plans every planner under six
configurations on random terrain and the standard grounds (in batches, which use the
parallel table kernel, and as single plans) and stores statuses, messages, footholds,
swing controls, energies and the searches' counters. ``python scripts/planner_dump.py
compare OLD.npz`` plans the same again and reports the largest differences: the check
that a change of the planners' internals leaves their plans as they were (to 1e-9 m).
``--counters-may-change PLANNER`` (repeatable) reports that planner's plans whose search
counters differ without failing (a change that does less work for the same plans).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from bench_planners import random_terrain, terrains  # noqa: E402

from planners import PLANNERS, EnergyWeights, Leg, PlannerConfig, plan, plan_batch  # noqa: E402

#: Counters that belong to the search (they do not depend on how the tables are built).
SEARCH_COUNTERS = ("nodes_expanded", "legality_checks")


def cases():
    """(name, config) pairs: the default, the crowd's, the paper's, coarse grids, no
    terminal cost, no snapping, n = 5."""
    base = PlannerConfig()
    return [("default", base),
            ("crowd", replace(base, n_steps=3, min_step_ratio=0.15)),
            ("paper", replace(base, step_model="paper", terminal_cost=False,
                              weights=EnergyWeights.paper())),
            ("coarse", replace(base, intervals=7)),
            ("nosnap", replace(base, snap=False, intervals=11)),
            ("n5", replace(base, n_steps=5, intervals=7))]


def plans(count: int, singles: int):
    """Every plan of the dump, in a fixed order: (key, Plan)."""
    rng = np.random.default_rng(99)
    grounds = list(terrains().values()) + [random_terrain(rng) for _ in range(count)]
    legs = [Leg.from_body_height(h) for h in rng.uniform(1.5, 1.95, len(grounds)).round(3)]
    speeds = rng.uniform(0.8, 1.8, len(grounds)).round(2)
    trailing = -rng.uniform(0.3, 0.8, len(grounds)).round(3)
    for cname, config in cases():
        for planner in sorted(PLANNERS):
            for tr_name, tr in (("own", trailing), ("default", None)):
                batch = plan_batch(grounds, legs, speeds, planner, config, trailing=tr)
                for i, p in enumerate(batch):
                    yield f"{cname}/{planner}/batch/{tr_name}/{i}", p
            for i in range(singles):
                p = plan(grounds[i], legs[i], float(speeds[i]), planner, config,
                         trailing=float(trailing[i]))
                yield f"{cname}/{planner}/single/{i}", p


def record(p) -> dict:
    return {"status": p.status, "message": p.message, "s": p.footholds_s, "z": p.footholds_z,
            "controls": p.swing_controls, "E": p.E,
            "counters": np.array([p.stats[k] for k in SEARCH_COUNTERS])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("dump", "compare"))
    parser.add_argument("path")
    parser.add_argument("--profiles", type=int, default=140, help="random profiles")
    parser.add_argument("--singles", type=int, default=30, help="single plans per case")
    parser.add_argument("--counters-may-change", action="append", default=[],
                        metavar="PLANNER",
                        help="compare: a planner whose search counters may differ (less "
                             "work done for the same plans); reported, not a failure")
    args = parser.parse_args()
    got = {k: record(p) for k, p in plans(args.profiles, args.singles)}
    if args.action == "dump":
        flat = {}
        for k, r in got.items():
            for f, v in r.items():
                flat[f"{k}|{f}"] = np.asarray(v)
        np.savez_compressed(args.path, **flat)
        print(f"wrote {len(got)} plans to {args.path}")
        return
    old = np.load(args.path)
    worst = {"s": 0.0, "z": 0.0, "controls": 0.0, "E": 0.0}
    bad = []
    counted: dict[str, int] = {}  # plans whose search counters differ, per planner
    for k, r in got.items():
        if str(old[f"{k}|status"]) != r["status"] or str(old[f"{k}|message"]) != r["message"]:
            bad.append(f"{k}: status/message {old[f'{k}|status']} -> {r['status']}")
            continue
        for f in worst:
            a, b = old[f"{k}|{f}"], np.asarray(r[f])
            if a.shape != b.shape:
                bad.append(f"{k}: {f} shape {a.shape} -> {b.shape}")
                continue
            if a.size:
                d = np.abs(a - b)
                d = d / np.maximum(np.abs(a), 1.0) if f == "E" else d
                worst[f] = max(worst[f], float(np.nanmax(d)) if np.isfinite(d).any() else 0.0)
        if not np.array_equal(old[f"{k}|counters"], r["counters"]):
            planner = k.split("/")[1]
            counted[planner] = counted.get(planner, 0) + 1
            if planner not in args.counters_may_change:
                bad.append(f"{k}: search counters {old[f'{k}|counters']} -> {r['counters']}")
    print(f"{len(got)} plans compared; largest differences: footholds s {worst['s']:.1e} m, "
          f"z {worst['z']:.1e} m, swing controls {worst['controls']:.1e} m, "
          f"E {worst['E']:.1e} (relative)")
    for planner, count in sorted(counted.items()):
        allowed = " (allowed)" if planner in args.counters_may_change else ""
        print(f"{planner}: {count} plans with other search counters{allowed}")
    print(f"{len(bad)} plans differ in status, message, shape or search counters")
    for line in bad[:20]:
        print("  " + line)
    same = not bad and worst["s"] <= 1e-9 and worst["z"] <= 1e-9 and worst["controls"] <= 1e-9
    print("SAME PLANS (to 1e-9 m)" if same else "PLANS DIFFER")
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
