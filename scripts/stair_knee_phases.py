"""Stair knee flexion of a run's walkers by phase, against Bovi 2011 and the stair datasets.

For every walker of a ``crowdwalk run`` folder with poses: the mean left-leg knee curve
(thigh − shank, :func:`crowdwalk.gait_report.sagittal_angles`) of its stairs-up and
stairs-down cycles (:func:`crowdwalk.gait_report.gait_figures`' cycle kinds), printed
every 6 % of the cycle beside Bovi's adult mean knee (``joint_references.json``) and the
shipped stair dataset's own knee (thigh − shank elevation, dataset time), and the RMS
differences run − Bovi, run − dataset and dataset − Bovi over loading (0–15 %), stance
(15–60 %), push-off and foot-off (60–75 %) and swing (75–100 %). It separates what the
data give from what the Animator adds (docs/architecture.md, "Stair datasets closed over
the swing").

    python scripts/stair_knee_phases.py RUN_DIR
"""

from __future__ import annotations

import sys

import numpy as np

from crowdwalk import gait_report as gr
from crowdwalk.gait.datasets import dataset_by_name
from crowdwalk.record import open_run

PHASES = ((0.0, 0.15, "loading"), (0.15, 0.6, "stance"), (0.6, 0.75, "push/foot-off"),
          (0.75, 1.01, "swing"))


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x ** 2)))


def main(run_dir: str) -> None:
    run = open_run(run_dir)
    poses = run.poses()
    if poses is None:
        raise SystemExit(f"{run_dir}: no poses stored")
    tracks = gr.load_tracks(poses)
    poses.close()
    steps = run.footsteps()
    t = np.linspace(0.0, 1.0, gr.SAMPLES)
    for agent, track in sorted(tracks.items()):
        strikes = np.array([a for a, _ in gr.stance_runs(track.contact[:, 0])][1:], dtype=int)
        if strikes.size < 2:
            continue
        kinds = np.array(gr._cycle_kinds(track.time[strikes], steps.of_agent(agent)),
                         dtype=object)
        curves = gr.cycle_curves(gr.sagittal_angles(track, 0), strikes)
        for kind in (gr.STAIRS_UP, gr.STAIRS_DOWN):
            idx = np.flatnonzero(kinds == kind)
            if not idx.size:
                continue
            knee = curves[idx, :, 1].mean(axis=0)
            ref = np.asarray(gr.references()["bovi"][kind]["knee"]["mean"])
            d = dataset_by_name(kind).angles
            dk = np.rad2deg(d[:, 2] - d[:, 1])
            grid = np.arange(d.shape[0] + 1) / d.shape[0]
            data = np.interp(t, grid, np.append(dk, dk[0]))
            print(f"agent {agent} {kind}: {idx.size} cycles")
            for name, row in (("t", t), ("run", knee), ("Bovi", ref), ("data", data)):
                print(f"  {name:5s}" + " ".join(f"{x:6.2f}" if name == "t" else f"{x:6.1f}"
                                                for x in row[::3]))
            for lo, hi, name in PHASES:
                m = (t >= lo) & (t < hi)
                print(f"  {name:14s} RMS run-Bovi {_rms((knee - ref)[m]):5.1f}  run-data "
                      f"{_rms((knee - data)[m]):5.1f}  data-Bovi {_rms((data - ref)[m]):5.1f}")
            s = t <= gr.STAIR_STANCE
            print(f"  whole cycle    RMS run-Bovi {_rms(knee - ref):5.1f}  data-Bovi "
                  f"{_rms(data - ref):5.1f}; 0-60 %: run {_rms((knee - ref)[s]):.1f}, data "
                  f"{_rms((data - ref)[s]):.1f}; run peak {knee.max():.0f}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit(__doc__)
    main(sys.argv[1])
