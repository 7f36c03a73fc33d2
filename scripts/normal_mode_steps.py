"""Planned level step vs the normal-mode step (WBDS) for bodies and speeds (issue 11).

For each body height and speed, plans four steps on level ground with every planner and
prints the planned step against ``planners.normal_mode.step_length`` at the body's leg
length, and the continuous optimum of the energy model (Eqs. 1-4 and the frequency term,
step length / energy maximal over a 1 mm grid). ``--paper`` uses ``step_model="paper"``.

Usage: ``python scripts/normal_mode_steps.py [--paper]``
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from planners import GroundProfile, Leg, PlannerConfig, normal_mode, plan  # noqa: E402
from planners.energy import step_energy  # noqa: E402

HEIGHTS = (1.50, 1.65, 1.75, 1.85, 1.95)
SPEEDS = (0.8, 1.0, 1.2, 1.33, 1.5, 1.7, 1.8)


def continuous_optimum(leg: Leg, speed: float, config: PlannerConfig) -> float:
    """Step length [m] of best level efficiency over a 1 mm grid."""
    L = np.arange(0.2, 1.1 * leg.length, 0.001)
    z = np.zeros_like(L)
    summit = z + leg.ankle_height + 0.75 * config.swing_lift
    _, _, _, E, ok = step_energy(z, z, L, z, summit, leg, speed, config)
    return float(L[np.argmax(np.where(ok, L / E, -np.inf))])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paper", action="store_true", help='step_model="paper"')
    args = ap.parse_args(argv)
    config = PlannerConfig(step_model="paper" if args.paper else "normal_mode")
    flat = GroundProfile.flat(12.0, 0.0, -2.0)
    print("height  speed  normal   best_first  fixed    optimum   [m, % off normal]")
    worst = {"best_first": 0.0, "fixed": 0.0, "optimum": 0.0}
    for h in HEIGHTS:
        leg = Leg.from_body_height(h)
        for v in SPEEDS:
            normal = float(normal_mode.step_length(v, normal_mode.leg_length_of(leg)))
            got = {name: float(plan(flat, leg, v, name, config).step_lengths[0])
                   for name in ("best_first", "fixed")}
            got["optimum"] = continuous_optimum(leg, v, config)
            off = {k: (x / normal - 1) * 100 for k, x in got.items()}
            for k in worst:
                worst[k] = max(worst[k], abs(off[k]))
            print(f"{h:5.2f}  {v:5.2f}  {normal:.3f}   " + "  ".join(
                f"{got[k]:.3f} {off[k]:+5.1f}" for k in ("best_first", "fixed", "optimum")))
    print("largest |deviation| [%]: " + ", ".join(f"{k} {x:.1f}" for k, x in worst.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
