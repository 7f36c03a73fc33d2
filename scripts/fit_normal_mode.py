"""Fit the normal-mode step length relation of ``planners.normal_mode`` to WBDS and validate it.

Calibration: all 258 treadmill trials (43 adults x 6 speeds) of the WBDS per-trial table
(Fukuchi, Fukuchi & Duarte 2018), least squares of the dimensionless step length
``SL / L`` on the dimensionless speed ``v / sqrt(g L)`` with Alexander's (1984) power law.
Validation: the speed-category means of Schwartz, Rozumalski & Trost (2008), children
walking overground, reported in the same dimensionless units. Run from anywhere::

    python scripts/fit_normal_mode.py [--gait-dir DIR] [--check]

``--check`` exits 1 when the refitted coefficients differ from the ones shipped in
``planners/normal_mode.py`` by more than rounding.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
# ../shared next to the repository (a worktree under /work/wt looks one level further up).
GAIT_DIR = next((p / "shared" / "data" / "gait" for p in (REPO.parent, REPO.parent.parent)
                 if (p / "shared" / "data" / "gait").is_dir()), REPO.parent / "shared")
WBDS_FILE = "wbds_treadmill_speed_steplength_cadence.csv"
SCHWARTZ_FILE = "schwartz2008_speed_reference_original.xls"
G = 9.81


def fit_wbds(gait_dir: Path) -> dict:
    """Coefficients, residuals and per-speed-category bias of the WBDS fit."""
    import pandas as pd
    from scipy.optimize import curve_fit

    wbds = pd.read_csv(gait_dir / WBDS_FILE)
    v = wbds["Speed"].to_numpy(float)
    leg = wbds["LegLength"].to_numpy(float)
    sl = wbds["StepLength"].to_numpy(float)
    cadence = wbds["Cadence"].to_numpy(float) / 60.0  # steps/s
    v_hat = v / np.sqrt(G * leg)
    (coef, expo), _ = curve_fit(lambda x, c, e: c * x ** e, v_hat, sl / leg, p0=(1.0, 0.5))
    sl_fit = coef * leg * v_hat ** expo
    freq_fit = v / sl_fit
    rows = []
    for cat in sorted(wbds["SpeedCat"].unique()):
        m = wbds["SpeedCat"].to_numpy() == cat
        rows.append((cat, v[m].mean(), sl[m].mean(), sl_fit[m].mean(), sl[m].std(ddof=1),
                     cadence[m].mean(), freq_fit[m].mean(), cadence[m].std(ddof=1)))
    return {
        "coefficient": float(coef), "exponent": float(expo), "n": len(v),
        "v_hat_range": (float(v_hat.min()), float(v_hat.max())),
        "speed_range": (float(v.min()), float(v.max())),
        "leg_ratio": float(np.median(leg / wbds["Height"].to_numpy(float))),
        "residual_sd_m": float(np.std(sl - sl_fit, ddof=2)),
        "residual_sd_dimless": float(np.std(sl / leg - sl_fit / leg, ddof=2)),
        "cadence_residual_sd": float(np.std(cadence - freq_fit, ddof=2)),
        "r2": float(1 - np.sum((sl - sl_fit) ** 2) / np.sum((sl - sl.mean()) ** 2)),
        "by_category": rows,
    }


def schwartz_categories(gait_dir: Path) -> list[tuple[str, float, float, float, float, float]]:
    """(category, v_hat, SL/L mean, SD, f_hat mean, SD) from Schwartz 2008, sheet ANOVA."""
    import pandas as pd

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sheet = pd.read_excel(gait_dir / SCHWARTZ_FILE, sheet_name="ANOVA", header=None)
    labels = sheet.iloc[:, 0].ffill().astype(str).str.strip()
    out = []
    for k in range(5):
        def row(name: str, k: int = k):
            block = sheet[labels == name]
            return float(block.iloc[k, 3]), float(block.iloc[k, 4]), str(block.iloc[k, 1])
        v_hat, _, cat = row("Dimensionless Speed")
        sl, sl_sd, _ = row("Dimensionless Step Length")
        f, f_sd, _ = row("Dimensionless Cadence")
        out.append((cat, v_hat, sl, sl_sd, f, f_sd))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gait-dir", type=Path, default=GAIT_DIR)
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    fit = fit_wbds(args.gait_dir)
    print(f"WBDS calibration ({fit['n']} trials): SL/L = {fit['coefficient']:.4f} "
          f"(v/sqrt(gL))^{fit['exponent']:.4f}")
    print(f"  residual SD {fit['residual_sd_m'] * 100:.2f} cm "
          f"({fit['residual_sd_dimless']:.4f} L), "
          f"R^2 {fit['r2']:.3f}, cadence residual SD {fit['cadence_residual_sd'] * 60:.1f} /min")
    print(f"  v/sqrt(gL) {fit['v_hat_range'][0]:.3f}-{fit['v_hat_range'][1]:.3f}, "
          f"speed {fit['speed_range'][0]:.2f}-{fit['speed_range'][1]:.2f} m/s, "
          f"median leg/height {fit['leg_ratio']:.3f}")
    print("  cat  speed   SL meas   SL fit   SD     cadence meas  fit   SD   [m/s, m, /min]")
    for cat, v, sl, slf, sd, c, cf, csd in fit["by_category"]:
        print(f"  {cat}   {v:.2f}    {sl:.3f}    {slf:.3f}   {sd:.3f}    "
              f"{c * 60:6.1f}  {cf * 60:6.1f}  {csd * 60:4.1f}")
    print("Schwartz et al. 2008 validation (children, overground; dimensionless):")
    print("  category    v_hat  SL/L meas   fit    z     f_hat meas   fit    z")
    c, e = fit["coefficient"], fit["exponent"]
    for cat, v_hat, sl, sl_sd, f, f_sd in schwartz_categories(args.gait_dir):
        sl_fit = c * v_hat ** e
        f_fit = v_hat / sl_fit
        print(f"  {cat:10s}  {v_hat:.3f}  {sl:.3f}±{sl_sd:.3f}  {sl_fit:.3f} "
              f"{(sl_fit - sl) / sl_sd:+.2f}"
              f"   {f:.3f}±{f_sd:.3f}  {f_fit:.3f} {(f_fit - f) / f_sd:+.2f}")
    if args.check:
        from planners import normal_mode

        ok = (abs(normal_mode.COEFFICIENT - round(c, 4)) < 1e-9
              and abs(normal_mode.EXPONENT - round(e, 4)) < 1e-9)
        print("shipped coefficients " + ("match" if ok else
              f"DIFFER: {normal_mode.COEFFICIENT}, {normal_mode.EXPONENT}"))
        return 0 if ok else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
