"""The counterflow trip a walker would have at Weidmann's speed for the density it met.

For each walker of finished counterflow runs (run folders of
``crowdwalk.verify.counterflow_scenario``, e.g. written by
``python scripts/counterflow_facts.py`` or ``crowdwalk run``): the trip / free walk ratio
it had (as ``crowdwalk verify`` counts it) and the one it would have walking each step at
Weidmann's speed for the PedPy Voronoi density it met there, scaled to its free speed
(``crowdwalk.verify.weidmann_trip_ratio``; density clipped at ``--clip``, 3.5 /m²), the
part of that ratio's excess over 1 walked within 5 m of its own start end
(``excess_start_zone``), the mean of its speed minus Weidmann's for its free speed, and
the walker-frames binned by density (share, measured speed, Weidmann's). A mean
Weidmann ratio above 1.5 means no walker that follows Weidmann in the crowd it meets
passes the case's trip criterion.

Usage: ``python scripts/counterflow_weidmann.py RUN_DIR [RUN_DIR ...] [--length 30]
[--clip 3.5]``; one JSON line per run, then one for all runs together.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from crowdwalk.verify import walker_frames, weidmann_speed, weidmann_trip_ratio

BINS = (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 10.0)


def run_figures(run_dir: Path, length: float, clip: float) -> tuple[dict, list, list]:
    """One run's figures (module docstring), and its walkers' ratios had and at Weidmann."""
    summary = json.loads((run_dir / "summary.json").read_text())
    agents = [a for a in summary["agents"] if a["arrived"] and a["distance_m"] > 0]
    fr = walker_frames(run_dir, summary, (0.0, 0.0, length, 4.0))
    would = weidmann_trip_ratio(fr, agents, clip)
    rho = np.minimum(fr.density, clip)
    slow = 1.34 / weidmann_speed(rho)
    w = fr.free_speed / slow
    had, excess, start = [], [], []
    for a in agents:
        k = fr.id == a["id"]
        had.append(a["travel_time_s"] / (a["distance_m"] / a["free_speed_m_s"]))
        excess.append(float(np.nanmean(fr.speed[k] - w[k])))
        own = (fr.x[k] < 5.0) if a["group"] == "eastward" else (fr.x[k] > length - 5.0)
        start.append(float(np.sum((fr.step[k] * (slow[k] - 1.0))[own]) / np.sum(fr.step[k])))
    idx = np.digitize(fr.density, BINS) - 1
    bins = [{"rho": round(float(fr.density[m].mean()), 2), "share": round(float(m.mean()), 3),
             "v": round(float(np.nanmean(fr.speed[m])), 2),
             "v_weidmann": round(float(w[m].mean()), 2)}
            for m in (idx == b for b in range(len(BINS) - 1)) if m.sum() >= 20]
    return ({"run": run_dir.name, "walkers": len(had),
             "trip_ratio_had": round(float(np.mean(had)), 2),
             "trip_ratio_weidmann": round(float(np.mean(would)), 2),
             "trip_ratio_weidmann_min_max": [round(float(would.min()), 2),
                                             round(float(would.max()), 2)],
             "excess_start_zone": round(float(np.mean(start)), 2),
             "density_path_mean": round(float(np.sum(rho * fr.step) / np.sum(fr.step)), 2),
             "speed_minus_weidmann_mean": round(float(np.mean(excess)), 2),
             "bins": bins}, had, list(would))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--length", type=float, default=30.0)
    ap.add_argument("--clip", type=float, default=3.5, metavar="PER_M2")
    args = ap.parse_args()
    had, would = [], []
    for r in args.runs:
        f, h, w = run_figures(r, args.length, args.clip)
        had += h
        would += w
        print(json.dumps(f), flush=True)
    print(json.dumps({"runs": len(args.runs), "trip_ratio_had": round(float(np.mean(had)), 2),
                      "trip_ratio_weidmann": round(float(np.mean(would)), 2)}))


if __name__ == "__main__":
    main()
