"""Double support per step in a run's poses against Chen & Li's Table 1 (§5.3).

For every step of every walker of a ``crowdwalk run`` folder with poses: the fraction of
the step (heel strike to heel strike, ``footsteps.csv``) during which both feet are in
contact (``poses.sqlite``), and Table 1's T2 for that step's rise and the walker's leg
(``planners.timing.phase_fractions``: the double-support phase). Printed by kind of step
(level |h| < 2 cm, up, down); the Animator takes this timing from its elevation-angle
datasets (Bovi et al. 2011, measured), see docs/architecture.md "MetaGait in the crowd".

    python3 scripts/phase_timing_report.py RUN_DIR
"""

from __future__ import annotations

import sys

import numpy as np

from crowdwalk.gait_report import load_tracks
from crowdwalk.record import open_run
from planners import normal_mode
from planners.timing import phase_fractions


def main(run_dir: str) -> None:
    run = open_run(run_dir)
    poses = run.poses()
    tracks = load_tracks(poses)
    poses.close()
    steps = run.footsteps()
    rows = []  # (rise, measured double support fraction, Table 1 T2)
    for agent, track in tracks.items():
        mine = np.flatnonzero(steps.agent == agent)
        ends = steps.time[mine]
        leg = float(normal_mode.leg_length_from_height(track.body_height))
        both = track.contact.all(axis=1)
        for k in range(1, mine.size):
            t0, t1 = ends[k - 1], ends[k]
            inside = (track.time >= t0) & (track.time < t1)
            if t1 - t0 <= 0 or inside.sum() < 6 or t0 < track.time[0]:
                continue
            h = float(steps.step_height[mine[k]])
            rows.append((h, float(both[inside].mean()),
                         float(phase_fractions(h, leg)[1])))
    rows = np.array(rows)
    print(f"{'steps':<8}{'n':>5}{'rise [m]':>10}{'double support (run)':>22}"
          f"{'Table 1 T2':>12}")
    for name, pick in (("level", np.abs(rows[:, 0]) < 0.02), ("up", rows[:, 0] >= 0.02),
                       ("down", rows[:, 0] <= -0.02)):
        if pick.any():
            r = rows[pick]
            print(f"{name:<8}{pick.sum():>5}{np.median(r[:, 0]):>+10.3f}"
                  f"{np.median(r[:, 1]):>22.3f}{np.median(r[:, 2]):>12.3f}")


if __name__ == "__main__":
    main(sys.argv[1])
