"""Shipped elevation-angle datasets: physiology, periodicity, loader and sampler."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.errors import InputError
from crowdwalk.gait.datasets import (
    ANGLE_NAMES,
    ElevationDataset,
    dataset_by_name,
    load_datasets,
    normative,
    sample,
)

FOOT, SHANK, THIGH, PELVIS = range(4)
LEVEL = ["level_xs", "level_s", "level_natural", "level_m", "level_l"]


def deg(x):
    return np.rad2deg(x)


def test_shipped_set_has_five_speeds_and_stairs():
    names = [d.name for d in load_datasets()]
    assert names == [*LEVEL, "stairs_up", "stairs_down"]
    kinds = {d.name: d.kind for d in load_datasets()}
    assert kinds["stairs_up"] == "stairs_up" and kinds["stairs_down"] == "stairs_down"
    assert ANGLE_NAMES == ("foot", "shank", "thigh", "pelvis")


def test_natural_speed_curves_have_physiological_shape():
    a = deg(dataset_by_name("level_natural").angles)
    thigh_range = np.ptp(a[:, THIGH])
    assert 40 <= thigh_range <= 50
    knee = a[:, THIGH] - a[:, SHANK]  # knee flexion from the elevation angles
    swing = slice(60, 100)
    assert 55 <= knee[swing].max() <= 70
    assert knee[swing].argmax() + 60 in range(65, 80)  # peak in early/mid swing
    assert knee[40] < 15  # nearly straight in late stance
    # Heel strike: thigh flexed, shank inclined forward, foot toe-up.
    assert 15 < a[0, THIGH] < 35 and a[0, SHANK] > 5 and a[0, FOOT] > 10
    # Flat foot at mid-stance, toe-down near toe-off.
    assert abs(a[25, FOOT]) < 2
    assert a[62, FOOT] < -25
    assert np.ptp(a[:, PELVIS]) < 5  # pelvic tilt excursion is a few degrees


def test_faster_datasets_have_longer_strides_and_shorter_stance():
    level = [dataset_by_name(n) for n in LEVEL]
    strides = [d.stride_length for d in level]
    speeds = [d.speed for d in level]
    assert strides == sorted(strides) and speeds == sorted(speeds)
    assert level[-1].stance_fraction < level[0].stance_fraction
    thigh_rom = [np.ptp(d.angles[:, THIGH]) for d in level]
    assert thigh_rom == sorted(thigh_rom)
    for d in level:
        assert 0.55 < d.stance_fraction < 0.7 and d.step_height == 0


def test_stair_datasets_rise_and_fall():
    up, down = dataset_by_name("stairs_up"), dataset_by_name("stairs_down")
    assert up.step_height > 0.04 and down.step_height < -0.02
    # Ascent lands with a strongly flexed hip; descent with a straighter one.
    assert deg(up.angles[0, THIGH]) > 45 > deg(down.angles[0, THIGH])
    # Descent lands toe first.
    assert deg(down.angles[0, FOOT]) < -10


def test_stair_stance_is_the_measured_stance():
    """Bovi 2011's stair cycles do not close (ascent thigh 54.8° at heel strike, 6.8° at the
    next one: the cycle ends off the flight). The stance phase is the measured one: from
    35 % to the contralateral strike the ascending knee (thigh − shank) is under 22°
    (Bovi: 16–21°), and the descent's stance knee stays in Bovi's stance range. With the
    drift removed linearly over the whole cycle (the data before gait11) the thigh
    carried +48°·t: the ascent knee was 37–41° from 35 to 50 % and its swing peak 100°
    (Bovi's mean 61°, the swing-peak parameter 65°)."""
    up, down = dataset_by_name("stairs_up"), dataset_by_name("stairs_down")
    knee_up = deg(up.angles[:, THIGH] - up.angles[:, SHANK])
    assert knee_up[35:50].max() < 22
    assert knee_up[0] > 60  # lands on the tread with the knee flexed, as measured
    knee_down = deg(down.angles[:, THIGH] - down.angles[:, SHANK])
    assert knee_down[:25].max() < 32  # Bovi's descent stance: 11-28° to 25 %


def test_stair_datasets_rise_alike_up_and_down():
    """Bovi's ascent and descent were measured on one staircase: the rise per step that
    Eq. 10 reads from the two datasets (``step_height``, group bodies 1.69 / 1.67 m)
    agrees within 1 cm (16.0 / 15.6 cm; 13.2 / 10.0 cm with the linear closure)."""
    up, down = dataset_by_name("stairs_up"), dataset_by_name("stairs_down")
    rise_up = up.step_height * up.body_height
    rise_down = -down.step_height * down.body_height
    assert abs(rise_up - rise_down) < 0.01


def test_stair_closure_switch_changes_the_stair_datasets_only():
    swing, linear = load_datasets(), load_datasets("linear")
    for a, b in zip(swing, linear, strict=True):
        assert a.name == b.name
        same = np.array_equal(a.angles, b.angles)
        assert same == (a.kind == "level"), a.name
    with pytest.raises(InputError, match=r"stair_closure"):
        load_datasets("cubic")


def test_curves_are_periodic_and_smooth():
    for d in load_datasets():
        a = deg(d.angles)
        step = np.abs(np.diff(np.vstack([a, a[:1]]), axis=0))
        # Largest sample-to-sample change, including the wrap t=0.99 -> 0.
        assert step.max() < 6, d.name
        wrap = np.abs(a[0] - a[-1])
        assert np.all(wrap <= step[:-1].max(axis=0) + 1e-6), d.name


def test_angles_are_read_only():
    d = load_datasets()[0]
    with pytest.raises(ValueError):
        d.angles[0, 0] = 1.0


def test_sample_is_exact_at_nodes_and_periodic():
    d = dataset_by_name("level_natural")
    t = np.arange(d.samples) / d.samples
    np.testing.assert_allclose(sample(d, t), d.angles, atol=1e-12)
    np.testing.assert_allclose(sample(d, t + 3.0), d.angles, atol=1e-9)
    np.testing.assert_allclose(sample(d, t - 1.0), d.angles, atol=1e-9)


@settings(max_examples=50, deadline=None)
@given(st.floats(-5, 5, allow_nan=False))
def test_sample_lies_between_neighbours_envelope(t):
    d = dataset_by_name("level_m")
    n = d.samples
    value = sample(d, t)
    k = int(np.floor(np.mod(t, 1.0) * n)) % n
    nb = d.angles[[(k - 1) % n, k, (k + 1) % n, (k + 2) % n]]
    lo, hi = nb.min(axis=0), nb.max(axis=0)
    margin = 0.2 * (hi - lo) + 1e-12  # Catmull-Rom overshoot stays small
    assert np.all(value >= lo - margin) and np.all(value <= hi + margin)


def test_sample_batch_matches_single():
    ds = load_datasets()
    curves = np.stack([d.angles for d in ds])
    t = np.linspace(-0.3, 1.7, len(ds))
    batch = sample(curves, t)
    single = np.stack([sample(d, ti) for d, ti in zip(ds, t, strict=True)])
    np.testing.assert_allclose(batch, single, atol=1e-12)
    assert batch.shape == (len(ds), 4)


def test_sample_rejects_nan_time():
    with pytest.raises(InputError, match=r"sample\.t must be finite"):
        sample(load_datasets()[0], np.array([0.1, np.nan]))


def test_dataset_validation_names_field_and_value():
    d = load_datasets()[0]
    with pytest.raises(InputError, match=r"ElevationDataset\.speed must be finite and > 0"):
        ElevationDataset(
            name="x", kind="level", speed=-1.0, body_height=1.7, stride_length=0.7,
            step_height=0.0, stance_fraction=0.6, double_support=0.2, stride_time=1.1,
            angles=d.angles,
        )
    with pytest.raises(InputError, match=r"ElevationDataset\.kind"):
        ElevationDataset(
            name="x", kind="slope", speed=1.0, body_height=1.7, stride_length=0.7,
            step_height=0.0, stance_fraction=0.6, double_support=0.2, stride_time=1.1,
            angles=d.angles,
        )
    with pytest.raises(InputError, match=r"dataset_by_name\.name"):
        dataset_by_name("jogging")


def test_normative_references_are_consistent():
    ref = normative()
    fit = ref["step_length_vs_speed"]
    at_optimal = fit["intercept_m"] + fit["slope_s"] * 1.34
    assert 0.62 <= at_optimal <= 0.78  # DESIGN.md: 0.65-0.78 m at 1.34 m/s (± fit SD)
    cad = ref["cadence_vs_speed"]
    f = cad["coefficient"] * 1.34 ** cad["exponent"]
    assert 1.5 <= f <= 2.1  # 90-126 steps/min
    # step length x cadence reproduces speed within 10 % over the fitted range
    v = np.linspace(*fit["speed_range_m_s"], 7)
    implied = (fit["intercept_m"] + fit["slope_s"] * v) * cad["coefficient"] * v ** cad["exponent"]
    assert np.all(np.abs(implied / v - 1) < 0.12)
    normal = ref["adult_normal_pace"]
    assert normal["velocity_m_s"][0] < 1.34 < normal["velocity_m_s"][1]
    assert 0.55 < ref["phases"]["stance_fraction_natural"] < 0.68
    for entry in ref.values():
        if isinstance(entry, dict):
            assert entry["source"]
    ref["phases"]["stance_fraction_natural"] = -1  # a fresh copy each call
    assert normative()["phases"]["stance_fraction_natural"] > 0


def test_dataset_and_region_plots_are_written(tmp_path):
    from crowdwalk.gait.elevinterp import ElevInterp, SagittalLeg
    from crowdwalk.plots import plot_elevation_datasets, plot_elevinterp_region

    a = plot_elevation_datasets(load_datasets(), tmp_path / "datasets.png")
    b = plot_elevinterp_region(ElevInterp(), SagittalLeg.from_body_height(1.75),
                               tmp_path / "region.png", requests=[[0.6, 0.0], [1.2, 0.3]])
    for path in (a, b):
        assert path.exists() and path.stat().st_size > 10_000


def test_pelvis_motion_shapes_are_the_two_legs_halves():
    """Unit-peak list and rotation with c(t + 0.5) = -c(t) (ElevWalker reads the stance
    leg's t in [0, 0.5) and swaps sides at 0.5, so the pelvis is continuous there); the
    list is greatest in loading response and the rotation at heel strike (Bovi 2011)."""
    from crowdwalk.gait.datasets import pelvis_motion

    m = pelvis_motion()
    t = np.linspace(0.0, 1.0, 400, endpoint=False)
    for shape in (m.list_shape, m.rotation_shape):
        np.testing.assert_allclose(shape(t + 0.5), -shape(t), atol=1e-12)
        assert abs(np.abs(shape(t)).max() - 1.0) < 1e-3
    assert 0.08 <= t[np.argmax(m.list_shape(t))] <= 0.2
    assert abs(m.list_shape(0.4)) < 0.3 and m.rotation_shape(0.0) > 0.9
    assert np.deg2rad(3) < m.list_peak < np.deg2rad(7)
    assert np.deg2rad(2) < m.rotation_peak < np.deg2rad(6)


def test_trunk_motion_counter_rotates_and_its_tilt_is_a_wave():
    """Schwartz 2008's thorax rotation: own side back at heel strike (against the pelvis),
    c(t + 0.5) = -c(t); the tilt wave repeats every step, about zero, under 1 deg."""
    from crowdwalk.gait.datasets import pelvis_motion, trunk_motion

    m = trunk_motion()
    t = np.linspace(0.0, 1.0, 400, endpoint=False)
    np.testing.assert_allclose(m.rotation_shape(t + 0.5), -m.rotation_shape(t), atol=1e-12)
    assert m.rotation_shape(0.0) < -0.9 < 0.9 < pelvis_motion().rotation_shape(0.0)
    assert np.deg2rad(3) < m.rotation_peak < np.deg2rad(7)
    wave = m.tilt_wave(t)
    np.testing.assert_allclose(m.tilt_wave(t + 0.5), wave, atol=1e-12)
    assert abs(wave.mean()) < 1e-9 and 0 < np.abs(wave).max() < np.deg2rad(1.0)
