"""ElevWalker (Sun & Metaxas 2001, §4): analytic single-DOF solve, foot–floor model,
Gauss–Newton joint complexes, curved locomotion, upper body."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.body import (
    JOINT,
    LEG_JOINTS,
    SUBTALAR_AXIS,
    TALOCRURAL_AXIS,
    Body,
    axis_angle_matrix,
    mirrored_axis,
)
from crowdwalk.gait.datasets import dataset_by_name, sample
from crowdwalk.gait.elevwalker import (
    GaitStyle,
    StanceFoot,
    WarmStart,
    elevwalker_pose,
    foot_points,
    leg_elevations,
    sagittal_elevation,
    solve_single_dof,
)

NATURAL = dataset_by_name("level_natural")


def _walk(heights, phase, heading=0.0, left=True, slope=0.0, style=None, warm=None,
          dataset=NATURAL, foothold=None):  # fmt: skip
    k = len(heights)
    body = Body.from_heights(heights)
    phase = np.broadcast_to(np.asarray(phase, float), (k,))
    psi = np.broadcast_to(np.asarray(heading, float), (k,))
    slope = np.broadcast_to(np.asarray(slope, float), (k,))
    foothold = np.zeros((k, 3)) if foothold is None else foothold
    foot = StanceFoot.from_foothold(body, foothold, psi, slope)
    pose = elevwalker_pose(
        body, np.full(k, left), phase, sample(dataset, phase), sample(dataset, phase + 0.5),
        psi, foot, np.full(k, np.radians(7.0)), warm or WarmStart.neutral(k), style,
    )  # fmt: skip
    return body, foot, pose


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(-1.2, 1.2), st.floats(-np.pi, np.pi))
def test_single_dof_solve_reaches_the_elevation_angle(seed, theta, heading):
    """Eqs. 2–7 with a skew axis: the returned angle gives exactly the elevation φ."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    parent = Rotation.from_euler("ZYX", [heading, *rng.uniform(-0.4, 0.4, 2)]).as_matrix()
    axis = TALOCRURAL_AXIS if seed % 2 else mirrored_axis(SUBTALAR_AXIS)
    w = np.array([0.0, 0.0, -1.0]) if seed % 3 else np.array([1.0, 0.0, 0.0])
    v = parent @ axis_angle_matrix(axis, np.array([theta]))[0] @ w
    psi = np.array([heading])
    phi = sagittal_elevation(v[None], psi)
    solved, ok = solve_single_dof(parent[None], axis, w, psi, phi)
    assert ok[0]
    v2 = parent @ axis_angle_matrix(axis, solved)[0] @ w
    assert sagittal_elevation(v2[None], psi)[0] == pytest.approx(phi[0], abs=1e-9)


def test_single_dof_reports_unreachable_elevations():
    # A hinge whose axis lies in the sagittal plane cannot tilt a segment along it.
    parent = np.eye(3)[None]
    axis = np.array([1.0, 0.0, 0.0])
    _, ok = solve_single_dof(parent, axis, np.array([0.0, 0.0, -1.0]), np.zeros(1),
                             np.array([0.5]))  # fmt: skip
    assert not ok[0]


@pytest.mark.parametrize("heading", [0.0, 0.7, -2.5])
def test_elevation_angles_of_the_poses_equal_the_data(heading):
    """Every segment's elevation measured on the skeleton equals the dataset (§4)."""
    heights = np.linspace(1.5, 1.95, 6)
    for phase in np.linspace(0.0, 0.49, 8):
        body, _, pose = _walk(heights, phase, heading)
        assert pose.converged.all()
        measured = leg_elevations(body, pose.positions, pose.rotations, np.full(6, heading))
        stance, swing = sample(NATURAL, np.full(6, phase)), sample(NATURAL, np.full(6, phase + .5))
        assert np.degrees(np.abs(measured[:, 0, :3] - stance[:, :3])).max() < 1e-3
        assert np.degrees(np.abs(measured[:, 1, :3] - swing[:, :3])).max() < 1e-3
        # the pelvis takes the mean of the two legs' pelvis curves: within 0.5°
        assert np.degrees(np.abs(measured[:, :, 3] - np.stack([stance, swing], 1)[:, :, 3])
                          ).max() < 0.5  # fmt: skip


@pytest.mark.parametrize("slope", [0.0, np.radians(8.0), np.radians(-8.0)])
def test_stance_foot_rolls_heel_flat_toe_without_sliding_or_penetrating(slope):
    """§4.1: the contact point is fixed (heel, then ball), the sole never goes below the
    ground plane, and the toes stay flat once the heel rises."""
    phases = np.linspace(0.0, 0.499, 60)
    heights = np.full(phases.size, 1.75)
    body, foot, pose = _walk(heights, phases, slope=slope)
    pts = foot_points(body, pose.positions, pose.rotations)[:, 0]  # left = stance
    heel, ball = foot.heel(body), foot.ball
    normal = np.array([-np.sin(slope), 0.0, np.cos(slope)])
    height_above = (pts - heel[:, None]) @ normal  # distance from the ground plane
    assert height_above.min() > -1e-9
    on_heel = np.abs(height_above[:, 0]) < 1e-9
    on_ball = np.abs(height_above[:, 1]) < 1e-9
    assert on_heel[0] and on_ball[-1] and (on_heel | on_ball).all()
    assert np.abs(pts[on_heel, 0] - heel[on_heel]).max() < 1e-9
    assert np.abs(pts[on_ball, 1] - ball[on_ball]).max() < 1e-9
    toes_flat = np.abs(height_above[on_ball & ~on_heel, 2]) < 1e-9
    assert toes_flat.all()


def test_gauss_newton_meets_stance_width_swing_width_and_toe_out():
    style = GaitStyle()
    phases = np.linspace(0.0, 0.49, 12)
    heights = np.full(phases.size, 1.8)
    body, _, pose = _walk(heights, phases, heading=0.3, left=False, style=style)
    assert pose.converged.all()
    n = np.array([-np.sin(0.3), np.cos(0.3), 0.0])
    st_leg, sw_leg = LEG_JOINTS[1], LEG_JOINTS[0]  # right stance, left swing
    half_hips = 0.5 * body.hip_separation
    sway = style.sway * body.height * np.sin(2 * np.pi * phases)
    half = 0.5 * style.step_width * body.height
    w_st = (pose.positions[:, st_leg[2]] - pose.positions[:, st_leg[0]]) @ n
    w_sw = (pose.positions[:, sw_leg[2]] - pose.positions[:, sw_leg[0]]) @ n
    assert np.allclose(w_st, -(half - half_hips - sway), atol=1e-6)  # Eq. 8
    assert np.allclose(w_sw, -(half_hips - half - sway), atol=1e-6)
    thigh_fwd = pose.rotations[:, sw_leg[0], :, 0]
    toe_out = np.arctan2(thigh_fwd @ n, thigh_fwd @ np.array([np.cos(0.3), np.sin(0.3), 0]))
    assert np.allclose(toe_out, np.radians(7.0), atol=1e-6)  # left foot out = +n


def test_joints_have_the_papers_degrees_of_freedom():
    """Knees and toes turn about their hinge only, ankles about Inman's skew axes."""
    _, _, pose = _walk(np.full(5, 1.7), np.linspace(0, 0.45, 5))
    for s, sign in ((0, 1.0), (1, -1.0)):
        for j in (LEG_JOINTS[s, 1], LEG_JOINTS[s, 4]):  # knee, metatarsal: about y
            r = pose.local[:, j]
            assert np.allclose(r[:, :, 1], [0, 1, 0], atol=1e-9)
        for j, axis in ((LEG_JOINTS[s, 2], TALOCRURAL_AXIS), (LEG_JOINTS[s, 3], SUBTALAR_AXIS)):
            a = axis if sign > 0 else mirrored_axis(axis)
            assert np.allclose(pose.local[:, j] @ a, a, atol=1e-9)  # the axis is fixed


def test_warm_start_converges_and_is_reused():
    k = 4
    body, _, first = _walk(np.full(k, 1.7), 0.2)
    _, _, second = _walk(np.full(k, 1.7), 0.21, warm=first.warm)
    assert second.converged.all()
    assert np.isfinite(second.warm.ankle_jacobian).all()
    assert np.abs(second.warm.hip - first.warm.hip).max() < 0.1


def test_non_convergence_is_flagged_not_hidden():
    style = GaitStyle(tolerance=1e-15, max_iterations=1)
    _, _, pose = _walk(np.full(3, 1.7), 0.3, style=style)
    assert not pose.converged.any()
    assert np.isfinite(pose.positions).all()


def test_curved_locomotion_turns_the_whole_figure_with_the_heading():
    """§4.4: the same data at heading ψ give the ψ = 0 pose rotated about the stance
    foot's contact (feet yawed with it)."""
    psi = 1.1
    body, _, straight = _walk(np.full(3, 1.7), [0.1, 0.25, 0.4], heading=0.0)
    _, _, turned = _walk(np.full(3, 1.7), [0.1, 0.25, 0.4], heading=psi)
    c, s = np.cos(psi), np.sin(psi)
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    assert np.allclose(straight.positions @ rz.T, turned.positions, atol=1e-6)


def test_upper_body_stays_upright_and_arms_swing_with_the_opposite_leg():
    phases = np.linspace(0, 0.49, 20)
    body, _, pose = _walk(np.full(phases.size, 1.75), phases)
    head_up = pose.rotations[:, JOINT["skullbase"], :, 2]
    assert np.allclose(head_up, [0, 0, 1], atol=1e-9)  # spine cancels tilt and list
    # left stance: the right (swing) thigh and the left arm move forward together
    left_arm = pose.positions[:, JOINT["l_elbow"], 0] - pose.positions[:, JOINT["l_shoulder"], 0]
    right_thigh = sample(NATURAL, phases + 0.5)[:, 2]
    assert np.corrcoef(left_arm, right_thigh)[0, 1] > 0.99


def test_pelvic_list_drops_the_swing_side():
    _, _, pose = _walk(np.full(1, 1.75), 0.2, left=True)
    hips = pose.positions[0, [JOINT["l_hip"], JOINT["r_hip"]], 2]
    assert hips[1] < hips[0]  # right (swing) hip lower


def test_trunk_follows_the_measured_rotation_with_attributes():
    """With KLAW attributes the trunk's yaw against the heading is shoulder_rotation times
    Schwartz 2008's thorax rotation shape (own side back at heel strike); with
    ``trunk_from_data=False`` it is the cosine, which differs by up to ~1 deg."""
    from crowdwalk.gait.datasets import trunk_motion
    from crowdwalk.style import Style

    n = 8
    phase = np.linspace(0.0, 0.45, n)
    body = Body.from_heights(np.full(n, 1.75))
    attrs = Style.default(body.height, 1.3)
    ds = NATURAL
    psi = np.zeros(n)
    foot = StanceFoot.from_foothold(body, np.zeros((n, 3)), psi, np.zeros(n))
    yaws = {}
    for data in (True, False):
        pose = elevwalker_pose(body, np.ones(n, bool), phase, sample(ds, phase),
                               sample(ds, phase + 0.5), psi, foot, np.full(n, 0.12),
                               WarmStart.neutral(n), GaitStyle(trunk_from_data=data),
                               attributes=attrs)
        trunk = pose.rotations[:, JOINT["vl5"]]
        yaws[data] = np.arctan2(trunk[:, 1, 0], trunk[:, 0, 0])
    want = -attrs.shoulder_rotation * trunk_motion().rotation_shape(phase)
    np.testing.assert_allclose(yaws[True], want, atol=np.deg2rad(0.2))
    assert np.abs(yaws[True] - yaws[False]).max() > np.deg2rad(0.5)


def test_a_stance_half_taken_gives_the_pose_solved_afresh():
    """``elevwalker_pose(..., stance=...)``: the stance half of a pose whose swing had
    other inputs (toe-out, ankle goal), for some of its rows, gives those rows' poses as
    they are solved afresh with the new swing inputs, bit for bit; and the swing's inputs
    do change the pose (so the half is not the whole)."""
    from crowdwalk.style import Style

    n = 12
    rng = np.random.default_rng(5)
    phase = rng.uniform(0.0, 0.49, n)
    body = Body.from_heights(rng.uniform(1.5, 1.9, n))
    attrs = Style.default(body.height, 1.3)
    psi = rng.uniform(-np.pi, np.pi, n)
    foot = StanceFoot.from_foothold(body, rng.normal(0.0, 1.0, (n, 3)), psi, np.zeros(n))
    left = rng.random(n) < 0.5
    offset = rng.normal(0.0, 0.02, (n, 3))

    def pose(rows, toe_out, goal, stance=None):
        b = body.take(rows)
        return elevwalker_pose(
            b, left[rows], phase[rows], sample(NATURAL, phase[rows]),
            sample(NATURAL, phase[rows] + 0.5), psi[rows],
            StanceFoot(foot.ball[rows], foot.yaw[rows], foot.slope[rows]), toe_out[rows],
            WarmStart.neutral(rows.size), GaitStyle(), stance_hip_offset=offset[rows],
            swing_goal=goal[rows], attributes=attrs.take(rows), stance=stance)  # fmt: skip

    everyone = np.arange(n)
    first = pose(everyone, np.full(n, 0.12), np.full((n, 3), np.nan))
    rows = np.array([1, 4, 5, 10])
    toe = rng.uniform(-0.3, 0.3, n)
    pinned = np.where(rng.random((n, 1)) < 0.5, first.positions[:, LEG_JOINTS[0, 2]] + 0.01,
                      np.nan)  # fmt: skip
    want = pose(rows, toe, pinned)
    got = pose(rows, toe, pinned, stance=first.stance.take(rows))
    for name in ("root_position", "root_rotation", "local", "positions", "rotations",
                 "contact", "converged", "solves"):  # fmt: skip
        assert np.array_equal(getattr(got, name), getattr(want, name)), name
    for name in ("ankle", "hip", "ankle_jacobian", "hip_jacobian"):
        assert np.array_equal(getattr(got.warm, name), getattr(want.warm, name), equal_nan=True)
    assert not np.array_equal(want.local, first.local[rows])


@pytest.mark.parametrize("styled", [True, False])
def test_a_walk_split_over_row_threads_is_the_walk_in_one(styled, monkeypatch):
    """elevwalker_pose's compiled passes on parts of the rows in row threads (the solves,
    and the joints, KLAW upper body, forward kinematics and finite check of _joint_rows)
    give one thread's poses bit for bit, and every part is used (the rows are split)."""
    import crowdwalk.gait.elevwalker as ew
    from crowdwalk.style import Style
    from crowdwalk.workers import RowThreads

    n = 700
    rng = np.random.default_rng(11)
    phase = rng.uniform(0.0, 0.49, n)
    body = Body.from_heights(rng.uniform(1.5, 1.9, n))
    attrs = Style.default(body.height, 1.3) if styled else None
    psi = rng.uniform(-np.pi, np.pi, n)
    foot = StanceFoot.from_foothold(body, rng.normal(0.0, 1.0, (n, 3)), psi, np.zeros(n))
    left = rng.random(n) < 0.5
    goal = np.where(rng.random((n, 1)) < 0.3, rng.normal(0.0, 1.0, (n, 3)), np.nan)
    toe_out, offset = rng.uniform(-0.2, 0.3, n), rng.normal(0.0, 0.01, (n, 3))

    def pose():
        return elevwalker_pose(
            body, left, phase, sample(NATURAL, phase), sample(NATURAL, phase + 0.5), psi, foot,
            toe_out, WarmStart.neutral(n), GaitStyle(), stance_hip_offset=offset,
            swing_goal=goal, attributes=attrs)  # fmt: skip

    parts = []
    joint_rows = ew._joint_rows

    def counted(*args):
        parts.append(len(args[2]))  # (after the two argument counts: the rows)
        return joint_rows(*args)

    monkeypatch.setattr(ew, "_joint_rows", counted)
    one, two = RowThreads(1), RowThreads(3)
    try:
        monkeypatch.setattr(ew, "row_threads", lambda: one)
        want = pose()
        monkeypatch.setattr(ew, "row_threads", lambda: two)
        got = pose()
    finally:
        one.close()
        two.close()
    assert sorted(parts) == [233, 233, 234, n]  # one call, then three parts
    for name in ("root_position", "root_rotation", "local", "positions", "rotations",
                 "contact", "converged", "solves"):  # fmt: skip
        assert np.array_equal(getattr(got, name), getattr(want, name)), name
    for name in ("ankle", "hip", "ankle_jacobian", "hip_jacobian"):
        assert np.array_equal(getattr(got.warm, name), getattr(want.warm, name), equal_nan=True)
    assert want.converged.sum() > n // 2


def test_exact_hip_offset_moves_the_root_by_the_offset_with_the_foot_turned_from_psi():
    """``GaitStyle.exact_hip_offset``: the stance hip's offset's sagittal IK assumes a leg in
    the plane of ψ; with the stance foot turned 50° from ψ (a turn after a stand) the root
    moves by the requested offset along ψ and vertically (nearer it) with the switch; a
    foot along ψ with a small offset keeps the single IK's pose bit for bit."""
    n = 5
    phase = np.array([0.3, 0.35, 0.4, 0.45, 0.4])
    body = Body.from_heights(np.full(n, 1.75))
    psi = np.zeros(n)
    turn = np.radians([50.0, -50.0, 50.0, 50.0, 7.0])
    foot = StanceFoot.from_foothold(body, np.zeros((n, 3)), psi + turn, np.zeros(n))
    offset = np.array([[0.0, 0.0, -0.04], [0.0, 0.0, -0.04], [0.015, 0.015, -0.036],
                       [0.0, 0.0, -0.03], [0.005, 0.0, -0.005]])

    def root(style, off):
        return elevwalker_pose(
            body, np.ones(n, bool), phase, sample(NATURAL, phase), sample(NATURAL, phase + 0.5),
            psi, foot, np.full(n, np.radians(7.0)), WarmStart.neutral(n), style,
            stance_hip_offset=off)  # fmt: skip

    free = root(GaitStyle(), None).root_position
    plain, exact = root(GaitStyle(), offset), root(GaitStyle(exact_hip_offset=True), offset)
    assert plain.converged.all() and exact.converged.all()

    def miss(pose):  # along ψ (x here) and vertical [m]
        shift = pose.root_position - free
        return np.abs(shift - offset)[:, [0, 2]].max(axis=1)

    # the single IK misses by several times the offset; four secant solves do not
    # always converge late in stance (rows 2, 3), but cut the miss to under a quarter
    assert np.all(miss(plain)[:4] > 0.05)
    assert np.all(miss(exact)[:2] < 0.005)
    assert np.all(miss(exact)[:4] < 0.25 * miss(plain)[:4])
    assert np.array_equal(exact.positions[4], plain.positions[4])
