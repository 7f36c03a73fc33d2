"""Reproduce Chen & Li's figures: Fig. 2 (efficiency against step length) and Fig. 11.

Usage: ``python scripts/reproduce_chen_li.py OUT_DIR``. Writes

- ``fig2_efficiency.png``: Eq. 5 on flat ground against step length for three body
  heights (and the measured preferred step length band), with the optimum marked;
- ``fig11_obstacle.png``: a low block (10 cm high, 35 cm deep) on the neutral footholds:
  the unplanned ``fixed`` walker steps onto it, ``best_first`` strides across;
- ``fig11_stairs.png``: the three planners on a flight of stairs;

and prints the numbers behind them.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from crowdwalk.plots import plot_efficiency_curve, plot_plan
from planners import GroundProfile, Leg, flat_efficiency, plan


def figure_2(out: Path) -> None:
    lengths = np.linspace(0.25, 0.95, 141)
    heights = (1.55, 1.75, 1.90)
    curves = np.array([flat_efficiency(Leg.from_body_height(h), 1.34, lengths)
                       for h in heights])
    path = plot_efficiency_curve(lengths, curves, out / "fig2_efficiency.png",
                                 labels=[f"body {h:.2f} m, 1.34 m/s" for h in heights],
                                 unit="m kg/J")
    print("Fig. 2: flat-ground efficiency (Eq. 5) peaks at")
    for h, c in zip(heights, curves, strict=True):
        print(f"  body {h:.2f} m: step {lengths[np.argmax(c)]:.3f} m "
              f"(efficiency {c.max():.4f} m kg/J)")
    print(f"  -> {path}")


def figure_11(out: Path) -> None:
    leg = Leg.from_body_height(1.75)
    block = GroundProfile(np.array([-2, 1.15, 1.15, 1.5, 1.5, 8]),
                          np.array([0, 0, 0.10, 0.10, 0, 0]))
    fixed = plan(block, leg, 1.34, "fixed")
    planned = plan(block, leg, 1.34, "best_first")
    path = plot_plan(block, [fixed, planned], out / "fig11_obstacle.png",
                     title="Fig. 11: a 10 cm x 35 cm block; (a) fixed, (b) best_first")
    print("Fig. 11: block 10 cm high, 35 cm deep at s = 1.15..1.50 m")
    for name, p in (("fixed (a)", fixed), ("best_first (b)", planned)):
        print(f"  {name:<15} footholds s = {np.round(p.footholds_s, 3).tolist()} "
              f"z = {np.round(p.footholds_z, 2).tolist()}  "
              f"{p.energy_per_metre:.3f} J/(kg m)")
    saving = 1 - planned.energy_per_metre / fixed.energy_per_metre
    print(f"  planning saves {100 * saving:.1f} % energy per metre  -> {path}")
    stairs = GroundProfile.stairs(0.17, 0.30, 6, first_edge=0.4)
    plans = [plan(stairs, leg, 1.34, name) for name in ("fixed", "best_first", "optimal")]
    path = plot_plan(stairs, plans, out / "fig11_stairs.png",
                     title="Stairs (rise 17 cm, going 30 cm)")
    print("Stairs: " + ", ".join(f"{p.planner} {p.energy_per_metre:.2f} J/(kg m)"
                                 for p in plans) + f"  -> {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="output folder")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    figure_2(args.out)
    figure_11(args.out)


if __name__ == "__main__":
    main()
