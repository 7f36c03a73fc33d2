"""Facts of ``crowdwalk verify``'s counterflow case: start density, entry, trip times.

Runs ``crowdwalk.verify.counterflow_scenario`` (2 × 50 walkers, 4 m wide corridor) per
seed and prints one JSON line each: the walkers placed at the first tick per group, the
eastward group's density then in its node area (4.8 × 3.6 m) and in the area the points
are drawn in (the node area 0.25 m inside its walls), the share of those placed closer
than 0.36 m (two body radii) to another one and of all drawn points
(``drawn_closer_than_0.36m``: those wait until their spot is clear), when the last
walker entered [s], and per walker means of: the trip as verify counts it (travel time
from entering, ``travel_time_s``), the trip from t = 0 (entry time + travel time), the
free walk (walked distance / free speed, as verify's ratio uses), the free walk of the
straight route (distance from the entry point to the destination node along x, minus
``arrive_distance``, / free speed), and the trip / free walk ratio verify checks
(mean ≤ 1.5).

Usage: ``python scripts/counterflow_facts.py [--seeds 1 2 3 4 5] [--length 30]
[--set speed_model='headway' ...]`` (``--set``: CrowdParams fields, Python literals).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd import CrowdParams
from crowdwalk.crowd.params import parse_overrides
from crowdwalk.verify import _run, counterflow_scenario


def facts(seed: int, length: float, params, folder: Path) -> dict:
    """The start and trip figures of one counterflow run."""
    run = _run(counterflow_scenario(seed, length=length), folder, params)
    ag = run.summary["agents"]
    tr = run.traj
    first = {}
    for i in np.unique(tr.id):  # analysis of a finished run: one pass per walker
        k = np.flatnonzero(tr.id == i)
        j = k[np.argmin(tr.frame[k])]
        first[int(i)] = (tr.x[j], tr.y[j])
    start = np.array([a["start_time_s"] for a in ag])
    at0 = start <= start.min() + 1e-6  # placed at the first tick
    east = np.array([a["group"] == "eastward" for a in ag])
    xy0 = np.array([first[a["id"]] for a in ag])
    near = cKDTree(xy0[at0]).query(xy0[at0], k=2)[0][:, 1] < 0.36
    drawn = np.concatenate([cKDTree(xy0[g]).query(xy0[g], k=2)[0][:, 1] < 0.36
                            for g in (east, ~east)])
    free_speed = np.array([a["free_speed_m_s"] for a in ag])
    dist = np.array([a["distance_m"] for a in ag])
    travel = np.array([a["travel_time_s"] if a["arrived"] else np.nan for a in ag])
    goal_x = np.where(east, length - 2.5, 2.5)
    straight = np.maximum(np.abs(goal_x - xy0[:, 0]) - params.arrive_distance, 0.0)
    ok = np.isfinite(travel) & (dist > 0)
    return {"seed": seed, "placed_first_tick": [int((at0 & east).sum()), int((at0 & ~east).sum())],
            "density_node_area": round(float((at0 & east).sum()) / (4.8 * 3.6), 2),
            "density_drawn_area": round(float((at0 & east).sum()) / (4.3 * 3.1), 2),
            "closer_than_0.36m": round(float(near.mean()), 2),
            "drawn_closer_than_0.36m": round(float(drawn.mean()), 2),
            "last_entry_s": round(float(start.max()), 1),
            "entry_mean_s": round(float(start.mean()), 2),
            "arrived": int(ok.sum()),
            "trip_s": round(float(np.mean(travel[ok])), 1),
            "trip_from_0_s": round(float(np.mean((start + travel)[ok])), 1),
            "free_walk_s": round(float(np.mean(dist[ok] / free_speed[ok])), 1),
            "free_walk_straight_s": round(float(np.mean(straight[ok] / free_speed[ok])), 1),
            "walked_m": round(float(np.mean(dist[ok])), 1),
            "trip_ratio": round(float(np.mean(travel[ok] / (dist[ok] / free_speed[ok]))), 2)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--length", type=float, default=30.0)
    ap.add_argument("--set", nargs="*", default=[], metavar="FIELD=VALUE")
    args = ap.parse_args()
    fields = parse_overrides(args.set)
    params = CrowdParams().with_overrides(fields)
    with tempfile.TemporaryDirectory() as tmp:
        for s in args.seeds:
            print(json.dumps({**fields, **facts(s, args.length, params, Path(tmp) / str(s))}),
                  flush=True)


if __name__ == "__main__":
    main()
