"""ElevInterp (Sun & Metaxas 2001, §5): Eq. 10 forward kinematics and inverse interpolation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.errors import InputError
from crowdwalk.gait.datasets import dataset_by_name, load_datasets
from crowdwalk.gait.elevinterp import (
    ElevInterp,
    ElevInterpConfig,
    SagittalLeg,
    dataset_step,
    lift_swing_toe,
    step_of,
)

CM = 0.01
PAPER = ElevInterpConfig(level_datum=False, heel_rise=False)  # §5 as written
LEVEL = ["level_xs", "level_s", "level_natural", "level_m", "level_l"]


def leg(height):
    return SagittalLeg.from_body_height(height)


# --- Eq. 10 forward kinematics -------------------------------------------------------


def test_compiled_blend_step_equals_step_of():
    """The refinement kernel's per-request Eq. 10 (feet on ball and heel) is step_of's."""
    from crowdwalk.gait.elevinterp import _row_step

    rng = np.random.default_rng(3)
    props = np.array([0.245, 0.246, 0.039, 0.038, 0.073]) / 0.53
    for _ in range(50):
        keys = rng.normal(0.0, 0.3, (3, 2, 4))
        w = rng.dirichlet(np.ones(3)) * 1.4 - 0.2
        blend = np.einsum("v,vrj->rj", w, keys)
        out = np.empty(2)
        _row_step(keys, w, props, out)
        expected = step_of(blend[0], blend[1], SagittalLeg(*props[:4], toe_offset=props[4],
                                                           ball_offset=props[4]))
        np.testing.assert_allclose(out, expected, atol=1e-12)


def test_compiled_blend_gives_einsums_values_bit_for_bit():
    """_blend (Eq. 9 without the gather) is the einsum of the gathered rows, bit for bit:
    signed zeros, tiny and large magnitudes, repeated vertices, one row and many."""
    from crowdwalk.gait.elevinterp import _blend

    rng = np.random.default_rng(5)
    for k, tail in ((1, (100, 4)), (7, (2, 4)), (300, (100, 4)), (40, (2,))):
        table = rng.normal(size=(25, *tail)) * 10.0 ** rng.integers(-8, 4, size=(25, *tail))
        table[rng.random(table.shape) < 0.1] = 0.0
        table[rng.random(table.shape) < 0.1] *= -0.0
        verts = rng.integers(0, 25, size=(k, 3)).astype(np.int32)
        w = rng.normal(size=(k, 3))
        w[rng.random(w.shape) < 0.1] = -0.0
        expected = np.einsum("kv,kv...->k...", w, table[verts])
        got = _blend(w, table, verts)
        assert got.shape == expected.shape
        assert got.tobytes() == expected.tobytes()
    # all products -0.0: the sum from 0 is +0.0, as einsum's
    minus = np.full((3, 2), -0.0)
    got = _blend(np.ones((1, 3)), minus, np.array([[0, 1, 2]]))
    assert got.tobytes() == np.einsum("kv,kvp->kp", np.ones((1, 3)), minus[[[0, 1, 2]]]).tobytes()


def test_standing_upright_is_a_zero_step():
    zero = np.zeros(4)
    np.testing.assert_allclose(step_of(zero, zero, leg(1.75)), [0.0, 0.0], atol=1e-12)


def test_symmetric_scissor_step_has_textbook_length():
    # Straight legs spread by ±a, feet flat: ankles 2 (thigh + shank) sin a apart, and the
    # swing ankle lands at the same height as the stance ankle.
    a = np.deg2rad(20)
    body = leg(1.75)
    stance = np.array([0.0, -a, -a, 0.0])
    swing = np.array([0.0, a, a, 0.0])
    sl, sh = step_of(stance, swing, body)
    assert sl == pytest.approx(2 * (body.thigh + body.shank) * np.sin(a), abs=1e-12)
    assert sh == pytest.approx(0.0, abs=1e-12)


def test_foot_roll_keeps_contact_points_fixed():
    # A stance foot pitched down rolls on its ball, which stays at ball_offset, so with a
    # vertical stance leg the hanging (flat) swing foot is raised by the roll.
    body = leg(1.75)
    phi = np.deg2rad(-30)
    stance = np.array([phi, 0.0, 0.0, 0.0])
    swing = np.zeros(4)
    sl, sh = step_of(stance, swing, body)
    ball = body.ball_offset
    rise = ball * np.sin(-phi) + body.ankle_height * (np.cos(phi) - 1)
    advance = ball * (1 - np.cos(phi)) + body.ankle_height * np.sin(-phi)
    assert sh == pytest.approx(rise, abs=1e-12)
    assert sl == pytest.approx(advance, abs=1e-12)
    # Without a ball the foot rolls on the toe tip (e.g. planners.Leg).
    tip = SagittalLeg(body.thigh, body.shank, body.ankle_height, body.heel_offset,
                      body.toe_offset)
    sl_tip, sh_tip = step_of(stance, swing, tip)
    assert sh_tip == pytest.approx(body.toe_offset * np.sin(-phi) + rise - ball * np.sin(-phi))
    # A heel-first landing swing foot lands on the heel: foothold heel_offset ahead of it.
    up = np.deg2rad(20)
    sl_up, sh_up = step_of(np.zeros(4), np.array([up, 0.0, 0.0, 0.0]), body)
    assert sh_up == pytest.approx(
        -body.ankle_height * np.cos(up) - body.heel_offset * np.sin(up) + body.ankle_height)
    assert sl_up == pytest.approx(
        -body.heel_offset * np.cos(up) + body.ankle_height * np.sin(up) + body.heel_offset)


def test_dataset_steps_match_measured_strides():
    # Eq. 10 on the measured curves reproduces half of Bovi's measured stride (±4 %, with
    # generic Winter segment proportions for the group's mean height).
    for name in LEVEL:
        d = dataset_by_name(name)
        sl, sh = dataset_step(d, leg(d.body_height)) / d.body_height
        assert sl == pytest.approx(d.stride_length / 2, rel=0.04), name
        assert abs(sh) < 0.02, name


def test_step_scales_with_body_height():
    d = dataset_by_name("level_natural")
    small, tall = dataset_step(d, leg(1.5)), dataset_step(d, leg(1.95))
    np.testing.assert_allclose(tall, small * 1.95 / 1.5, rtol=1e-12)


# --- ElevInterp ----------------------------------------------------------------------


def test_source_datasets_reproduce_their_own_steps_exactly():
    interp = ElevInterp(config=PAPER)
    body = leg(1.75)
    steps = interp.source_steps(body)
    out = interp.request(body, steps[:, 0], steps[:, 1])
    assert not out.refined.any() and not out.clamped.any()
    np.testing.assert_allclose(out.step_length, steps[:, 0], atol=1e-9)
    np.testing.assert_allclose(out.step_height, steps[:, 1], atol=1e-9)
    for k, d in enumerate(load_datasets()):
        np.testing.assert_allclose(out.angles[k], d.angles, atol=1e-9)
        assert out.stance_fraction[k] == pytest.approx(d.stance_fraction)


def test_interpolation_between_speeds_is_monotonic():
    # Between adjacent speeds the blend shifts monotonically: step length and thigh
    # excursion grow and the stance fraction shrinks (as in the measured series).
    interp = ElevInterp(config=PAPER)
    body = leg(1.75)
    steps = interp.source_steps(body)
    s = np.linspace(0, 1, 11)
    for i in range(len(LEVEL) - 1):
        a, b = steps[i], steps[i + 1]
        req = a + s[:, None] * (b - a)
        out = interp.request(body, req[:, 0], req[:, 1])
        assert out.converged.all() and not out.clamped.any()
        thigh_rom = np.ptp(out.angles[:, :, 2], axis=1)
        assert np.all(np.diff(thigh_rom) > 0), LEVEL[i]
        assert np.all(np.diff(out.stance_fraction) < 0), LEVEL[i]
        assert np.all(np.diff(out.step_length) > 0), LEVEL[i]


def random_requests(interp, body, rng, n):
    """Points inside the legal region (convex combinations of its corners, shrunk 10 %)."""
    poly = interp.legal_region(body)
    w = rng.dirichlet(np.ones(len(poly)), size=n)
    centre = poly.mean(axis=0)
    return centre + 0.9 * (w @ poly - centre)


@settings(max_examples=30, deadline=None)
@given(st.floats(1.50, 1.95), st.integers(0, 2**31 - 1))
def test_refined_step_matches_request_within_1cm(height, seed):
    # Walking requests: level steps at 0.8-1.6 m/s (WBDS step length, scaled with body
    # height) and up/down steps of up to 6 cm at shorter lengths (0.50-0.60 m: the stair
    # datasets' Eq. 10 steps are 0.45 / 0.42 m for 1.75 m, the region's left corners).
    rng = np.random.default_rng(seed)
    interp = ElevInterp(config=ElevInterpConfig(max_inserted=0))  # every request searched
    body = leg(height)
    scale = height / 1.75
    speed = rng.uniform(0.8, 1.6, 6)
    level = np.stack([0.2555 + 0.312 * speed, np.zeros(6)], axis=1) * scale
    sloped = np.stack([rng.uniform(0.50, 0.60, 6), rng.uniform(-0.03, 0.06, 6)], axis=1) * scale
    req = np.vstack([level, sloped])
    out = interp.request(body, req[:, 0], req[:, 1])
    assert out.converged.all() and not out.clamped.any()
    assert np.all(np.abs(out.step_length - req[:, 0]) < 1 * CM)
    assert np.all(np.abs(out.step_height - req[:, 1]) < 1 * CM)
    # The produced dataset really has that step (independent re-measurement).
    np.testing.assert_allclose(dataset_step(out.angles, body), req, atol=1 * CM)
    assert np.all(np.isfinite(out.angles))


@settings(max_examples=30, deadline=None)
@given(st.floats(1.50, 1.95), st.integers(0, 2**31 - 1))
def test_every_request_in_the_region_is_served_or_flagged(height, seed):
    interp = ElevInterp(config=ElevInterpConfig(max_inserted=0))
    body = leg(height)
    req = random_requests(interp, body, np.random.default_rng(seed), 16)
    out = interp.request(body, req[:, 0], req[:, 1])
    achieved = np.stack([out.step_length, out.step_height], axis=1)
    err = np.linalg.norm(achieved - req, axis=1)
    assert np.all(err[out.converged] <= interp.config.tolerance + 1e-12)
    # Where Eq. 10 folds, no blend reaches the request: flagged, and still close.
    assert np.all(out.clamped[~out.converged])
    assert np.all(err < 2 * CM)
    assert out.converged.mean() >= 0.75
    # Sane curves even when extrapolating: stance 50-75 %, knee flexion peak 40-110 deg.
    assert np.all((out.stance_fraction > 0.5) & (out.stance_fraction < 0.75))
    knee = np.rad2deg(out.angles[:, :, 2] - out.angles[:, :, 1]).max(axis=1)
    assert np.all((knee > 40) & (knee < 110))


def test_mixed_bodies_in_one_batch():
    rng = np.random.default_rng(7)
    heights = rng.uniform(1.5, 1.95, 40)
    body = leg(heights)
    interp = ElevInterp()
    # each body's own region (the stair corners scale with the body: a small body's
    # region is not inside a tall one's since the stair datasets' Eq. 10 steps are long)
    corner = rng.integers(0, 3, 40)
    req = np.empty((40, 2))
    for i, h in enumerate(heights):
        region = interp.legal_region(leg(h))
        centre = region.mean(axis=0)
        req[i] = centre + 0.5 * (region[corner[i] % len(region)] - centre)
    out = interp.request(body, req[:, 0], req[:, 1])
    achieved = np.stack([out.step_length, out.step_height], axis=1)
    assert np.abs(achieved - req).max() < 1 * CM
    np.testing.assert_allclose(dataset_step(out.angles, body), achieved, atol=1e-9)
    assert out.angles.shape == (40, 100, 4)


def test_same_dataset_for_every_body_size_at_the_same_normalised_step():
    # Size invariance: a step scaled with leg length gets the same angle curves.
    sizes = np.array([1.5, 1.7, 1.95])
    body = leg(sizes)
    # the paper's triangulation (no level datum: with it the midpoint's height is moved
    # onto the level line and, with the stair corners at 0.45-0.49 leg lengths since the
    # stair cycles close in the swing, lands in a triangle that needs the search)
    interp = ElevInterp(config=ElevInterpConfig(max_inserted=0, level_datum=False))
    unit = interp.source_steps(leg(1.0)) / leg(1.0).length  # per leg length
    for normalised, exact in [
        (0.5 * (unit[2] + unit[3]), True),  # between natural and M: no search needed
        (np.array([0.55, 0.02]), False),  # searched: equal up to the solver tolerance
    ]:
        req = normalised * body.length[:, None]
        out = interp.request(body, req[:, 0], req[:, 1])
        assert out.refined.any() != exact
        atol = 1e-9 if exact else 2e-3
        np.testing.assert_allclose(out.angles[0], out.angles[2], atol=atol)
        np.testing.assert_allclose(out.angles[1], out.angles[2], atol=atol)
        np.testing.assert_allclose(out.step_length / body.length, normalised[0], atol=3e-3)


def test_solved_datasets_are_inserted_and_reused():
    # §5 step 6 as written (the level line's secant refinement is flagged ``refined`` on
    # every call, and serves a 1.75 m body's long level steps since ``knee_closure``)
    interp = ElevInterp(config=PAPER)
    body = leg(1.75)
    req = random_requests(interp, body, np.random.default_rng(3), 20)
    first = interp.request(body, req[:, 0], req[:, 1])
    assert first.refined.any()
    inserted = interp.stats["inserted"]
    assert inserted > 0
    again = interp.request(body, req[:, 0], req[:, 1])
    # Inserted datasets are now vertices: their requests (nearly) all need no search.
    assert again.refined.sum() <= 0.1 * first.refined.sum()
    assert interp.stats["inserted"] == inserted  # nothing new
    np.testing.assert_allclose(again.step_length, req[:, 0], atol=interp.config.tolerance)


def test_request_outside_is_clamped_to_nearest_legal_step():
    interp = ElevInterp()
    body = leg(1.75)
    region = interp.legal_region(body)
    out = interp.request(body, [1.5, 0.6, 0.6], [0.0, 0.5, 0.0])
    assert list(out.clamped) == [True, True, False]
    assert out.converged.all()
    for k, want in enumerate([[1.5, 0.0], [0.6, 0.5]]):
        got = out.target[k]
        # No vertex of the region is nearer to the request than the clamped target.
        assert np.linalg.norm(got - want) <= np.linalg.norm(region - want, axis=1).min() + 1e-9
        assert abs(out.step_length[k] - got[0]) < 0.002 + 1e-9
    assert out.target[0, 0] < 1.0  # longest step the data allow for this body
    assert interp.stats["clamped"] == 2


@pytest.mark.parametrize(
    ("kwargs", "field", "value"),
    [
        ({"step_length": np.nan, "step_height": 0.0}, "step_length", "nan"),
        ({"step_length": -0.5, "step_height": 0.0}, "step_length", "-0.5"),
        ({"step_length": 0.6, "step_height": np.inf}, "step_height", "inf"),
    ],
)
def test_bad_requests_name_field_and_value(kwargs, field, value):
    with pytest.raises(InputError, match=rf"ElevInterp\.{field} must be .*got {value}"):
        ElevInterp().request(leg(1.75), **kwargs)


def test_bad_leg_and_config_are_rejected():
    bad = SagittalLeg(-0.4, 0.43, 0.07, 0.05, 0.2)
    with pytest.raises(InputError, match=r"ElevInterp\.leg\.thigh must be finite and > 0"):
        ElevInterp().request(bad, 0.6, 0.0)
    with pytest.raises(InputError, match=r"ElevInterpConfig\.tolerance"):
        ElevInterpConfig(tolerance=0.0)
    with pytest.raises(InputError, match=r"ElevInterp\.datasets"):
        ElevInterp(load_datasets()[:2])
    with pytest.raises(InputError, match=r"SagittalLeg\.height"):
        SagittalLeg.from_body_height(np.nan)


# --- level steps (extensions of §5, docs/architecture.md "Level steps") -----------------


def test_level_datum_serves_level_steps_from_level_data_only():
    # The level datasets' own Eq. 10 height is about -1.5 cm for this body: the paper's
    # space blends a stair dataset into a SH = 0 request, the level datum does not.
    body = leg(1.75)
    natural = LEVEL.index("level_natural")
    paper = ElevInterp(config=PAPER)
    length = paper.source_steps(body)[natural, 0]
    mixed = paper.request(body, length, 0.0)
    datum = ElevInterp(config=ElevInterpConfig(heel_rise=False)).request(body, length, 0.0)
    want = dataset_by_name("level_natural")
    np.testing.assert_allclose(datum.angles[0], want.angles, atol=1e-9)
    assert np.abs(mixed.angles[0] - want.angles).max() > np.deg2rad(1.0)


def test_heel_rise_closes_level_steps_with_the_trailing_foot():
    body = leg(np.full(3, 1.75))
    length = np.array([0.58, 0.68, 0.76])
    open_ = ElevInterp(config=ElevInterpConfig(heel_rise=False)).request(body, length, 0.0)
    closed = ElevInterp().request(body, length, 0.0)
    assert closed.converged.all()
    # the step lands on the level foothold (Eq. 10, re-measured), not 1-2 cm below it
    assert np.all(open_.step_height < -0.5 * CM)
    np.testing.assert_allclose(dataset_step(closed.angles, body), np.stack(
        [length, np.zeros(3)], axis=1), atol=0.2 * CM)
    # ... by a higher heel from mid-stance to foot-off (the blend is re-solved for the
    # length, so the flat foot moves a little too)
    t = np.arange(100) / 100
    rise = np.rad2deg(closed.angles[:, :, 0] - open_.angles[:, :, 0])
    assert np.all(np.abs(rise[:, t < 0.3]) < 1.0)
    assert np.all(rise[:, (t > 0.45) & (t < 0.6)] < -2.0)


def test_lift_swing_toe_flexes_only_the_swing_knee_to_the_clearance():
    body = leg(np.full(2, 1.75))
    data = ElevInterp().request(body, np.array([0.58, 0.68]), 0.0)
    lifted = lift_swing_toe(data.angles, body, data.stance_fraction, hip_drop=np.zeros(2),
                            clearance=0.03)
    changed = lifted != data.angles
    assert not changed[:, :50].any()  # the swing half only
    assert not changed[:, :, [0, 3]].any()  # foot and pelvis keep the data
    bend = lifted - data.angles  # the knee flexes: thigh forward, shank back, equally
    assert np.all(bend[:, :, 2] >= 0) and bend[:, :, 2].max() > np.deg2rad(1.0)
    np.testing.assert_allclose(bend[:, :, 1], -bend[:, :, 2], atol=1e-12)
    less = lift_swing_toe(data.angles, body, data.stance_fraction, hip_drop=np.zeros(2),
                          clearance=0.01)
    assert np.all(lifted[:, :, 2] >= less[:, :, 2]) and (lifted != less).any()
    none = lift_swing_toe(data.angles, body, data.stance_fraction, hip_drop=np.zeros(2),
                          clearance=-1.0)
    np.testing.assert_array_equal(none, data.angles)  # a swing that clears is untouched


def test_level_line_reaches_a_tall_bodys_slow_step():
    """A 1.95 m body's level datasets start at a 0.67 m step (end interval 0.09 m); its
    0.8 m/s step is 0.54 m. The level line extrapolates 1.5 end intervals
    (``level_line_beyond``), so that step is a blend of the two shortest level datasets,
    not of the triangulation's stair datasets (with the former 0.6 it was)."""
    body = leg(1.95)
    interp = ElevInterp(config=ElevInterpConfig(heel_rise=False))
    steps = interp.source_steps(body)
    level = [i for i, d in enumerate(interp.datasets) if d.kind == "level"]
    a, b = sorted(level, key=lambda i: steps[i, 0])[:2]
    interval = steps[b, 0] - steps[a, 0]
    length = steps[a, 0] - 1.4 * interval
    out = interp.request(body, length, 0.0)
    assert out.converged[0] and not out.clamped[0]
    assert out.step_length[0] == pytest.approx(length, abs=1e-3)
    lo, hi = interp.datasets[a].angles, interp.datasets[b].angles
    f = np.sum((out.angles[0] - lo) * (hi - lo)) / np.sum((hi - lo) ** 2)
    assert f < -1.0  # beyond the shortest, by more than the former limit
    np.testing.assert_allclose(out.angles[0], lo + f * (hi - lo), atol=1e-9)
    short = ElevInterp(config=ElevInterpConfig(heel_rise=False, level_line_beyond=0.6))
    assert np.abs(short.request(body, length, 0.0).angles[0] - out.angles[0]).max() > 0.01


def test_level_steps_on_the_line_serve_the_requested_height():
    """On the level line the heel rise closes the step onto the floor, and that is what
    the request is served: height 0, not the line's own Eq. 10 height less the datum
    interpolated between the level datasets (1-3 mm apart along the line), which
    flagged a 1.75 m body's 0.79-0.80 m steps as missed and sent them to the clamped
    triangulation (landing 2-3 mm below the floor)."""
    body = leg(np.full(9, 1.75))
    length = np.linspace(0.62, 0.80, 9)
    out = ElevInterp().request(body, length, 0.0)
    assert out.converged.all() and not out.clamped.any()
    np.testing.assert_array_equal(out.target[:, 1], 0.0)
    np.testing.assert_allclose(out.step_height, 0.0, atol=0.2 * CM)


def test_long_level_steps_are_closed_by_the_trailing_knee():
    """Past a level step of about 0.81 m (1.75 m body) the trailing foot's rise is spent
    (capped, and the ankle near straight above the ball), so the step was served from the
    clamped triangulation 1.5-2 cm below the floor. The trailing knee closes the rest
    (``knee_closure``): the step lands on the floor, the knee at the other heel strike
    extends but never past straight, and steps the foot closes are left unchanged."""
    length = np.array([0.70, 0.85, 0.90, 0.93])
    body = leg(np.full(length.size, 1.75))
    foot_only = ElevInterp(config=ElevInterpConfig(knee_closure=False)).request(body, length,
                                                                                0.0)
    out = ElevInterp().request(body, length, 0.0)
    assert np.all(foot_only.clamped[1:]) and np.all(foot_only.step_height[1:] < -CM)
    assert out.converged.all() and not out.clamped.any()
    np.testing.assert_allclose(dataset_step(out.angles, body), np.stack(
        [length, np.zeros(length.size)], axis=1), atol=0.2 * CM)
    np.testing.assert_array_equal(out.angles[0], foot_only.angles[0])
    half = out.angles[:, 50]  # the stance leg at the other heel strike
    knee = half[:, 2] - half[:, 1]
    assert np.all(knee >= 0.0)
    # the data bend it more at longer steps (level_l 17°, natural 15°); closed, the longest
    # step has the straightest
    assert knee[-1] < knee[:-1].min()


def test_stair_closure_selects_the_shipped_stair_datasets():
    """``ElevInterpConfig.stair_closure``: "swing" (default) and "linear" (before gait11)
    put the stair corners of the region where their datasets' Eq. 10 steps are — a 1.75 m
    body's ascent corner at 0.45 m with the swing closure, 0.26 m with the linear one —
    and anything else is refused."""
    body = leg(1.75)
    swing = ElevInterp().source_steps(body)
    linear = ElevInterp(config=ElevInterpConfig(stair_closure="linear")).source_steps(body)
    np.testing.assert_array_equal(swing[:5], linear[:5])  # level datasets: the same
    assert swing[5, 0] > 0.4 > 0.3 > linear[5, 0]
    with pytest.raises(InputError, match=r"stair_closure"):
        ElevInterpConfig(stair_closure="cubic")


def test_low_rise_blend_is_continuous_at_level():
    """``ElevInterpConfig.low_rise_blend``: a rise of 1 mm changes the served dataset by
    next to nothing against the level step of the same length. Without it the level datum
    sends a 1 mm rise to the triangulation, whose short-step corner is spanned by the
    stair datasets: a 0.5 m step rising 1 mm got 22° different angles (a jump at SH = 0)."""
    body = leg(1.75)
    for length in (0.5, 0.55, 0.62, 0.7):
        out = ElevInterp().request(body, [length] * 3, [0.0, 0.001, -0.001])
        assert out.converged.all() and not out.clamped.any()
        np.testing.assert_allclose(out.step_height, [0.0, 0.001, -0.001], atol=2e-3)
        jump = np.rad2deg(np.abs(out.angles[1:] - out.angles[0]).max())
        assert jump < 2.0, (length, jump)


def test_level_line_kernel_is_the_numpy_code():
    """ElevInterp._level_line's compiled arithmetic (pose17) is the numpy code's, bitwise."""
    from crowdwalk.gait.elevinterp import _leg_of, _level_line_kernel

    rng = np.random.default_rng(17)
    interp = ElevInterp()
    props = np.array([0.245, 0.246, 0.0392, 0.0565, 0.0713]) / (0.245 + 0.246 + 0.0392)
    key = np.round(props / interp.config.shape_resolution).astype(np.int64)
    space = interp._space(key, props)
    level = interp._level[np.argsort(space.points[interp._level, 0])]
    k = 3000
    xs = space.points[level, 0]
    length = rng.uniform(xs[0] - 0.3, xs[-1] + 0.3, k)
    length[:len(xs)] = xs  # exactly a level dataset's length
    p = np.repeat(props[None], k, axis=0) * rng.uniform(0.97, 1.03, (k, 1))
    beyond = interp.config.level_line_beyond
    # ElevInterp._level_line before pose17
    j = np.clip(np.searchsorted(xs, length) - 1, 0, len(xs) - 2)
    lo, hi = xs[j], xs[j + 1]
    f = np.clip((length - lo) / (hi - lo), -beyond, 1.0 + beyond)
    keys = space.keys[level]
    for _ in range(3):
        kk = (1.0 - f)[:, None, None] * keys[j] + f[:, None, None] * keys[j + 1]
        step = step_of(kk[:, 0], kk[:, 1], _leg_of(p))
        f = np.clip(f + (length - step[:, 0]) / (hi - lo), -beyond, 1.0 + beyond)
    kk = (1.0 - f)[:, None, None] * keys[j] + f[:, None, None] * keys[j + 1]
    step = step_of(kk[:, 0], kk[:, 1], _leg_of(p))
    curves = ((1.0 - f)[:, None, None] * space.angles[level][j]
              + f[:, None, None] * space.angles[level][j + 1])
    phases = (1.0 - f)[:, None] * space.phases[level][j] + f[:, None] * space.phases[
        level][j + 1]
    got = _level_line_kernel(xs, np.ascontiguousarray(keys),
                             np.ascontiguousarray(space.angles[level]),
                             np.ascontiguousarray(space.phases[level]), length, p, beyond)
    for g, w in zip(got, (curves, phases, step), strict=True):
        assert g.shape == w.shape and np.array_equal(g, w)


def _numpy_clamp(hull: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """_ShapeSpace.clamp in numpy (ElevInterp before its kernel): targets moved just inside
    the counter-clockwise hull where outside."""
    a = hull
    b = np.roll(a, -1, axis=0)
    edge = b - a
    rel = target[:, None, :] - a[None]
    u = np.clip(np.einsum("khd,hd->kh", rel, edge) / np.einsum("hd,hd->h", edge, edge), 0, 1)
    proj = a[None] + u[..., None] * edge[None]
    dist = np.linalg.norm(target[:, None, :] - proj, axis=-1)
    # Inside a counter-clockwise convex polygon every edge has the point on its left.
    cross = edge[None, :, 0] * rel[..., 1] - edge[None, :, 1] * rel[..., 0]
    outside = np.any(cross < -1e-12 * np.linalg.norm(edge, axis=1), axis=1)
    nearest = proj[np.arange(len(target)), np.argmin(dist, axis=1)]
    centre = hull.mean(axis=0)
    nearest = nearest + 1e-9 * (centre - nearest)  # strictly inside
    return np.where(outside[:, None], nearest, target), outside


def test_clamp_kernel_is_the_numpy_code():
    """_ShapeSpace.clamp's compiled arithmetic (pose17) is the numpy code's, bitwise."""
    rng = np.random.default_rng(18)
    interp = ElevInterp()
    space = next(iter(interp._spaces.values()), None) or interp._space(
        np.array([1, 1, 1, 1, 1]), np.array([0.46, 0.46, 0.074, 0.107, 0.134]))
    lo, hi = space.hull.min(axis=0), space.hull.max(axis=0)
    target = rng.uniform(lo - 0.2 * (hi - lo), hi + 0.2 * (hi - lo), (5000, 2))
    target[:len(space.hull)] = space.hull  # on the vertices
    target[len(space.hull):2 * len(space.hull)] = 0.5 * (space.hull + np.roll(space.hull, -1, 0))
    got, want = space.clamp(target), _numpy_clamp(space.hull, target)
    assert 0 < want[1].sum() < len(target)  # inside and outside both
    for g, w in zip(got, want, strict=True):
        assert g.shape == w.shape and g.dtype == w.dtype and np.array_equal(g, w)
