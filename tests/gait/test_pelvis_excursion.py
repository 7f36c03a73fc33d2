"""scripts/pelvis_excursion.py: the hip-excursion parts and the trials' event rule."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "pelvis_excursion.py"
_spec = importlib.util.spec_from_file_location("pelvis_excursion", SCRIPT)
pe = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(pe)


def test_parts_of_a_rigid_compass_leg():
    """A straight leg of length L pivoting on a fixed ankle from +θ0 at heel strike to
    −θ0 at the other heel strike: the hip rises L (1 − cos θ0), all of it hip − ankle."""
    n, length, theta0, ankle_z = 101, 0.85, np.radians(20.0), 0.07
    theta = np.linspace(theta0, -theta0, 51)
    theta = np.concatenate([theta, np.linspace(-theta0, theta0, n - 51)])  # "swing" back
    ankle = np.full(n, ankle_z)
    hip = ankle + length * np.cos(theta)
    deg = np.degrees(theta)
    parts = pe._parts(hip, ankle, deg, deg, 0, n - 1)
    rise = length * (1.0 - np.cos(theta0))
    assert parts[2] == pytest.approx(100 * rise, rel=1e-3)  # hip rise [cm]
    assert parts[3] == pytest.approx(100 * rise, rel=1e-3)  # hip - ankle [cm]
    assert parts[4] == pytest.approx(0.0, abs=1e-9)  # ankle [cm]
    assert parts[1] == pytest.approx(100 * rise, rel=1e-3)  # 0-50 % peak to peak
    assert parts[5] == pytest.approx(20.0) and parts[6] == pytest.approx(deg[20])


def test_heel_strikes_where_the_heel_stops():
    """A heel that stands still 0.6 of each 1 s stride and moves at 2.5 v otherwise is
    struck once per stride, on the first frame it is slow."""
    rate, v = 100.0, 1.2
    time = np.arange(0.0, 3.0, 1.0 / rate)
    moving = (time % 1.0) >= 0.6
    x = np.cumsum(np.where(moving, 2.5 * v, 0.0)) / rate
    strikes = pe._heel_strikes(x, time, v)
    assert np.allclose(time[strikes] % 1.0, 0.0, atol=1.5 / rate)
    assert strikes.size == 2  # t = 1 s and 2 s (t = 0 has no moving frame before it)


@pytest.mark.skipif(not pe.WINTER.exists(), reason="measured gait data (../shared) not found")
def test_rigid_segments_remove_the_markers_leg_lengthening():
    """Winter's markers lengthen thigh and shank over the stance; the rigid hip, built
    with constant lengths, rises less than the trochanter marker."""
    rows = pe.winter()
    marker, rigid = rows["Winter A1, trochanter marker"], rows["Winter A1, rigid segments"]
    assert rigid[2] < marker[2] and rigid[4] < marker[4]  # 0-50 %, hip - ankle
    assert np.isnan(rigid[1])  # no stride figure: in swing the hip is on the other leg
    assert rigid[6:] == marker[6:]  # the same measured elevations
