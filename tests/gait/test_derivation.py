"""The shipped gait data are exactly what scripts/derive_gait_data.py derives from the
measured sources (skipped when ../shared is not present)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
GAIT_DIR = REPO / ".." / "shared" / "data" / "gait"
DATA = REPO / "crowdwalk" / "data"

pytestmark = pytest.mark.skipif(
    not (GAIT_DIR / "bovi2011_multitask_reference_mmc3.xls").exists(),
    reason="measured gait data (../shared/data/gait) not available",
)


@pytest.fixture(scope="module")
def script():
    pytest.importorskip("xlrd")
    spec = importlib.util.spec_from_file_location("derive", REPO / "scripts/derive_gait_data.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def derived(script):
    return script.derive_all(GAIT_DIR)


def test_shipped_npz_matches_rederivation(script, derived):
    angles, meta, _ = derived
    linear, meta_linear = script.derive_datasets(GAIT_DIR, "linear")
    meta_linear = {"header": meta["header"], "datasets": meta_linear}
    with np.load(DATA / "elevation_datasets.npz") as shipped:
        np.testing.assert_array_equal(shipped["angles"], angles)
        assert json.loads(str(shipped["meta"])) == json.loads(json.dumps(script._fields(meta)))
        np.testing.assert_array_equal(shipped["angles_linear"], linear)
        assert json.loads(str(shipped["meta_linear"])) == json.loads(
            json.dumps(script._fields(meta_linear)))


def test_shipped_normative_matches_rederivation(derived):
    _, _, norm = derived
    assert json.loads((DATA / "normative.json").read_text()) == norm


def test_check_mode_reports_match(script, capsys):
    assert script.main(["--gait-dir", str(GAIT_DIR), "--out-dir", str(DATA), "--check"]) == 0
    assert "shipped files match" in capsys.readouterr().out


def test_conventions_against_the_raw_bovi_columns(script):
    curves = script.read_bovi_curves(GAIT_DIR / script.BOVI_FILE)["Natural"]
    thigh = curves["Thigh Flex/Extension"]
    hip = curves["Hip Flex/Extension"]
    tilt = curves["Pelvic Ant/Posterior Tilt"]
    knee = curves["Knee Flex/Extension"]
    shank = curves["Shank Flex/Extension"]
    # Bovi's pelvic tilt is posterior-positive: thigh (lab) = hip (pelvis) + tilt.
    assert np.abs(thigh - (hip + tilt)).max() < 2.0
    assert tilt.mean() < -5  # i.e. about 9 deg anterior
    # Knee flexion = thigh - shank elevation (both distal-anterior positive).
    assert np.abs(knee - (thigh - shank)).max() < 2.5


def test_foot_offset_and_pelvis_sign_in_the_derived_data(derived):
    angles, meta, _ = derived
    names = [m["name"] for m in meta["datasets"]]
    natural = np.rad2deg(angles[names.index("level_natural")].astype(float))
    assert abs(np.median(natural[15:30, 0])) < 1.0  # flat foot = 0 at mid-stance
    assert natural[0, 0] > 10  # toe-up at heel strike
    assert abs(natural[:, 3].mean()) < 0.5  # pelvis zero = natural-speed mean
    fast = np.rad2deg(angles[names.index("level_l")].astype(float))
    assert fast[:, 3].mean() > 2  # faster walking tilts the pelvis further anterior


def test_level_kinematics_reproduce_measured_strides(derived):
    _, meta, _ = derived
    for m in meta["datasets"]:
        if m["kind"] == "level":
            assert m["fk_step_length"] == pytest.approx(m["stride_length"] / 2, rel=0.04)


def test_natural_walk_agrees_with_winter_and_wbds(script, derived):
    angles, meta, norm = derived
    check = script.cross_check(GAIT_DIR, angles, meta, norm)
    # Knee from the elevation angles vs Winter (1991) natural cadence: same curve.
    assert check["knee"]["rms_deg"] < 4 and check["knee"]["corr"] > 0.98
    # Ankle: same shape; zero differs (Winter's anatomical zero vs our flat foot).
    assert check["ankle"]["corr"] > 0.9 and abs(check["ankle"]["mean_diff_deg"]) < 8
    # Bovi's level step lengths lie within ~2.5 residual SDs of the WBDS speed fit.
    sd = norm["step_length_vs_speed"]["residual_sd_m"]
    assert all(abs(d) < 2.5 * sd for d in check["step_length_vs_wbds"].values())


def test_warp_puts_contralateral_strike_at_half(script):
    from crowdwalk.gait.datasets import sample

    t = np.arange(100) / 100
    curve = np.stack([np.sin(2 * np.pi * t + k) for k in range(4)], axis=1)
    warped, to_t = script.warp_to_half(curve, 0.56)
    assert to_t(0.56) == pytest.approx(0.5, abs=1e-3)
    assert to_t(0.0) == pytest.approx(0.0) and to_t(1.0) == pytest.approx(1.0)
    np.testing.assert_allclose(warped[50], sample(curve, 0.56), atol=1e-12)
    np.testing.assert_allclose(warped[0], curve[0], atol=1e-12)
    # Still periodic and smooth: the wrap-around step is like any other step.
    steps = np.abs(np.diff(np.vstack([warped, warped[:1]]), axis=0))
    assert steps[-1].max() <= 1.1 * steps[:-1].max()


def test_shipped_pelvis_motion_matches_rederivation_and_bovi(script):
    """pelvis_motion.json is what the script derives, and its harmonics rebuild Bovi's
    adult natural obliquity and rotation (their half-period-antisymmetric part) to within
    0.3 deg; + own side up in loading response, own side forward at heel strike."""
    pelvis = script.derive_pelvis_motion(GAIT_DIR)
    assert json.loads((DATA / "pelvis_motion.json").read_text()) == json.loads(
        json.dumps(pelvis))
    curves = script.read_bovi_curves(GAIT_DIR / script.BOVI_FILE)["Natural"]
    from crowdwalk.gait.datasets import pelvis_motion

    motion = pelvis_motion("Natural")
    t = np.linspace(0.0, 1.0, 101)[:100]
    for column, shape, peak in ((script.OBLIQUITY, motion.list_shape, motion.list_peak),
                                (script.ROTATION, motion.rotation_shape, motion.rotation_peak)):
        raw = curves[column][:100]
        odd = 0.5 * (raw - np.roll(raw, -50))
        # the time warp moves samples by < 1 % of the stride: compare on the raw grid
        assert np.sqrt(np.mean((np.rad2deg(peak) * shape(t) - odd) ** 2)) < 0.3
    assert motion.list_shape(0.15) > 0.9 and motion.rotation_shape(0.0) > 0.9


def test_shipped_trunk_motion_matches_rederivation(script):
    """trunk_motion.json is what the script derives from Schwartz 2008 (Free speed)."""
    trunk = script.derive_trunk_motion(GAIT_DIR)
    assert json.loads((DATA / "trunk_motion.json").read_text()) == json.loads(
        json.dumps(trunk))
    assert trunk["rotation"]["residual_rms_deg"] < 0.2
    assert trunk["tilt"]["residual_rms_deg"] < 0.2


def test_stair_cycles_close_in_the_swing(script):
    """The stair cycles (which do not close: Bovi's ascent thigh 54.8° → 6.8°) are closed
    over the swing alone: every sample up to the measured foot-off is Bovi's curve, the
    closed curve is periodic, and the level datasets are those of the linear closure."""
    curves = script.read_bovi_curves(GAIT_DIR / script.BOVI_FILE)
    params = script.read_bovi_parameters(GAIT_DIR / script.BOVI_FILE)
    for task in ("Ascending", "Descending"):
        fo = params[task]["Ipsilateral Foot Off [% cycle]"] / 100
        for column in script.SEGMENTS:
            raw = curves[task][column]
            closed = script.close_in_swing(raw, fo)
            before = np.arange(100) <= int(fo * 100)
            np.testing.assert_array_equal(closed[before], raw[:100][before])
            # periodic: the wrap is a step like its neighbours, not the 48° drift
            assert abs(closed[-1] - closed[0]) < 2.0 * np.abs(np.diff(closed)).max()
    swing, _ = script.derive_datasets(GAIT_DIR, "swing")
    linear, meta = script.derive_datasets(GAIT_DIR, "linear")
    level = [k for k, m in enumerate(meta) if m["kind"] == "level"]
    np.testing.assert_array_equal(swing[level], linear[level])
