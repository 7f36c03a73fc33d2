"""Generated hip, knee and ankle flexion over a level cycle vs Winter (1991).

As Sun & Metaxas (2001, Fig. 15) compare their generated motion with Inman et al., this
script drives ElevWalker with the shipped ``level_natural`` dataset (Bovi et al. 2011,
adult natural speed) for a body, measures hip, knee and ankle flexion on the posed
skeleton, and compares them with Winter's natural-cadence group means (Winter 1991, in
``../shared/data/gait/winter1991_slow_natural_fast_cadence.xlsx``): RMS error, correlation
and mean offset per joint. It prints a table and writes a PNG.

Usage: ``python scripts/gait_validation_report.py [--out gait_validation.png]
[--height 1.75]``
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

WINTER = (
    Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "gait"
    / "winter1991_slow_natural_fast_cadence.xlsx"
)  # fmt: skip
JOINTS = ("Hip", "Knee", "Ankle")


def load_winter(path: Path = WINTER, cadence: str = "Natural") -> dict[str, np.ndarray]:
    """Winter's joint-angle group means: ``t`` (51,) stride fraction [1], and per joint
    ``Hip``/``Knee``/``Ankle`` mean and ``<joint> sd`` (51,) [deg]."""
    import pandas as pd

    table = pd.read_excel(path, sheet_name=f"Joint Angles {cadence} Cadence")
    table = table.apply(pd.to_numeric, errors="coerce").dropna(subset=["Percent Stride"])
    out = {"t": table["Percent Stride"].to_numpy(float) / 100.0}
    for joint in JOINTS:
        out[joint] = table[f"{joint} Mean"].to_numpy(float)
        out[f"{joint} sd"] = table[f"{joint} Std. Dev."].to_numpy(float)
    return out


def generated_flexion(height: float = 1.75, samples: int = 100) -> dict[str, np.ndarray]:
    """Hip, knee, ankle flexion [deg] of ElevWalker over one level stride (left leg)."""
    from crowdwalk.gait.datasets import dataset_by_name
    from crowdwalk.gait.elevwalker import joint_flexion, walk_cycle

    elevations, converged = walk_cycle(dataset_by_name("level_natural").angles, height, samples)
    if not converged.all():
        raise RuntimeError("ElevWalker did not converge on the level cycle")
    flex = np.rad2deg(joint_flexion(elevations))
    out = {"t": np.arange(samples) / samples}
    for i, joint in enumerate(JOINTS):
        out[joint] = flex[:, i]
    return out


def compare(generated: dict, reference: dict) -> dict[str, dict[str, float]]:
    """RMS error, RMS after removing the mean offset [deg], correlation and offset per
    joint, with the generated curves sampled at the reference's stride fractions."""
    t_ref = np.mod(reference["t"], 1.0)
    t_gen = np.append(generated["t"], 1.0)
    metrics = {}
    for joint in JOINTS:
        gen = np.interp(t_ref, t_gen, np.append(generated[joint], generated[joint][0]))
        ref = reference[joint]
        diff = gen - ref
        offset = float(diff.mean())
        metrics[joint] = {
            "rms": float(np.sqrt(np.mean(diff**2))),
            "rms_centred": float(np.sqrt(np.mean((diff - offset) ** 2))),
            "correlation": float(np.corrcoef(gen, ref)[0, 1]),
            "offset": offset,
        }
    return metrics


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("gait_validation.png"))
    parser.add_argument("--height", type=float, default=1.75, help="Body height [m].")
    args = parser.parse_args(argv)
    reference = load_winter()
    generated = generated_flexion(args.height)
    metrics = compare(generated, reference)
    print(f"{'joint':<6} {'RMS [deg]':>10} {'RMS-offset [deg]':>17} {'r':>6} {'offset [deg]':>13}")
    for joint, m in metrics.items():
        print(f"{joint:<6} {m['rms']:>10.2f} {m['rms_centred']:>17.2f} "
              f"{m['correlation']:>6.3f} {m['offset']:>13.2f}")  # fmt: skip
    from crowdwalk.plots import plot_gait_validation

    path = plot_gait_validation(generated, reference, metrics, args.out)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
