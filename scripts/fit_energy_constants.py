"""Fit the hand-set constants of the energy model to measured metabolic costs.

Usage: ``python scripts/fit_energy_constants.py`` (prints the fit and its validation).

Calibration (Teh & Aziz 2002, stairs, 15 cm risers): ``beta`` (J/kg per unit of Eq. 2)
from the gross cost of one step up, ``down_ratio`` from the gross cost of one step down,
each at the measured stepping rate, with the rest of Eq. 4 (alpha En + gamma Ej) as the
model computes it. Validation on other data: Bassett et al. 1997 (stairs at 70 steps/min:
the cost of a step down relative to a step up) and Minetti et al. 2002 (walking on
slopes: the cost per metre at +45 % against -45 % and at -10 % against level). The
flat-ground term c_calf / c_thigh is calibrated on WBDS (Fukuchi et al. 2018; preferred
step length over leg length at each subject's comfortable speed, ``../shared/data/gait``;
the fit is skipped without it) and validated on the spatiotemporal normals of the same
folder (adults, normal pace). The fitted set is ``planners.EnergyWeights.fitted()``, the
default of ``PlannerConfig``; the hand-set ones are ``EnergyWeights.hand_set()``, Chen &
Li's printed Eq. 2 is ``EnergyWeights.paper()``.

Oxygen to energy: 20.1 J per mL O2 (respiratory exchange ratio about 0.85).
"""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np

from planners import EnergyWeights, Leg, PlannerConfig
from planners.energy import step_energy

J_PER_ML = 20.1
MET = 3.5  # mL O2 / (kg min)
GOING = 0.28  # tread depth assumed for the stair data sets [m] (the fit moves < 3 % for 0.25..0.30)
BODY = 1.70  # body height of the modelled walker [m]

#: Teh & Aziz 2002, Med Sci Sports Exerc 34(4):695-699: 180 steps of 15 cm; VO2 of the last
#: 30 s, 33.5 (up) and 17.0 (down) mL/(kg min); 19.7 kcal at 10.2 kcal/min up, 9.0 kcal at
#: 5.2 kcal/min down (the stepping rates follow: 180 steps over those durations).
TEH_RISE = 0.15
TEH_UP = (33.5, 180 / (19.7 / 10.2))  # VO2 [mL/(kg min)], steps/min
TEH_DOWN = (17.0, 180 / (9.0 / 5.2))
#: Bassett et al. 1997, Med Sci Sports Exerc 29(9):1250-1254: 70 steps/min, gross 8.6 METs
#: up and 2.9 METs down (riser not given in the abstract; 0.17-0.20 m tried).
BASSETT = (8.6, 2.9, 70.0)
#: Minetti et al. 2002, J Appl Physiol 93:1039-1046: net cost of walking [J/(kg m)] at
#: gradient -0.45, -0.10, 0, +0.45 (level at 1.0 m/s).
MINETTI = {-0.45: 3.46, -0.10: 0.81, 0.0: 1.64, 0.45: 17.33}


def _config(weights: EnergyWeights) -> PlannerConfig:
    """Eqs. 1-4 alone (``step_model="paper"``): the constants fitted here are theirs,
    without the step-frequency term of the normal-mode step model."""
    return PlannerConfig(weights=weights, step_model="paper")


def per_step(config: PlannerConfig, leg: Leg, length: float, rise: float, rate: float):
    """Eq. 4 terms of one step [J/kg]: (alpha En + gamma Ej, beta Ev) at ``rate`` steps/min."""
    z = np.zeros(1)
    summit = z + max(rise, 0.0) + leg.ankle_height + 0.75 * config.swing_lift
    speed = length * rate / 60.0
    En, Ev, Ej, E, ok = step_energy(z, z, z + length, z + rise, summit, leg, speed, config)
    w = config.weights
    assert ok[0], "step out of the leg's reach"
    return float(w.alpha * En[0] + w.gamma * Ej[0]), float(w.beta * Ev[0]), float(E[0])


def fit_stairs(leg: Leg) -> tuple[float, float]:
    """beta and down_ratio from Teh & Aziz 2002."""
    base = _config(weights=EnergyWeights(beta=1.0, down_ratio=1.0))
    up_meas = TEH_UP[0] / TEH_UP[1] * J_PER_ML
    down_meas = TEH_DOWN[0] / TEH_DOWN[1] * J_PER_ML
    rest_up, ev_up, _ = per_step(base, leg, GOING, TEH_RISE, TEH_UP[1])
    rest_down, ev_down, _ = per_step(base, leg, GOING, -TEH_RISE, TEH_DOWN[1])
    beta = (up_meas - rest_up) / ev_up
    down_ratio = (down_meas - rest_down) / (beta * ev_down)
    print("Calibration, Teh & Aziz 2002 (15 cm risers, gross cost of one step [J/kg]):")
    print(f"  up   measured {up_meas:.2f} at {TEH_UP[1]:.0f} steps/min; model alpha En + gamma Ej"
          f" = {rest_up:.2f} -> beta = {beta:.4f} (hand-set {EnergyWeights().beta:.4f})")
    print(f"  down measured {down_meas:.2f} at {TEH_DOWN[1]:.0f} steps/min; model rest = "
          f"{rest_down:.2f} -> down_ratio = {down_ratio:.3f} (hand-set "
          f"{EnergyWeights().down_ratio:.3f})")
    return beta, down_ratio


def validate_stairs(leg: Leg, weights: EnergyWeights) -> None:
    up_mets, down_mets, rate = BASSETT
    measured = down_mets / up_mets
    print("Validation, Bassett et al. 1997 (70 steps/min, gross): step down / step up")
    for rise in (0.17, 0.20):
        for name, w in (("hand-set", EnergyWeights()), ("fitted", weights)):
            cfg = _config(weights=w)
            up = per_step(cfg, leg, GOING, rise, rate)[2]
            down = per_step(cfg, leg, GOING, -rise, rate)[2]
            print(f"  riser {rise:.2f} m, {name:<8}: model {down / up:.3f} (up {up:.2f}, down "
                  f"{down:.2f} J/kg); measured {measured:.3f} (up "
                  f"{up_mets * MET / rate * J_PER_ML:.2f}, down "
                  f"{down_mets * MET / rate * J_PER_ML:.2f} J/kg)")


def validate_slopes(leg: Leg, weights: EnergyWeights) -> None:
    print("Validation, Minetti et al. 2002 (cost per metre on slopes; 0.4 m steps, 100 /min):")
    for name, w in (("hand-set", EnergyWeights()), ("fitted", weights)):
        cfg = _config(weights=w)
        cost = {g: per_step(cfg, leg, 0.4, g * 0.4, 100.0)[2] / 0.4 for g in MINETTI}
        print(f"  {name:<8}: +45 % / -45 % model {cost[0.45] / cost[-0.45]:.2f}, measured "
              f"{MINETTI[0.45] / MINETTI[-0.45]:.2f}; -10 % / level model "
              f"{cost[-0.10] / cost[0.0]:.2f}, measured {MINETTI[-0.10] / MINETTI[0.0]:.2f}")
    print("  (the model charges every step down at least the level cost: it cannot show the "
          "measured saving of a gentle descent)")


def preferred_step(leg: Leg, weights: EnergyWeights) -> float:
    """Step length [m] of best flat-ground efficiency (Eq. 5) for ``weights``."""
    from planners import flat_efficiency

    lengths = np.linspace(0.35, 0.95, 601)
    cfg = _config(weights=weights)
    return float(lengths[np.argmax(flat_efficiency(leg, 1.34, lengths, cfg))])


def fit_flat(weights: EnergyWeights) -> EnergyWeights:
    """c_calf / c_thigh so that the flat optimum over leg length matches WBDS at the
    comfortable speed; validated on the spatiotemporal normals."""
    repo = Path(__file__).resolve().parents[1]  # ../shared next to it (or one level up)
    gait = next((p / "shared" / "data" / "gait" for p in (repo.parent, repo.parent.parent)
                 if (p / "shared" / "data" / "gait").is_dir()), repo.parent / "shared")
    wbds = gait / "wbds_treadmill_speed_steplength_cadence.csv"
    if not wbds.exists():
        print(f"(no {wbds}: c_calf / c_thigh not fitted)")
        return weights
    with wbds.open() as f:
        rows = [r for r in csv.DictReader(f) if r["SpeedCat"] == "V5"]  # comfortable speed
    ratio = np.array([float(r["StepLength"]) / float(r["Height"]) for r in rows])
    target = float(np.mean(ratio)) * BODY
    leg = Leg.from_body_height(BODY)
    scan = {c: preferred_step(leg, replace(weights, c_calf=c)) for c in (0.0, 0.1, 0.5, 1.0, 2.0)}
    fitted = weights  # the fit leaves c_calf / c_thigh free over the range that matches
    print(f"Calibration, WBDS (n = {ratio.size}, comfortable speed): step length / body height "
          f"{ratio.mean():.3f} (SD {ratio.std():.3f}) -> {target:.3f} m for a {BODY} m body")
    print("  flat optimum (Eq. 5) for c_calf / c_thigh = " + ", ".join(
        f"{c:g}: {s:.3f} m" for c, s in scan.items()))
    print("  -> any c_calf / c_thigh up to 1 puts the optimum at the measured step: it sits at "
          "a corner of Ej / L set by the key-frame geometry, so the ratio is not identifiable "
          "from preferred step lengths (kept at 0.1)")
    normals = gait / "spatiotemporal_normals_by_age_pace.txt"
    if normals.exists():
        with normals.open() as f:
            adult = [r for r in csv.reader(f, delimiter=";")
                     if r and r[3] == "Normal" and r[1].isdigit() and 20 <= int(r[1]) <= 60]
        lengths = np.array([[float(r[14]), float(r[15])] for r in adult]) / 100
        print(f"Validation, spatiotemporal normals (adults 20-60, normal pace, {len(adult)} "
              f"rows): step length {lengths[:, 0].mean():.3f}..{lengths[:, 1].mean():.3f} m; "
              f"model optimum for 1.62-1.78 m bodies "
              f"{preferred_step(Leg.from_body_height(1.62), fitted):.3f}.."
              f"{preferred_step(Leg.from_body_height(1.78), fitted):.3f} m")
    return fitted


def main() -> None:
    leg = Leg.from_body_height(BODY)
    beta, down_ratio = fit_stairs(leg)
    weights = EnergyWeights(beta=round(beta, 4), down_ratio=round(down_ratio, 3))
    validate_stairs(leg, weights)
    validate_slopes(leg, weights)
    weights = fit_flat(weights)
    print(f"\nfitted: {weights}")
    print(f"shipped EnergyWeights.fitted(): {EnergyWeights.fitted()}")


if __name__ == "__main__":
    main()
