"""Reproduce Chen & Li's figures: Fig. 2 (efficiency against step length) and Fig. 11.

Usage: ``python scripts/reproduce_chen_li.py OUT_DIR``. Writes

- ``fig2_efficiency.png``: Eq. 5 on flat ground against step length for three body
  heights (and the measured preferred step length band), with the optimum marked;
- ``fig11_obstacle.png``: a low block (10 cm high, 35 cm deep) on the neutral footholds:
  the unplanned ``fixed`` walker steps onto it; so does Chen & Li's ``best_first`` as
  written (one start, the grid neighbours; with this project's criterion and with the
  paper's own: Eq. 5 over the planned steps, a rigid grid, Eq. 2 as printed), while
  ``best_first_multistart`` and ``optimal`` stride across;
- ``fig11_stairs.png``: the planners on a flight of stairs;

and prints the numbers behind them.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from crowdwalk.plots import plot_efficiency_curve, plot_plan
from planners import EnergyWeights, GroundProfile, Leg, PlannerConfig, flat_efficiency, plan

#: Chen & Li's model throughout: Eq. 5 over the n planned steps, the rigid grid of
#: §6.2, Eqs. 1-4 alone (no step-frequency term) and Eq. 2 as printed.
PAPER = PlannerConfig(terminal_cost=False, snap=False, step_model="paper",
                      weights=EnergyWeights(vertical="paper"))


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
    cases = [("fixed (a)", plan(block, leg, 1.34, "fixed")),
             ("best_first", plan(block, leg, 1.34, "best_first")),
             ("best_first, paper criterion", plan(block, leg, 1.34, "best_first", PAPER)),
             ("best_first_multistart (b)", plan(block, leg, 1.34, "best_first_multistart")),
             ("optimal", plan(block, leg, 1.34, "optimal"))]
    path = plot_plan(block, [cases[0][1], cases[1][1], cases[3][1]],
                     out / "fig11_obstacle.png",
                     title="Fig. 11: a 10 cm x 35 cm block; fixed, best_first, multistart")
    print("Fig. 11: block 10 cm high, 35 cm deep at s = 1.15..1.50 m")
    fixed_cost = cases[0][1].energy_per_metre
    for name, p in cases:
        on = bool(np.any(p.footholds_z > 0.05))
        change = 100 * (p.energy_per_metre / fixed_cost - 1)
        print(f"  {name:<29} footholds s = {np.round(p.footholds_s, 3).tolist()} "
              f"{'steps onto the block' if on else 'strides across'}; "
              f"{p.energy_per_metre:.3f} J/(kg m) ({change:+.1f} % against fixed)")
    print(f"  -> {path}")
    stairs = GroundProfile.stairs(0.17, 0.30, 6, first_edge=0.4)
    plans = [plan(stairs, leg, 1.34, name)
             for name in ("fixed", "best_first", "best_first_multistart", "optimal")]
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
