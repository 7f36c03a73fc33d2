"""Ko & Badler (1992): walk data, φ_ρ, ψ and the paper's theorems as properties."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.gait.ko_badler import (
    BodyCondition,
    StepStart,
    TimedSequence,
    achieved_step_length,
    body_generalization,
    hip_height_at_heel_strike,
    interpolation,
    load_prototype,
    mu,
    step_length_generalization,
)
from crowdwalk.gait.ko_badler.walkdata import SEQUENCES

PROTO = load_prototype()
FIELDS = ("thigh", "shin", "ankle_height", "heel", "ball", "toes")

ratios = st.floats(0.6, 1.5)
starts = st.builds(StepStart, st.floats(0.35, 0.9), st.floats(0.6, 0.85))
scales = st.lists(st.floats(0.75, 1.35), min_size=6, max_size=6)


def scaled_body(factors) -> BodyCondition:
    """The prototype's body with each segment scaled by its own factor (non-similar)."""
    pairs = zip(FIELDS, factors, strict=True)
    return BodyCondition(**{k: float(getattr(PROTO.body, k)) * f for k, f in pairs})


def assert_same_walk(a, b, atol=1e-9) -> None:
    np.testing.assert_allclose(a.step_length, b.step_length, rtol=0, atol=atol)
    np.testing.assert_allclose(a.previous_step_length, b.previous_step_length, rtol=0, atol=atol)
    for k in SEQUENCES:
        np.testing.assert_allclose(getattr(a, k).v, getattr(b, k).v, rtol=0, atol=atol,
                                   err_msg=k)  # fmt: skip
    for k in FIELDS:
        np.testing.assert_allclose(getattr(a.body, k), getattr(b.body, k), atol=atol)


def test_prototype_is_a_consistent_walk():
    w = PROTO
    # Events in order within the step (FGM < TOM of the swing foot < MOM < 1 + TOM).
    assert 0 < w.fgm < w.tom < 0.5 < w.mom < 1 + w.tom
    assert w.foot2.t[-1] == pytest.approx(1 + w.tom)
    assert w.meta.t[-1] == pytest.approx(1 + w.tom)
    # Sequences meet the μ* they define; the walk's own step is what its ankle realises.
    m = mu(w.law, w.body, w.step_length)
    np.testing.assert_allclose(m, w.law.mu_star, atol=1e-12)
    assert w.foot1.v[0] == pytest.approx(m[1]) and w.foot3.v[-1] == pytest.approx(m[1])
    assert w.foot2.v[-1] == pytest.approx(-m[2]) and w.meta.v[-1] == pytest.approx(m[3])
    assert achieved_step_length(w) == pytest.approx(w.step_length, abs=1e-8)
    # A normal adult walk: step 0.6-0.8 m, hip 0.6-0.9 m above the floor, heel strike
    # 10-30 deg toe up, toe-off 50-80 deg heel up.
    assert 0.6 < w.step_length < 0.8 and np.all((w.hip.y > 0.6) & (w.hip.y < 0.9))
    assert 10 < np.degrees(m[1]) < 30 and 50 < np.degrees(m[2]) < 80
    # φ_1 leaves the prototype unchanged (it was made consistent with the model).
    assert_same_walk(step_length_generalization(w, 1.0), w, atol=1e-8)


def test_interpolation_is_eq2_and_batches():
    q = TimedSequence(np.array([0.0, 0.5, 1.0]), np.array([[0.0, 1.0, 3.0], [2.0, 2.0, 0.0]]))
    np.testing.assert_allclose(interpolation(q, np.array([0.25, 0.75])), [0.5, 1.0])
    np.testing.assert_allclose(q(1.0), [3.0, 0.0])
    path = TimedSequence(np.array([0.0, 1.0]), np.array([[0.0, 0.0], [2.0, 4.0]]))
    np.testing.assert_allclose(path(0.5), [1.0, 2.0])


def test_hip_height_lower_for_longer_steps():
    """Fig. 4: the hip at HSM⁺ is lower after a longer step."""
    sl = np.array([0.4, 0.6, 0.8, 1.0])
    h = hip_height_at_heel_strike(PROTO.law, PROTO.body, sl)
    assert np.all(np.diff(h) < 0)


@settings(max_examples=40, deadline=None)
@given(rho=ratios, start=starts)
def test_lemma2_step_length_is_rho_sl(rho, start):
    """Lemma 2: the step length of φ_ρ(W(S, sl)) is exactly ρ·sl (its heel lands on the floor)."""
    w = step_length_generalization(PROTO, rho, start=start)
    assert achieved_step_length(w) == pytest.approx(rho * PROTO.step_length, abs=1e-9)
    ah, th = w.body.ankle_heel, w.body.heel_angle
    heel_y = w.ankle.y[-1] - ah * np.sin(th + w.foot3.v[-1])
    assert heel_y == pytest.approx(0.0, abs=1e-9)
    # ... and so for a generalised walk generalised again.
    again = step_length_generalization(w, 1.0 / rho)
    assert achieved_step_length(again) == pytest.approx(PROTO.step_length, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(r1=ratios, r2=ratios, start=starts)
def test_theorem1_composition(r1, r2, start):
    """Theorem 1: φ_{ρ1ρ2} = φ_{ρ2} ∘ φ_{ρ1} (same previous step and posture)."""
    two = step_length_generalization(
        step_length_generalization(PROTO, r1, start=start), r2, start=start)
    one = step_length_generalization(PROTO, r1 * r2, start=start)
    assert_same_walk(two, one)


@settings(max_examples=40, deadline=None)
@given(f1=scales, f2=scales)
def test_theorem3_body_generalization_is_transitive(f1, f2):
    """Theorem 3: ψ_{S1}^{S2} ∘ ψ_S^{S1} = ψ_S^{S2} for bodies of any segment ratios."""
    s1, s2 = scaled_body(f1), scaled_body(f2)
    two = body_generalization(body_generalization(PROTO, s1), s2)
    one = body_generalization(PROTO, s2)
    assert_same_walk(two, one)
    # Lemma 3: the step length becomes ll(S2)/ll(S) sl, and the ankle realises it.
    expect = s2.leg_length / PROTO.body.leg_length * PROTO.step_length
    assert achieved_step_length(one) == pytest.approx(expect, abs=1e-9)


def combined(w, body, step_length):
    """τ (Eq. 205): φ_{(S1/S2)(sl2/sl1)} on W(S1, sl1), then ψ_{S1}^{S2}."""
    alpha = body.leg_length / w.body.leg_length
    return body_generalization(step_length_generalization(
        w, step_length / (alpha * w.step_length)), body)  # fmt: skip


@settings(max_examples=40, deadline=None)
@given(f1=scales, f2=scales, sl2=st.floats(0.4, 0.9), sl3=st.floats(0.4, 0.9),
       a1=st.floats(0.8, 1.25), a2=st.floats(0.8, 1.25))  # fmt: skip
def test_theorem5_combined_generalization_is_transitive(f1, f2, sl2, sl3, a1, a2):
    """Theorem 5: τ23 ∘ τ12 = τ13.

    Exact in every sequence for bodies of any segment ratios except the hip height, which
    §2.1 computes from each body's own segments (Eqs. 7–11): that part is exact for
    similar bodies (S2 = α S1), the case the paper's proof (Eq. 170) assumes.
    """
    s2, s3 = scaled_body(f1), scaled_body(f2)
    two = combined(combined(PROTO, s2, sl2), s3, sl3)
    one = combined(PROTO, s3, sl3)
    assert achieved_step_length(two) == pytest.approx(sl3, abs=1e-9)
    for k in ("foot1", "foot2", "foot3", "meta", "ankle"):
        np.testing.assert_allclose(getattr(two, k).v, getattr(one, k).v, atol=1e-9, err_msg=k)
    np.testing.assert_allclose(two.hip.x, one.hip.x, atol=1e-9)
    similar2, similar3 = scaled_body([a1] * 6), scaled_body([a1 * a2] * 6)
    assert_same_walk(combined(combined(PROTO, similar2, sl2), similar3, sl3),
                     combined(PROTO, similar3, sl3))  # fmt: skip


def test_generalisation_broadcasts_over_walkers():
    """A batch of walkers gives each the walk it would get alone."""
    bodies = [scaled_body([1.0] * 6), scaled_body([1.1, 0.9, 1.2, 1.0, 0.8, 1.3])]
    batch = BodyCondition(**{k: np.array([getattr(b, k) for b in bodies]) for k in FIELDS})
    rho = np.array([0.8, 1.2])
    together = step_length_generalization(body_generalization(PROTO, batch), rho)
    for i, b in enumerate(bodies):
        alone = step_length_generalization(body_generalization(PROTO, b), rho[i])
        for k in SEQUENCES:
            np.testing.assert_allclose(getattr(together, k).v[i], getattr(alone, k).v, atol=1e-12)


def test_prototype_rederives_from_the_measured_markers():
    """scripts/derive_ko_badler_prototype.py --check: the shipped file is what it derives."""
    import importlib.util
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    script = repo / "scripts" / "derive_ko_badler_prototype.py"
    spec = importlib.util.spec_from_file_location("derive_ko_badler_prototype", script)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    if not (mod.GAIT_DIR / mod.WINTER_FILE).exists():
        pytest.skip("measured gait data (../shared/data/gait) not available")
    data, report = mod.derive(mod.GAIT_DIR)
    shipped = json.loads((repo / "crowdwalk" / "data" / "ko_badler_prototype.json").read_text())
    assert mod._close(shipped, data)
    # Winter's trial: about 1.4 m/s; events in the order of Fig. 1.
    assert 1.3 < report["speed_m_per_s"] < 1.55
    ev = report["events_frame"]
    assert ev["HSM1"] < ev["FGM1"] < ev["MOM"] < ev["TOM"] < ev["HSM2"] < ev["FGM2"]
