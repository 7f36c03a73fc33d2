"""Calibrate the crowd's time gap T on the SFPE handbook's corridor speeds.

The time-gap speed model (``crowdwalk.crowd.speed``; Tordeux et al. 2016's collision-
free speed model applied per step) has one free parameter, the time gap T [s]. This
script fits it on **one** data set — the SFPE handbook's corridor relation v = 1.40 (1 −
0.266 D) m/s (Nelson & Mowrer 2002) — by running the closed ring corridor of
``crowdwalk verify`` (RiMEA 4) at several densities for each candidate T and printing
the speed measured with PedPy against SFPE, and the root-mean-square error per T.
Weidmann's (1993) diagram and Seyfried et al.'s (2009) bottleneck flows are then the
validation (``crowdwalk verify``, tests), never used here.

Usage: ``python scripts/calibrate_time_gap.py [--model contact_gap] [--gaps 0.6 0.7 0.8
0.9] [--densities 0.75 1.5 2.5]`` (about a minute per run on a free core); ``--model``
is the speed model whose T is fitted (``time_gap`` or ``contact_gap``).
"""

from __future__ import annotations

import argparse
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from crowdwalk.crowd import CrowdParams
from crowdwalk.verify import ring_corridor_speed, sfpe_speed


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", choices=["time_gap", "contact_gap"], default="contact_gap")
    ap.add_argument("--gaps", type=float, nargs="+", default=[0.6, 0.7, 0.8, 0.9])
    ap.add_argument("--densities", type=float, nargs="+", default=[0.75, 1.5, 2.5])
    args = ap.parse_args()
    print("| T [s] | set ρ [1/m²] | measured ρ [1/m²] | v [m/s] | SFPE v [m/s] |")
    print("|---|---|---|---|---|")
    rms = {}
    with tempfile.TemporaryDirectory() as tmp:
        for gap in args.gaps:
            params = replace(CrowdParams(), speed_model=args.model,
                             **{"time_gap" if args.model == "time_gap"
                                else "contact_time_gap": gap})
            err = []
            for rho in args.densities:
                d, v = ring_corridor_speed(rho, Path(tmp) / f"T{gap}_{rho}", params=params)
                ref = float(sfpe_speed(d))
                err.append(v - ref)
                print(f"| {gap:.2f} | {rho:g} | {d:.2f} | {v:.3f} | {ref:.3f} |", flush=True)
            rms[gap] = float(np.sqrt(np.mean(np.square(err))))
    print()
    for gap, e in rms.items():
        print(f"T = {gap:.2f} s: RMS error against SFPE {e:.3f} m/s")
    print(f"best: T = {min(rms, key=rms.get):.2f} s")


if __name__ == "__main__":
    main()
