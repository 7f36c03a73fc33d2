"""Speeds along the 3-D path: PedPy's horizontal speeds plus the height over the same
window, from what `crowdwalk run` wrote and `crowdwalk analyse` reads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from crowdwalk.cli import app
from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.record import open_run

pytest.importorskip("pedpy")
from crowdwalk.speeds3d import _window, walking_speeds  # noqa: E402

SCENARIO = Path(__file__).parents[1] / "scenarios" / "stairs_up_down.yaml"


@pytest.fixture(scope="module")
def stairs_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("stairs")
    run_scenario(SCENARIO, out, overrides=RunOverrides(poses=False, duration=16.0))
    return out


def test_pedpy_window_and_height(stairs_run):
    s = walking_speeds(stairs_run)
    rows = open_run(stairs_run).trajectories()
    order = np.lexsort((rows.frame, rows.id))
    x, y, z = rows.x[order], rows.y[order], rows.z[order]
    step = max(1, int(round(0.5 * rows.fps)))  # a 1 s window
    lo, hi = _window(rows.frame[order], rows.id[order], step)
    dt = (rows.frame[order][hi] - rows.frame[order][lo]) / rows.fps
    ok = np.isfinite(s.speed_xy) & (dt > 0)
    assert ok.mean() > 0.95
    # the horizontal part over our window is PedPy's speed: the windows are the same
    np.testing.assert_allclose(np.hypot(x[hi] - x[lo], y[hi] - y[lo])[ok] / dt[ok],
                               s.speed_xy[ok], rtol=1e-6, atol=1e-9)
    # ... and the 3-D speed is the displacement in space over that window
    np.testing.assert_allclose(
        np.sqrt((x[hi] - x[lo]) ** 2 + (y[hi] - y[lo]) ** 2 + (z[hi] - z[lo]) ** 2)[ok] / dt[ok],
        s.speed_3d[ok], rtol=1e-6, atol=1e-9)
    on = s.sloped & ok
    assert on.sum() >= 10  # the walker reached the flight (0.17 / 0.30 m risers)
    grade = np.abs(s.speed_z[on]) / s.speed_xy[on]
    assert 0.2 < np.median(grade) < 0.7  # at most the flight's 0.57
    assert np.all(s.speed_3d[on] > s.speed_xy[on])
    flat = ~s.sloped & ok
    np.testing.assert_allclose(s.speed_3d[flat], s.speed_xy[flat], rtol=0.0013)


def test_analyse_writes_speeds_without_measurement_lines(stairs_run):
    result = CliRunner().invoke(app, ["analyse", str(stairs_run)])
    assert result.exit_code == 0, result.output
    assert "on stairs and slopes" in result.output
    table = np.loadtxt(stairs_run / "analysis" / "speeds_3d.csv", delimiter=",", skiprows=1)
    assert table.shape[1] == 6 and np.nanmax(table[:, 5] - table[:, 3]) > 0.05
