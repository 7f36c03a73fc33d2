"""Planned against unplanned walkers: what each search contributes over ``fixed``.

Usage: ``python scripts/planner_study.py`` from the repository root. Walks every profile
in ``scenarios/profiles/`` (and a 15 cm curb) as ``crowdwalk plan --profile P.csv
--planner X`` does (receding horizon, 1.75 m body, 1.34 m/s, default PlannerConfig), for
each planner, and prints the energy [J/kg] to the same point (the shortest walk's end,
its last step pro rata) against ``fixed``, and whether a foothold lands on the Fig. 11
block.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from crowdwalk.planning import plan_profile

ROOT = Path(__file__).resolve().parents[1]
PLANNERS = ("fixed", "best_first", "best_first_multistart", "optimal")
CURB = "# a 15 cm curb 0.9 m ahead\ns,z\n-2,0\n0.9,0\n0.9,0.15\n8,0.15\n"


def energy_to(walked, s: float) -> float:
    """Summed step energy [J/kg] until the footholds pass ``s`` [m] (pro rata)."""
    return float(np.interp(s, walked.footholds_s, np.concatenate([[0], np.cumsum(walked.E)])))


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        curb = Path(tmp) / "curb.csv"
        curb.write_text(CURB)
        paths = sorted((ROOT / "scenarios" / "profiles").glob("*.csv")) + [curb]
        print(f"{'profile':<12}" + "".join(f"{p:>24}" for p in PLANNERS))
        for path in paths:
            walks = {p: plan_profile(path, p) for p in PLANNERS}
            end = min(w.footholds_s[-1] for w in walks.values())
            base = energy_to(walks["fixed"], end)
            cells = []
            for w in walks.values():
                e = energy_to(w, end)
                tag = "" if w.ok else " blocked"
                if path.stem == "block":
                    tag += " on" if np.any(w.footholds_z > 0.05) else " over"
                cells.append(f"{e:7.2f} ({100 * (e / base - 1):+5.1f} %){tag}")
            print(f"{path.stem:<12}" + "".join(f"{c:>24}" for c in cells)
                  + f"   to s = {end:.2f} m")
    print("\nenergy [J/kg] to the same point (change against fixed); block: 'on' = a "
          "foothold on the Fig. 11 block, 'over' = strides across; blocked = stopped by "
          "a wall")


if __name__ == "__main__":
    main()
