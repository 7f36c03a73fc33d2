"""Derive ``crowdwalk/data/joint_references.json``: the joint-angle reference curves the gait
report compares a run with.

- Winter (1991) group means ± SD of hip, knee and ankle flexion at slow, natural and fast
  cadence (``winter1991_slow_natural_fast_cadence.xlsx``), 51 samples over the stride.
- Bovi et al. (2011) adult knee flexion mean ± SD in stair ascent and descent
  (``bovi2011_multitask_reference_mmc3.xls``, sheet Joint Rotations), resampled to the
  same 51 samples.

Usage: ``python scripts/derive_joint_references.py [--gait-dir DIR] [--check]``
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
GAIT_DIR = next((p / "shared" / "data" / "gait" for p in (REPO.parent, REPO.parent.parent)
                 if (p / "shared" / "data" / "gait").is_dir()), REPO.parent / "shared")
OUT = REPO / "crowdwalk" / "data" / "joint_references.json"
WINTER = ("Winter DA (1991). The Biomechanics and Motor Control of Human Gait: Normal, "
          "Elderly and Pathological, 2nd ed., Univ. of Waterloo Press: group means +/- SD "
          "at slow, natural and fast cadence (EpicToolbox 'Biomechanics Data.xlsx').")
WINTER_CADENCE = {"slow": 87.0, "natural": 105.0, "fast": 123.0}  # steps/min, Winter 1991
BOVI = ("Bovi G, Rabuffetti M, Mazzoleni P, Ferrarin M (2011). A multiple-task gait analysis "
        "approach: kinematic, kinetic and EMG reference data for healthy young and adult "
        "subjects. Gait & Posture 33(1):6-13, supplement mmc3, adult group.")
BOVI_TASKS = ["Natural", "XS", "S", "M", "L", "Toe", "Heel", "Ascending", "Descending"]
ADULT_FIRST_COLUMN = 2 + 3 * len(BOVI_TASKS)
T = np.linspace(0.0, 1.0, 51)


def derive(gait_dir: Path) -> dict:
    import pandas as pd

    out = {"t": T.round(3).tolist(), "units": "deg; t = stride fraction from heel strike",
           "winter": {"source": WINTER, "cadence_steps_per_min": WINTER_CADENCE}}
    for name in WINTER_CADENCE:
        sheet = pd.read_excel(gait_dir / "winter1991_slow_natural_fast_cadence.xlsx",
                              sheet_name=f"Joint Angles {name.title()} Cadence")
        sheet = sheet.apply(pd.to_numeric, errors="coerce").dropna(subset=["Percent Stride"])
        out["winter"][name] = {
            joint.lower(): {"mean": sheet[f"{joint} Mean"].round(2).tolist(),
                            "sd": sheet[f"{joint} Std. Dev."].round(2).tolist()}
            for joint in ("Hip", "Knee", "Ankle")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rot = pd.read_excel(gait_dir / "bovi2011_multitask_reference_mmc3.xls",
                            sheet_name="Joint Rotations", header=None)
    knee = rot[rot[0].astype(str).str.strip() == "Knee Flex/Extension"]
    t_bovi = knee[1].to_numpy(float)
    out["bovi"] = {"source": BOVI}
    for name, task in (("stairs_up", "Ascending"), ("stairs_down", "Descending")):
        col = ADULT_FIRST_COLUMN + 3 * BOVI_TASKS.index(task)
        low, mean, high = (knee[col + k].to_numpy(float) for k in range(3))
        out["bovi"][name] = {"knee": {
            "mean": np.interp(T, t_bovi, mean).round(2).tolist(),
            "sd": np.interp(T, t_bovi, (high - low) / 2).round(2).tolist()}}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gait-dir", type=Path, default=GAIT_DIR)
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    data = derive(args.gait_dir)
    text = json.dumps(data, indent=1) + "\n"
    for name in ("stairs_up", "stairs_down"):
        print(f"Bovi {name} knee peak {max(data['bovi'][name]['knee']['mean']):.1f} deg")
    if args.check:
        same = OUT.read_text() == text
        print("joint_references.json " + ("matches" if same else "DIFFERS"))
        return 0 if same else 1
    OUT.write_text(text)
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
