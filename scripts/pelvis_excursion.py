"""Vertical hip excursion of runs against the measured trials, split into its parts.

Issue 11's "vertical pelvis excursion" (gait-report: the HumanoidRoot, the mid-hip, peak
to peak over a level stride). This script asks where the figure comes from and whether
measured people at the same body, speed and step show more. For each run folder (a lone
walker; ``crowdwalk run`` then this) it prints, medians over the level strides:

- mid-hip (HumanoidRoot) peak to peak over the stride [cm] (the gait-report figure);
- one hip joint (left) over the stride and over 0-50 % (heel strike to the other heel
  strike) [cm]: what a single trochanter marker sees;
- that hip's rise from heel strike to its stance peak, and its parts: hip - ankle height
  (thigh and shank elevations) and the ankle's own height (the foot's roll) [cm];
- thigh / shank elevation [deg] at heel strike and at 20 % of the stride.

and the same for the two measured trials in ``../shared/data/gait`` (markers low-passed
at 6 Hz, 2nd-order zero-lag Butterworth):

- Winter's Table A1 trial (2-D, right side; 1.56 m, 1.41 m/s, 0.707 m steps): the
  trochanter marker, and the hip rebuilt from the ankle marker with the trial's *mean*
  thigh and shank lengths and its measured elevations ("rigid"; the markers' thigh and
  shank lengths vary by up to 1.4 cm over the stance, which a skeleton cannot);
- BMClab ``walk1`` (3-D, 1.18 m/s): the mid-trochanter point and the mid-PSIS (sacrum).

Usage::

    python scripts/pelvis_excursion.py RUN [RUN ...]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.signal import butter, filtfilt

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "gait"
WINTER = DATA / "winter_tableA1_raw_markers.txt"
BMCLAB = DATA / "bmclab_walk1_markers.trc"
CUTOFF = 6.0  # [Hz], low-pass of the marker trajectories
COLUMNS = ("mid-hip", "hip/stride", "hip/0-50%", "hip rise", "hip-ankle", "ankle",
           "thigh@0/20%", "shank@0/20%")


def _lowpass(x: np.ndarray, rate: float) -> np.ndarray:
    b, a = butter(2, CUTOFF / (rate / 2.0))
    return filtfilt(b, a, x, axis=0)


def _elev(proximal: np.ndarray, distal: np.ndarray) -> np.ndarray:
    """Sagittal elevation [deg] (F,) of proximal->distal (x fwd, last axis up), + anterior."""
    v = distal - proximal
    return np.degrees(np.arctan2(v[:, 0], -v[:, -1]))


def _parts(hip_z: np.ndarray, ankle_z: np.ndarray, thigh: np.ndarray, shank: np.ndarray,
           a: int, b: int) -> list[float]:
    """Single-hip figures of one stride [a, b] (frame indices of two heel strikes): peak
    to peak over the stride and over 0-50 %, the rise from heel strike to the stance
    peak and its hip - ankle and ankle parts [cm]; thigh at 0 and 20 %, shank at 0 and
    20 % [deg]. ``hip_z``, ``ankle_z`` (F,) [m]; ``thigh``, ``shank`` (F,) [deg]."""
    half = a + int(round(0.5 * (b - a)))
    at20 = a + int(round(0.2 * (b - a)))
    stance = slice(a, half + 1)
    peak = a + int(np.argmax(hip_z[stance]))
    return [100 * np.ptp(hip_z[a:b + 1]), 100 * np.ptp(hip_z[stance]),
            100 * (hip_z[peak] - hip_z[a]),
            100 * ((hip_z - ankle_z)[peak] - (hip_z - ankle_z)[a]),
            100 * (ankle_z[peak] - ankle_z[a]), thigh[a], thigh[at20], shank[a], shank[at20]]


def _speed(x: np.ndarray, time: np.ndarray) -> float:
    """Mean forward speed [m/s] of a trunk marker's x (F,) over ``time`` (F,) [s]."""
    return float(np.polyfit(time, x, 1)[0])


def _heel_strikes(heel_x: np.ndarray, time: np.ndarray, speed: float) -> np.ndarray:
    """Frames where the heel marker's forward speed falls below 30 % of the walking
    speed (the same rule for both trials)."""
    slow = np.gradient(heel_x, time) < 0.3 * speed
    return np.flatnonzero(slow[1:] & ~slow[:-1]) + 1


def winter() -> dict[str, list[float]]:
    """Winter Table A1 (right side): marker trochanter and rigid-segment hip figures."""
    raw = np.loadtxt(WINTER, skiprows=2)
    rate = 1.0 / float(np.diff(raw[:, 1]).mean())
    m = _lowpass(raw[:, 2:], rate) / 100.0  # cm -> m
    hip, knee, ankle, heel = (m[:, 2 * i:2 * i + 2] for i in (1, 2, 4, 5))
    a, b = _heel_strikes(heel[:, 0], raw[:, 1], _speed(m[:, 0], raw[:, 1]))[:2]
    thigh, shank = _elev(hip, knee), _elev(knee, ankle)
    lt = np.linalg.norm(knee - hip, axis=1).mean()
    ls = np.linalg.norm(ankle - knee, axis=1).mean()
    rigid = ankle[:, 1] + lt * np.cos(np.radians(thigh)) + ls * np.cos(np.radians(shank))
    nan = float("nan")
    rigid_parts = _parts(rigid, ankle[:, 1], thigh, shank, a, b)
    rigid_parts[0] = nan  # in swing the hip does not stand on this leg
    return {"Winter A1, trochanter marker": [nan, *_parts(hip[:, 1], ankle[:, 1], thigh,
                                                          shank, a, b)],
            "Winter A1, rigid segments": [nan, *rigid_parts]}


def bmclab() -> dict[str, list[float]]:
    """BMClab walk1: mid-trochanter and mid-PSIS peak to peak over the right strides."""
    raw = np.loadtxt(BMCLAB, skiprows=5)
    names = ("R.ASIS L.ASIS R.PSIS L.PSIS L.Iliac R.Iliac R.GTR R.Knee R.HF R.TT R.Ankle "
             "R.Heel").split()
    rate = 1.0 / float(np.diff(raw[:, 1]).mean())
    m = {n: _lowpass(raw[:, 2 + 3 * i:5 + 3 * i], rate)[:, [0, 1]] / 1000.0
         for i, n in enumerate(names)}  # (x fwd, y up) [m]
    l_gtr = _lowpass(raw[:, 2 + 3 * 14:5 + 3 * 14], rate)[:, [0, 1]] / 1000.0
    strikes = _heel_strikes(m["R.Heel"][:, 0], raw[:, 1],
                            _speed(m["R.PSIS"][:, 0], raw[:, 1]))
    mid_gtr = 0.5 * (m["R.GTR"][:, 1] + l_gtr[:, 1])
    sacrum = 0.5 * (m["R.PSIS"][:, 1] + m["L.PSIS"][:, 1])
    nan = float("nan")
    out = {}
    for label, z in (("BMClab walk1, mid-trochanter", mid_gtr),
                     ("BMClab walk1, mid-PSIS (sacrum)", sacrum)):
        out[label] = [float(np.median([100 * np.ptp(z[a:b + 1])
                                       for a, b in zip(strikes[:-1], strikes[1:],
                                                       strict=True)]))] + [nan] * 9
    return out


def run(run_dir: str) -> list[float]:
    """The run's first walker: the figures above, medians over its level strides."""
    from crowdwalk.body import LEG_JOINTS
    from crowdwalk.gait_report import _elevation, _forward, load_tracks, stance_runs
    from crowdwalk.record import open_run

    poses = open_run(run_dir).poses()
    track = load_tracks(poses)[0]
    poses.close()
    p = track.positions
    strikes = np.array([a for a, _ in stance_runs(track.contact[:, 0])][1:], int)[1:-1]
    fwd = _forward(p)
    hip, knee, ankle = (p[:, LEG_JOINTS[0, j]] for j in range(3))
    thigh = np.degrees(_elevation(knee - hip, fwd))
    shank = np.degrees(_elevation(ankle - knee, fwd))
    rows = [[100 * np.ptp(p[a:b + 1, 0, 2]),
             *_parts(hip[:, 2], ankle[:, 2], thigh, shank, a, b)]
            for a, b in zip(strikes[:-1], strikes[1:], strict=True)]
    return np.median(np.array(rows), axis=0).tolist()


def main(argv: list[str]) -> int:
    if not (WINTER.exists() and BMCLAB.exists()):
        print(f"{DATA}: the shared gait data are needed")
        return 1
    rows = {**winter(), **bmclab(), **{d: run(d) for d in argv}}
    width = max(len(k) for k in rows) + 2
    print("".ljust(width) + "  ".join(c.rjust(11) for c in COLUMNS) + "   [cm; deg]")
    for label, v in rows.items():
        cells = [f"{x:11.2f}" for x in v[:6]]
        cells += [f"{v[6]:5.1f}/{v[7]:5.1f}", f"{v[8]:5.1f}/{v[9]:5.1f}"]
        print(label.ljust(width) + "  ".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
