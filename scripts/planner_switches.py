"""What two planner switches change under today's defaults: ``EnergyWeights.vertical``
(``"linear"``, the default, against Eq. 2 as printed) and ``PlannerConfig.snap`` (True,
the default, against the rigid grid).

Usage: ``python scripts/planner_switches.py [--profiles N]`` from the repository root.
A lone walker (1.75 m body, 1.34 m/s, ``best_first_multistart``, receding horizon:
``planners.walk``) on ramps of 0-15 %, on the profiles of ``scenarios/profiles/`` and on
N random terrain profiles (``benchmarks/bench_planners.random_terrain``, seed 3);
``--paper-steps`` adds both on the paper's step-length grid (``step_model="paper"``,
footholds compared with that grid's default). Prints
per ground the median step length [m], the energy per metre [J/(kg m)] to the same point
(the shortest walk's end; each walk's under its own energy model) and whether the walk
reached the end and its footholds differ from the default's, for the default and each
alternative. The printed quadratic is taken with β scaled so that a 17 cm riser costs
what it costs with the fitted linear form (0.0361 × Ev_linear(17) / Ev_paper(17)), as
the hand-set pair 0.0549 / 0.0961 was.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_planners import random_terrain  # noqa: E402

from planners import GroundProfile, Leg, PlannerConfig, walk  # noqa: E402
from planners.energy import vertical_energy  # noqa: E402


def variants() -> dict[str, PlannerConfig]:
    """The default configuration and the two alternatives."""
    base = PlannerConfig()
    w = base.weights
    scale = float(vertical_energy(0.17, model="linear") / vertical_energy(0.17, model="paper"))
    paper = replace(w, vertical="paper", beta=w.beta * scale)
    grid = replace(base, step_model="paper")
    out = {"default": base, "vertical=paper": replace(base, weights=paper),
           "snap=False": replace(base, snap=False)}
    if PAPER_STEPS:  # the same two on the paper's step-length grid (step_model="paper")
        out.update({"paper steps": grid,
                    "paper steps, vertical=paper": replace(grid, weights=paper)})
    return out


PAPER_STEPS = "--paper-steps" in sys.argv


def grounds(count: int) -> dict[str, GroundProfile]:
    """Ramps, the scenario profiles and ``count`` random profiles."""
    out = {f"ramp {g:.0f} %": GroundProfile(np.array([-2.0, 0.3, 9.0]),
                                            np.array([0.0, 0.0, 8.7 * g / 100]))
           for g in (0, 5, 8, 10, 15)}
    for path in sorted((ROOT / "scenarios" / "profiles").glob("*.csv")):
        data = np.loadtxt(path, delimiter=",", comments=("#", "s"), ndmin=2)
        out[path.stem] = GroundProfile(data[:, 0], data[:, 1])
    rng = np.random.default_rng(3)
    for i in range(count):
        out[f"random {i}"] = random_terrain(rng)
    return out


def energy_to(walked, s: float) -> float:
    """Summed step energy [J/kg] until the footholds pass ``s`` [m] (pro rata)."""
    return float(np.interp(s, walked.footholds_s,
                           np.concatenate([[0.0], np.cumsum(walked.E)])))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profiles", type=int, default=40, help="random profiles")
    parser.add_argument("--paper-steps", action="store_true",
                        help="also the default and vertical=paper with step_model='paper'")
    args = parser.parse_args()
    leg = Leg.from_body_height(1.75)
    configs = variants()
    print("median step [m], energy per metre [J/(kg m)] to the end of the shorter of the "
          "walk and its reference (the default; for 'paper steps, ...' 'paper steps'), "
          "reached the end; * footholds differ from the reference's")
    print(f"{'ground':<14}" + "".join(f"{n:>36}" for n in configs))
    summary = {n: [] for n in configs}
    for name, ground in grounds(args.profiles).items():
        stop = min(6.0, float(ground.s[-1]) - 1.0)
        walks = {n: walk(ground, leg, 1.34, "best_first_multistart", c, stop=stop)
                 for n, c in configs.items()}
        cells = []
        for n, w in walks.items():
            ref = walks["paper steps" if n.startswith("paper steps, ") else "default"]
            end = min(float(w.footholds_s[-1]), float(ref.footholds_s[-1]))
            per = [energy_to(x, end) / end if end > 0 else np.nan for x in (w, ref)]
            step = float(np.median(w.step_lengths)) if w.step_lengths.size else np.nan
            same = (w.footholds_s.shape == ref.footholds_s.shape
                    and bool(np.all(np.abs(w.footholds_s - ref.footholds_s) <= 1e-9)))
            summary[n].append((per[0], per[1], w.ok, ref.ok, same, name))
            cells.append(f"{step:5.3f} m {per[0]:6.3f} J/(kg m) "
                         f"{'ok' if w.ok else 'blocked'}{'' if same else ' *'}")
        if not name.startswith("random") or int(name.split()[1]) < 3:
            print(f"{name:<14}" + "".join(f"{c:>36}" for c in cells))
    print(f"\nrandom terrain, {args.profiles} profiles, against the reference:")
    for n, rows in summary.items():
        rows = [r for r in rows if r[5].startswith("random")]
        if not rows or n in ("default", "paper steps"):
            continue
        e = np.array([r[0] for r in rows])
        e0 = np.array([r[1] for r in rows])
        ok = np.array([r[2] for r in rows])
        both = ok & np.array([r[3] for r in rows]) & np.isfinite(e) & np.isfinite(e0)
        d = 100 * (e[both] / e0[both] - 1)
        print(f"  {n}: reaching the end {int(ok.sum())} (reference "
              f"{sum(r[3] for r in rows)}); footholds differ in "
              f"{sum(not r[4] for r in rows)}; energy per metre (both reaching the end, "
              f"{both.sum()}) median {np.median(d):+.2f} %, range {d.min():+.2f} .. "
              f"{d.max():+.2f} %")

if __name__ == "__main__":
    main()
