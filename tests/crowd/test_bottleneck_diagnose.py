"""scripts/bottleneck_diagnose.py's measures on made-up trajectories: one file against a
zipper (consecutive walkers on alternating sides), facing against walking direction."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from crowdwalk.record import Trajectories

_SPEC = importlib.util.spec_from_file_location(
    "bottleneck_diagnose", Path(__file__).parents[2] / "scripts" / "bottleneck_diagnose.py")
diagnose_mod = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(diagnose_mod)


def _walkers(offsets, gap=0.8, speed=1.0, fps=10.0, yaw=0.0) -> Trajectories:
    """Walkers along x from 6 to 11.05 m at ``speed``, one every ``gap`` s, walker i at
    y = 5 + offsets[i], facing ``yaw`` [rad] off the walking direction."""
    rows = []
    for i, dy in enumerate(offsets):
        t0 = gap * i
        for f in range(int(round(t0 * fps)), int(round((t0 + 5.05 / speed) * fps)) + 1):
            rows.append((f, i, 6.0 + speed * (f / fps - t0), 5.0 + dy))
    rows.sort()
    a = np.array(rows)
    n = len(rows)
    return Trajectories(frame=a[:, 0].astype(int), id=a[:, 1].astype(int), x=a[:, 2],
                        y=a[:, 3], z=np.zeros(n), ori_x=np.full(n, np.cos(yaw)),
                        ori_y=np.full(n, np.sin(yaw)), fps=fps)


def test_one_file_and_zipper_told_apart():
    one = diagnose_mod.diagnose(_walkers([0.0] * 20))
    zip_ = diagnose_mod.diagnose(_walkers([0.2 * (-1) ** i for i in range(20)], gap=0.5))
    assert one["dy_median"] < 0.01 and one["staggered_share"] == 0.0
    assert zip_["dy_median"] > 0.35 and zip_["staggered_share"] == 1.0
    assert abs(one["exit_gap_median"] - 0.8) < 0.051 and abs(zip_["exit_gap_median"] - 0.5) < 0.051
    # where they enter: one file in the first bin, the zipper's 0.4 m apart in the last
    assert one["entry_dy_median"] < 0.01 and one["entry_gap_by_dy"][">=0.3"][0] == 0
    assert abs(one["entry_gap_by_dy"]["<0.1"][1] - 0.8) < 0.051
    assert zip_["entry_dy_median"] > 0.35 and zip_["entry_gap_by_dy"]["<0.1"][0] == 0
    assert abs(zip_["entry_gap_by_dy"][">=0.3"][1] - 0.5) < 0.051
    assert abs(one["flow"] - 1.25) < 0.05 and abs(zip_["flow"] - 2.0) < 0.1
    assert one["in_front_standing_share"] == 0.0


def test_twist_is_facing_against_walking_direction():
    assert diagnose_mod.diagnose(_walkers([0.0] * 20))["twist_median_deg"] < 0.5
    turned = diagnose_mod.diagnose(_walkers([0.0] * 20, yaw=np.deg2rad(60.0)))
    assert abs(turned["twist_median_deg"] - 60.0) < 0.5
