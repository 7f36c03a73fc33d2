"""Derive the Ko & Badler prototype walk W̄(S*, sl*) from Winter's normal-walk markers.

Writes ``crowdwalk/data/ko_badler_prototype.json`` and prints the measurement and the
model residuals. Run from anywhere::

    python scripts/derive_ko_badler_prototype.py [--gait-dir DIR] [--out FILE] [--check]

``--check`` re-derives in memory and compares with the shipped file instead of writing.
See ``crowdwalk/data/README.md`` ("ko_badler_prototype.json") for what is derived and how.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

# ../shared next to the checkout (a worktree under /work/wt/<name> has it two levels up).
GAIT_DIR = next((d for d in (REPO / ".." / "shared" / "data" / "gait",
                             REPO / ".." / ".." / "shared" / "data" / "gait") if d.is_dir()),
                REPO / ".." / "shared" / "data" / "gait")  # fmt: skip
OUT = REPO / "crowdwalk" / "data" / "ko_badler_prototype.json"
WINTER_FILE = "winter_normal_walk_smoothed_markers_wn35b.txt"
BOVI_FILE = "bovi2011_multitask_reference_mmc3.xls"
WINTER = (
    "Winter DA (2009). Biomechanics and Motor Control of Human Movement, 4th ed., Wiley, "
    "Appendix A (one normal walking trial, right side, sagittal markers; the smoothed "
    "copy demotu/BMC data/wn35b.txt, commit 1f1c1ab4e37c84bb3bd6de4ca352db6e0a057dc8)."
)
BOVI = (
    "Bovi G, Rabuffetti M, Mazzoleni P, Ferrarin M (2011). A multiple-task gait analysis "
    "approach: kinematic, kinetic and EMG reference data for healthy young and adult "
    "subjects. Gait & Posture 33(1):6-13, supplementary mmc3, adult means, tasks XS, S, "
    "Natural, M, L."
)
MARKERS = ("shoulder", "hip", "knee", "fibula", "ankle", "heel", "ball", "toe")
# wn35b columns: Shoulder, Hip, Tib.Epic. (= Table A.1 KNEE, lateral femoral condyle),
# Knee (= Table A.1 FIBULA head), Ankle, Heel, Ball, Toes; values in metres (SOURCES.md).
FLAT_BAND = 0.005  # heel and ball markers within this of their stance minima: foot flat [m]
LIFT = 0.005  # ball / toe marker this far above its stance minimum: meta-off / toe-off [m]
LEVEL_TASKS = ("XS", "S", "Natural", "M", "L")


def read_markers(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Times (F,) [s] and marker positions (F, 2) [m] (x forward, y up) by name."""
    d = np.loadtxt(path, skiprows=3)
    return d[:, 0], {m: d[:, 1 + 2 * i: 3 + 2 * i] for i, m in enumerate(MARKERS)}


def extremum(v: np.ndarray, lo: int, hi: int, find_max: bool) -> float:
    """Sub-frame index of the extremum of v[lo:hi] (parabola through the 3 best frames)."""
    seg = v[lo:hi] * (-1.0 if find_max else 1.0)
    k = int(np.argmin(seg)) + lo
    a, b, c = (v[k - 1: k + 2] * (-1.0 if find_max else 1.0))
    den = a - 2 * b + c
    return k + (0.5 * (a - c) / den if den > 0 else 0.0)


def crossing(v: np.ndarray, level: float, start: float, rising: bool) -> float:
    """First sub-frame index after ``start`` where v crosses ``level`` (linear)."""
    s = (v - level) * (1.0 if rising else -1.0)
    for k in range(int(np.ceil(start)), len(v) - 1):
        if s[k] < 0 <= s[k + 1]:
            return k + (-s[k]) / (s[k + 1] - s[k])
    raise ValueError(f"no crossing of {level} after frame {start}")


def at(v: np.ndarray, frame: float) -> np.ndarray:
    """Linear interpolation of per-frame values (F,) or (F, d) at a sub-frame index."""
    k = min(int(np.floor(frame)), len(v) - 2)
    w = frame - k
    return (1 - w) * v[k] + w * v[k + 1]


def pitch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle of the vector a→b from the forward horizontal [rad]."""
    return np.arctan2(b[..., 1] - a[..., 1], b[..., 0] - a[..., 0])


def segment(times: np.ndarray, values: np.ndarray, first: float, last: float,
            to_step) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Samples over sub-frame [first, last]: the events themselves and the frames between."""
    inner = np.arange(int(np.floor(first)) + 1, int(np.ceil(last)))
    frames = np.concatenate([[first], inner, [last]])
    vals = np.array([at(values, f) for f in frames])
    return to_step(frames), vals


def calibrate_alpha(gait_dir: Path) -> tuple[np.ndarray, dict]:
    """α1…α3 from Bovi's five level speeds (least-squares slopes vs step length / ll)."""
    sys.path.insert(0, str(REPO / "scripts"))
    import derive_gait_data as dg

    from crowdwalk.body import PROPORTIONS

    path = gait_dir / BOVI_FILE
    curves, params = dg.read_bovi_curves(path), dg.read_bovi_parameters(path)
    t = np.linspace(0.0, 1.0, 101)
    rows = []
    for task in LEVEL_TASKS:
        c, p = curves[task], params[task]
        cfo = p["Controlateral Foot Off [% cycle]"] / 100
        cfs = p["Controlateral Foot Strike [% cycle]"] / 100
        fo = p["Ipsilateral Foot Off [% cycle]"] / 100
        foot = c["Foot Flex/Extension"]
        foot = foot - np.median(foot[(t >= cfo) & (t <= 0.5 * (cfo + cfs))])
        height = p["Stride length [m]"] / (p["Stride length / BH [%BH]"] / 100)
        ll = (PROPORTIONS["thigh"] + PROPORTIONS["shank"]) * height
        rows.append((0.5 * p["Stride length [m]"] / ll,
                     np.pi - np.radians(c["Knee Flex/Extension"][0]),  # interior knee
                     np.radians(foot[0]), -np.radians(np.interp(fo, t, foot))))  # fmt: skip
    r = np.array(rows)
    slopes = [np.polyfit(r[:, 0], r[:, k], 1)[0] for k in (1, 2, 3)]
    alpha1 = float(np.clip(-slopes[0], 0.0, 0.3))  # Eq. 5: α1 in [0, 0.3] (Inman)
    info = {"step_over_leg": r[:, 0].round(4).tolist(), "raw_slopes": np.round(slopes, 4).tolist()}
    # No toe (meta) angle is measured at several speeds: α4 is taken equal to α3.
    return np.array([alpha1, slopes[1], slopes[2], slopes[2]]), info


def derive(gait_dir: Path) -> tuple[dict, dict]:
    """The prototype's JSON dict and a report of measurements and residuals."""
    from crowdwalk.gait.ko_badler.generalize import (
        ankle_at_heel_strike,
        ankle_at_toe_off,
        hip_height_at_heel_strike,
    )
    from crowdwalk.gait.ko_badler.walkdata import (
        BodyCondition,
        GaitLaw,
        TimedSequence,
        WalkData,
        walk_to_dict,
    )

    times, p = read_markers(gait_dir / WINTER_FILE)
    dt = float(np.mean(np.diff(times)))
    heel, ball, toe, ankle, hip, knee = (p[k] for k in ("heel", "ball", "toe", "ankle", "hip",
                                                         "knee"))  # fmt: skip
    n = len(times)
    # Events of the right foot. Heel strike: heel-marker height minimum (as the BMC notes
    # for this trial); toe-off: the toe marker's most posterior position relative to the
    # hip (Zeni, Richards & Higginson 2008, Gait Posture 27:710, with the hip marker for
    # the pelvis).
    swing = np.flatnonzero(heel[:, 1] > 0.15)
    mid_swing = [int(swing[swing < 50].mean()), int(swing[swing > 50].mean())]
    hs1 = extremum(heel[:, 1], mid_swing[0], mid_swing[1], find_max=False)
    hs2 = extremum(heel[:, 1], mid_swing[1], n - 1, find_max=False)
    zeni_to = extremum(toe[:, 0] - hip[:, 0], int(hs1) + 10, int(hs2), find_max=False)
    # Foot flat: heel and ball markers both within FLAT_BAND of their stance minima.
    stance = np.arange(int(np.ceil(hs1)), int(zeni_to))
    flat = stance[(heel[stance, 1] < heel[stance, 1].min() + FLAT_BAND)
                  & (ball[stance, 1] < ball[stance, 1].min() + FLAT_BAND)]  # fmt: skip
    sole_raw = pitch(heel, ball)  # heel→ball line [rad]
    flat_pitch = float(np.median(sole_raw[flat]))
    foot_angle = sole_raw - flat_pitch  # toe up positive, flat 0
    fgm1 = crossing(foot_angle, 0.0, hs1, rising=False)
    fgm2 = crossing(foot_angle, 0.0, hs2, rising=False)
    mom = crossing(ball[:, 1], ball[stance, 1].min() + LIFT, flat[-1], rising=True)
    to = crossing(toe[:, 1], toe[flat[-1]:int(zeni_to), 1].min() + LIFT, mom, rising=True)
    meta_raw = np.arctan2(ball[:, 1] - toe[:, 1], toe[:, 0] - ball[:, 0])
    meta_angle = meta_raw - at(meta_raw, mom)  # 0 at MOM by definition
    # Foot geometry (rigid, mean over the flat frames) in the sole frame heel→ball.
    u = np.array([np.cos(flat_pitch), np.sin(flat_pitch)])
    nrm = np.array([-u[1], u[0]])
    rel = ankle[flat] - heel[flat]
    h_n = float(np.mean(rel @ u))
    a_n = float(np.mean(rel @ nrm))
    b_n = float(np.mean(np.linalg.norm(ball[flat] - heel[flat], axis=1))) - h_n
    b_t = float(np.mean(np.linalg.norm(toe[flat] - ball[flat], axis=1)))
    # Thigh and shin: marker distances at the two heel strikes, where Eq. 7 uses them
    # (skin markers: hip→knee runs 0.31–0.33 m, knee→ankle 0.41–0.43 m over the trial).
    thigh = float(np.mean([np.linalg.norm(at(hip - knee, f)) for f in (hs1, hs2)]))
    shin = float(np.mean([np.linalg.norm(at(knee - ankle, f)) for f in (hs1, hs2)]))
    body = BodyCondition(thigh=thigh, shin=shin, ankle_height=a_n, heel=h_n, ball=b_n, toes=b_t)
    # Floor: the sole line below the ankle (point N) in the flat frames.
    floor = float(np.mean((heel[flat] + np.outer(rel @ u, u))[:, 1]))
    n1, n2 = float(at(ankle[:, 0], fgm1)), float(at(ankle[:, 0], fgm2))
    sl = 0.5 * (n2 - n1)  # step symmetry: one step is half the stride
    step_time = 0.5 * (hs2 - hs1)  # [frames]

    def stance_time(f):
        return (np.asarray(f) - hs1) / step_time

    def swing_time(f):
        return (np.asarray(f) - (hs2 - step_time)) / step_time

    up = np.array([0.0, floor])
    t_h, v_h = segment(times, hip - up - [n1, 0.0], hs1, hs1 + step_time, stance_time)
    t_f1, v_f1 = segment(times, foot_angle, hs1, fgm1, stance_time)
    t_f2, v_f2 = segment(times, foot_angle, fgm1, to, stance_time)
    t_m, v_m = segment(times, meta_angle, mom, to, stance_time)
    t_f3, v_f3 = segment(times, foot_angle, to, hs2, swing_time)
    t_a, v_a = segment(times, ankle - up - [n1 + sl, 0.0], to, hs2, swing_time)

    def knee_interior(f):
        th, sh = at(hip, f) - at(knee, f), at(ankle, f) - at(knee, f)
        return float(np.arccos(th @ sh / np.linalg.norm(th) / np.linalg.norm(sh)))

    mu_star = np.array([0.5 * (knee_interior(hs1) + knee_interior(hs2)),
                        0.5 * (at(foot_angle, hs1) + at(foot_angle, hs2)),
                        -at(foot_angle, to), at(meta_angle, to)])  # fmt: skip
    alpha, calib = calibrate_alpha(gait_dir)
    law = GaitLaw(alpha=alpha, mu_star=mu_star, step_ratio=sl / body.leg_length)

    # Make the measured walk consistent with the model, with the paper's own remaps:
    # F1 to the mean heel-strike angle (Eq. 20), F3 to it at HSM⁺ (Eq. 23), the hip to the
    # §2.1 heel-strike height at both ends (Eq. 14), the swing ankle to Lemma 1's toe-off
    # and landing positions (Eqs. 29–30). The residuals are reported.
    b1 = ankle_at_toe_off(law, body, sl, sl)
    b2 = ankle_at_heel_strike(law, body, sl)
    y_hs = float(hip_height_at_heel_strike(law, body, sl))
    f1 = v_f1 * mu_star[1] / v_f1[0]
    tp = (t_f3 - t_f3[0]) / (1 - t_f3[0])
    f3 = v_f3 + (1 - tp) * (-mu_star[2] - v_f3[0]) + tp * (mu_star[1] - v_f3[-1])
    hy = v_h[:, 1] + (1 - t_h) * (y_hs - v_h[0, 1]) + t_h * (y_hs - v_h[-1, 1])
    hip_seq = np.stack([v_h[:, 0], hy], axis=1)
    tpa = (t_a - t_a[0]) / (1 - t_a[0])
    ax = b1[0] + (b2[0] - b1[0]) / (v_a[-1, 0] - v_a[0, 0]) * (v_a[:, 0] - v_a[0, 0])
    ay = v_a[:, 1] + (1 - tpa) * (b1[1] - v_a[0, 1]) + tpa * (b2[1] - v_a[-1, 1])
    walk = WalkData(
        body=body, step_length=sl, previous_step_length=sl, law=law,
        hip=TimedSequence(t_h, hip_seq), foot1=TimedSequence(t_f1, f1),
        foot2=TimedSequence(t_f2, v_f2), foot3=TimedSequence(t_f3, f3),
        meta=TimedSequence(t_m, v_m), ankle=TimedSequence(t_a, np.stack([ax, ay], axis=1)),
    )  # fmt: skip
    # Lemma 1 as printed (no θb) against the corrected form, for the measured toe-off ankle.
    mu3, mu4 = mu_star[2], mu_star[3]
    printed = np.array([b_n + b_t - b_t * np.cos(mu4) - body.ankle_ball * np.cos(mu3) - sl,
                        b_t * np.sin(mu4) + body.ankle_ball * np.sin(mu3)])  # fmt: skip
    mm = 1000.0
    report = {
        "hip_at_HSM_m": [v_h[0].round(4).tolist(), v_h[-1].round(4).tolist()],
        "zeni_toe_off_frame": zeni_to,
        "events_frame": {"HSM1": hs1, "FGM1": fgm1, "MOM": mom, "TOM": to, "HSM2": hs2,
                         "FGM2": fgm2},
        "events_step_time": {"FGM": float(t_f1[-1]), "MOM": float(t_m[0]),
                             "TOM_stance": float(t_f2[-1]), "TOM_swing": float(t_f3[0])},
        "step_length_m": sl, "step_time_s": step_time * dt,
        "cadence_steps_per_min": 60.0 / (step_time * dt),
        "speed_m_per_s": sl / (step_time * dt),
        "body_m": {k: float(getattr(body, k)) for k in ("thigh", "shin", "ankle_height",
                                                        "heel", "ball", "toes")},
        "mu_star_deg": np.degrees(mu_star).round(2).tolist(),
        "alpha": alpha.round(4).tolist(), "alpha_calibration": calib,
        "residual_heel_strike_angles_deg": float(np.degrees(at(foot_angle, hs2)
                                                            - at(foot_angle, hs1))),
        "residual_hip_height_at_HSM_mm": [(v_h[0, 1] - y_hs) * mm, (v_h[-1, 1] - y_hs) * mm],
        "residual_toe_off_ankle_mm": {"corrected_eq32_33": ((v_a[0] - b1) * mm).round(1).tolist(),
                                      "as_printed": ((v_a[0] - printed) * mm).round(1).tolist()},
        "residual_landing_ankle_mm": ((v_a[-1] - b2) * mm).round(1).tolist(),
    }  # fmt: skip
    out = walk_to_dict(walk)
    out["source"] = WINTER
    out["calibration"] = BOVI + " alpha1..alpha3 are least-squares slopes; alpha4 = alpha3."
    out["events"] = {k: round(v, 6) for k, v in report["events_step_time"].items()}
    return out, report


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gait-dir", type=Path, default=GAIT_DIR)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--check", action="store_true", help="compare with the shipped file")
    args = ap.parse_args(argv)
    data, report = derive(args.gait_dir)
    print(json.dumps(report, indent=1, default=float))
    if args.check:
        shipped = json.loads(args.out.read_text(encoding="utf-8"))
        same = _close(shipped, data)
        print("check:", "identical to the shipped file" if same else "DIFFERS from shipped")
        return 0 if same else 1
    text = json.dumps(data, indent=None, separators=(",", ":")) + "\n"
    args.out.write_text(text, encoding="utf-8")
    print(f"wrote {args.out}")
    return 0


def _close(a, b) -> bool:
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(_close, a, b))
    if isinstance(a, float) or isinstance(b, float):
        return abs(float(a) - float(b)) <= 1e-6
    return a == b


if __name__ == "__main__":
    raise SystemExit(main())
