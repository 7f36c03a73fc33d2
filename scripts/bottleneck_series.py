"""Bottleneck width series over seeds: flow and zipper measures per width.

Runs ``crowdwalk verify``'s bottleneck scenario (``crowdwalk.verify._bottleneck``: a
room, a 2 m long opening, 60 walkers) per width and seed with the flow as verify
measures it (door line crossings 6 to n − 5), and prints one JSON line per width: the
flow per seed, its mean and 95 % interval (Student t), Seyfried et al.'s (2009) band,
and at mid-opening (x = 9 m) the share of consecutive walkers on alternating sides
(``alternate``), the share more than 0.1 m off the axis (``off_axis``) and the lane
separation (mean offset of the walkers left of the axis minus that of those right of
it, ``lane_sep``; Hoogendoorn & Daamen 2005: about 0.45 m in a 1 m bottleneck).

Usage: ``python scripts/bottleneck_series.py [--widths 0.8 0.9 1.0 1.1 1.2]
[--seeds 4 5 6] [--count 60] [--set opening_ease=True ...]`` (``--set``: CrowdParams
fields, Python literals; about 8 s per run).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
from scipy import stats

from crowdwalk.analysis import analyse_run
from crowdwalk.crowd import CrowdParams
from crowdwalk.crowd.params import parse_overrides
from crowdwalk.verify import _bottleneck, _run, seyfried_band


def measure(width: float, seed: int, count: int, params, folder: Path) -> dict:
    """Flow [1/s] and the zipper measures of one run."""
    run = _run(_bottleneck(width, seed, count), folder, params)
    analyse_run(run.folder, plots=False)
    rows = np.genfromtxt(folder / "analysis" / "line_door.csv", delimiter=",", names=True)
    crossed, t = rows["crossed"], rows["time_s"]
    n = int(crossed.max())
    flow = (n - 11) / (t[np.argmax(crossed >= n - 5)] - t[np.argmax(crossed >= 6)])
    tr, side = run.traj, []
    for i in np.unique(tr.id):  # analysis of a finished run: one pass per walker
        k = np.flatnonzero(tr.id == i)
        c = k[np.flatnonzero((tr.x[k][:-1] < 9.0) & (tr.x[k][1:] >= 9.0))]
        if c.size:
            side.append((tr.frame[c[0]], tr.y[c[0]] - 5.0))
    side.sort()
    ys = np.array([y for _, y in side])
    return {"flow": float(flow),
            "alternate": float(np.mean(np.sign(ys[1:]) != np.sign(ys[:-1]))),
            "off_axis": float(np.mean(np.abs(ys) > 0.1)),
            "lane_sep": float(ys[ys > 0].mean() - ys[ys < 0].mean())
            if (ys > 0).any() and (ys < 0).any() else float("nan")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--widths", type=float, nargs="+", default=[0.8, 0.9, 1.0, 1.1, 1.2])
    ap.add_argument("--seeds", type=int, nargs="+", default=[4, 5, 6])
    ap.add_argument("--count", type=int, default=60)
    ap.add_argument("--set", nargs="*", default=[], metavar="FIELD=VALUE")
    args = ap.parse_args()
    fields = parse_overrides(args.set)
    params = CrowdParams().with_overrides(fields)
    with tempfile.TemporaryDirectory() as tmp:
        for w in args.widths:
            runs = [measure(w, s, args.count, params, Path(tmp) / f"bn_{w:g}_{s}")
                    for s in args.seeds]
            flows = np.array([r["flow"] for r in runs])
            mean = float(flows.mean())
            half = (float(stats.t.ppf(0.975, flows.size - 1) * flows.std(ddof=1)
                          / np.sqrt(flows.size)) if flows.size > 1 else float("nan"))
            print(json.dumps({"width": w, "flows": flows.round(3).tolist(),
                              "mean": round(mean, 3),
                              "ci95": [round(mean - half, 3), round(mean + half, 3)],
                              "band": seyfried_band(w),
                              **{k: round(float(np.nanmean([r[k] for r in runs])), 3)
                                 for k in ("alternate", "off_axis", "lane_sep")}}),
                  flush=True)


if __name__ == "__main__":
    main()
