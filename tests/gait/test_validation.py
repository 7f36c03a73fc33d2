"""Validation against measured data and physical constraints (issue 4, item 8).

- generated hip, knee, ankle flexion over a level cycle vs Winter (1991) natural cadence;
- elevation angles recomputed from generated poses equal the dataset's within 0.5°;
- stance-foot drift < 1 mm per frame and ground penetration < 5 mm on flat ground, an 8°
  slope and stairs (the stairs driven with the planners' own collision-free swing Bezier);
- the same datasets drive bodies from 1.50 to 1.95 m; step length scales with leg length;
- the swing foot clears the stair nosings.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from crowdwalk.body import LEG_JOINTS, Body, forward_kinematics, quaternion_to_matrix
from crowdwalk.gait.animator import Animator, StepCommand
from crowdwalk.gait.datasets import dataset_by_name, sample
from crowdwalk.gait.elevwalker import (
    StanceFoot,
    WarmStart,
    elevwalker_pose,
    foot_points,
    leg_elevations,
)
from crowdwalk.gait.metagait import animate_paths

SHARED = Path(__file__).resolve().parents[2] / ".." / "shared"
WINTER = SHARED / "data" / "gait" / "winter1991_slow_natural_fast_cadence.xlsx"
SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "gait_validation_report.py"
HEIGHTS = np.array([1.50, 1.65, 1.80, 1.95])
FPS = 50.0
RISER, TREAD, FIRST_RISER = 0.15, 0.32, 1.0


def _flat(xy):
    return np.zeros(len(xy))


def _slope(xy):
    return np.tan(np.radians(8.0)) * xy[:, 0]


def _stairs(xy):
    steps = np.floor((xy[:, 0] - FIRST_RISER) / TREAD) + 1.0
    return RISER * np.clip(steps, 0.0, 6.0)


def _measure(body: Body, frames, ground, animator):
    """Worst stance-foot drift per frame [m] (contact points of the foot that carries the
    root), worst penetration [m], swing clearance over the ground [m] (min over frames of
    the airborne foot's lowest point), fallbacks."""
    drift = penetration = 0.0
    clearance = np.inf
    previous = None
    for frame in frames:
        stance = np.column_stack([frame.stance_left, ~frame.stance_left])
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        pts = foot_points(body, frame.positions, rot)  # (k, 2, 3, 3)
        gap = pts[..., 2] - ground(pts[..., :2].reshape(-1, 2)).reshape(pts.shape[:-1])
        penetration = max(penetration, float(-gap.min()))
        airborne = ~frame.contact  # (k, 2)
        if airborne.any():
            clearance = min(clearance, float(gap[airborne].min()))
        on_ground = np.abs(gap) < 5e-4
        if previous is not None:
            same = stance & previous[2]
            both = on_ground & previous[1] & same[:, :, None]
            moved = np.linalg.norm(pts[..., :2] - previous[0][..., :2], axis=-1)
            if both.any():
                drift = max(drift, float(moved[both].max()))
        previous = (pts, on_ground, stance)
    fallbacks = int(sum(f.fallback.sum() for f in frames))
    return drift, penetration, clearance, fallbacks


@pytest.fixture(scope="module")
def flat_walk():
    body = Body.from_heights(HEIGHTS)
    animator = Animator(body, ground=_flat)
    paths = np.tile(np.array([[[0.0, 0.0], [40.0, 0.0]]]), (HEIGHTS.size, 1, 1))
    return body, animate_paths(body, paths, _flat, 1.3, 3.0, FPS, animator=animator), animator


@pytest.fixture(scope="module")
def slope_walk():
    body = Body.from_heights(HEIGHTS[[0, 3]])
    animator = Animator(body, ground=_slope)
    paths = np.tile(np.array([[[0.0, 0.0], [30.0, 4.0]]]), (2, 1, 1))
    return body, animate_paths(body, paths, _slope, 1.2, 3.0, FPS, animator=animator), animator


@pytest.fixture(scope="module")
def stairs_walk():
    """A 1.75 m walker climbs six 15 cm risers, one tread per step, swing curves from
    planners.swing.adjust_swings (§5.2 of Chen & Li) on the stair profile."""
    from planners.config import PlannerConfig
    from planners.leg import Leg
    from planners.profile import GroundProfile
    from planners.swing import adjust_swings

    body = Body.from_heights([1.75])
    heel, toe = float(body.heel_offset[0]), float(body.toe_offset[0])
    footholds = [FIRST_RISER - toe - 0.03, FIRST_RISER - toe - 0.03 - 0.3]  # right, left
    for i in range(6):
        footholds.append(FIRST_RISER + i * TREAD + heel + 0.02)
    xs = np.array(footholds)
    order = np.argsort(xs)
    xs = xs[order]
    z = _stairs(np.column_stack([xs, np.zeros_like(xs)]))
    edges = FIRST_RISER + TREAD * np.arange(7)
    s = np.concatenate([[-2.0], np.repeat(edges, 2), [10.0]])
    zz = np.concatenate([[0.0], np.ravel(np.column_stack([RISER * np.arange(7),
                                                          RISER * np.arange(1, 8)])), [0.0]])
    zz[-2:] = RISER * 6  # top landing
    profile = GroundProfile(s, np.minimum(zz, RISER * 6))
    leg = Leg(float(body.thigh[0]), float(body.shank[0]), float(body.foot_length[0]), heel, toe,
              float(body.ankle_height[0]))  # fmt: skip
    animator = Animator(body, ground=_stairs)
    frames, t, duration = [], 0.0, 0.6
    lateral = [0.044, -0.044]
    for step in range(1, len(xs) - 1):
        stance, target, back = xs[step], xs[step + 1], xs[step - 1]
        swing = adjust_swings([back], [z[step - 1]], [target], [z[step + 1]], profile, leg,
                              PlannerConfig())  # fmt: skip
        ctrl = swing.controls[0]
        swing_side = (step + 1) % 2  # alternate feet
        y_swing = lateral[swing_side]
        bezier = np.column_stack([ctrl[:, 0], np.full(4, y_swing), ctrl[:, 1]])[None]
        cmd = StepCommand(
            agent=np.array([0]), time=[t], duration=[duration], swing_foot=[swing_side],
            start=[[stance, lateral[1 - swing_side], z[step]]],
            target=[[target, y_swing, z[step + 1]]], heading=[0.0],
            step_length=[target - stance], step_height=[z[step + 1] - z[step]],
            swing_bezier=bezier,
        )  # fmt: skip
        animator.command(cmd)
        for f in range(int(round(duration * FPS))):
            frames.append(animator.pose(t + f / FPS))
        t += duration
    return body, frames, animator


@pytest.mark.skipif(not WINTER.exists(), reason="measured gait data (../shared) not found")
def test_joint_flexion_matches_winter_natural_cadence():
    """Measured 1.75 m body, level_natural dataset: hip r = 0.998 (RMS 3.8°), knee
    r = 0.995 (RMS 2.1°), ankle r = 0.945 (RMS 5.4°, 4.7° of it a constant offset)."""
    spec = importlib.util.spec_from_file_location("gait_validation_report", SCRIPT)
    report = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(report)
    metrics = report.compare(report.generated_flexion(1.75), report.load_winter(WINTER))
    assert metrics["Hip"]["correlation"] > 0.99 and metrics["Hip"]["rms"] < 5.0
    assert metrics["Knee"]["correlation"] > 0.99 and metrics["Knee"]["rms"] < 3.5
    assert metrics["Ankle"]["correlation"] > 0.9 and metrics["Ankle"]["rms_centred"] < 4.0


@pytest.mark.parametrize("name", ["level_xs", "level_natural", "level_l", "stairs_up",
                                  "stairs_down"])  # fmt: skip
def test_elevation_angles_from_poses_equal_the_dataset(name):
    data = dataset_by_name(name)
    k = 24
    t = np.linspace(0.0, 0.49, k)
    body = Body.from_heights(np.linspace(1.5, 1.95, k))
    psi = np.linspace(-3.0, 3.0, k)
    foot = StanceFoot.from_foothold(body, np.zeros((k, 3)), psi, np.zeros(k))
    st, sw = sample(data, t), sample(data, t + 0.5)
    pose = elevwalker_pose(body, t < 0.25, t, st, sw, psi, foot, np.full(k, 0.1),
                           WarmStart.neutral(k))  # fmt: skip
    assert pose.converged.all()
    measured = leg_elevations(body, pose.positions, pose.rotations, psi)
    stance_leg = np.where(t < 0.25, 0, 1)
    rows = np.arange(k)
    err_st = np.abs(measured[rows, stance_leg] - st)
    err_sw = np.abs(measured[rows, 1 - stance_leg] - sw)
    # foot, shank, thigh of both legs: exact (well within 0.5°)
    assert np.degrees(max(err_st[:, :3].max(), err_sw[:, :3].max())) < 1e-3
    # one rigid pelvis takes the mean of the two legs' pelvis curves; the datasets are
    # half-stride symmetric within 1° on level ground, not on stairs (Bovi 2011 means)
    asymmetry = np.abs(st[:, 3] - sw[:, 3])
    assert np.allclose(measured[rows, stance_leg, 3], 0.5 * (st[:, 3] + sw[:, 3]), atol=1e-9)
    assert np.all(err_st[:, 3] <= 0.5 * asymmetry + 1e-9)
    if not name.startswith("stairs"):
        assert np.degrees(max(err_st[:, 3].max(), err_sw[:, 3].max())) < 0.5


def test_animated_legs_follow_the_dataset():
    """With the Animator's corrections (root continuity over the first half of a step,
    the trailing foot kept on the ground until toe-off, the landing on the commanded
    foothold) the stance leg equals the data within 0.5° once the root has rejoined it;
    mid-swing the swing leg is within 2.5° (measured: up to 2.1°; ElevWalker alone is
    exact, see test_elevation_angles_from_poses_equal_the_dataset)."""
    body = Body.from_heights(HEIGHTS)
    animator = Animator(body, ground=_flat)
    paths = np.tile(np.array([[[0.0, 0.0], [40.0, 0.0]]]), (HEIGHTS.size, 1, 1))
    worst = {"stance": 0.0, "swing": 0.0}

    def check(frame, animator):
        st, sw, left, phase = animator.followed_angles(frame.time, frame.agents)
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        measured = leg_elevations(body, frame.positions, rot, np.zeros(len(body)))
        rows = np.arange(len(body))
        side = np.where(left, 0, 1)
        late = phase >= 0.25
        mid = (phase > 0.15) & (phase < 0.35)
        e_st = np.degrees(np.abs(measured[rows, side, :3] - st[:, :3]).max(axis=1))
        e_sw = np.degrees(np.abs(measured[rows, 1 - side, :3] - sw[:, :3]).max(axis=1))
        worst["stance"] = max(worst["stance"], float(e_st[late].max(initial=0.0)))
        worst["swing"] = max(worst["swing"], float(e_sw[mid].max(initial=0.0)))
        worst["checked"] = worst.get("checked", 0) + int(late.sum() + mid.sum())

    animate_paths(body, paths, _flat, 1.3, 2.5, FPS, animator=animator, on_frame=check)
    assert worst["checked"] > 100
    worst_stance, worst_swing = worst["stance"], worst["swing"]
    assert worst_stance < 0.5
    assert worst_swing < 2.5


@pytest.mark.parametrize("walk", ["flat_walk", "slope_walk", "stairs_walk"])
def test_no_sliding_and_no_penetration(walk, request):
    body, frames, animator = request.getfixturevalue(walk)
    ground = {"flat_walk": _flat, "slope_walk": _slope, "stairs_walk": _stairs}[walk]
    drift, penetration, _, fallbacks = _measure(body, frames, ground, animator)
    assert drift < 1e-3  # per frame, contact points of the stance foot
    assert penetration < 5e-3
    assert fallbacks == 0
    assert all(np.isfinite(f.positions).all() for f in frames)


def test_swing_foot_clears_the_stair_nosings(stairs_walk):
    body, frames, animator = stairs_walk
    _, penetration, clearance, _ = _measure(body, frames, _stairs, animator)
    assert clearance > -1e-3  # the airborne swing foot never goes into a step
    assert penetration < 5e-3
    # the foot actually rose by the riser each step (it is on the top tread at the end)
    final = frames[-1].positions[0, :, 2].min()
    assert final > 5 * RISER - 0.01


def test_stair_swing_knee_follows_the_stair_data(stairs_walk):
    """Issue 11 item 5 (knee flexion on stairs within 10° of the stair curves): given the
    planner's swing Bezier, as the crowd gives it, the swing knee (thigh − shank, either
    leg) over the flight flexes at most 10° beyond the stair dataset's own swing peak
    (86°; measured 91°). Following the Bezier (``GaitStyle(lift_swing=False)``, control
    points 15 cm above the chord) flexed it to 111°."""
    body, frames, animator = stairs_walk
    assert animator.stats["bezier_steps"] == 0 and animator.stats["lift_steps"] > 0
    pos = np.array([f.positions[0] for f in frames])
    knee = []
    for side in (0, 1):
        hip, kn, ankle = (pos[:, LEG_JOINTS[side, j]] for j in range(3))
        thigh = np.arctan2((kn - hip)[:, 0], -(kn - hip)[:, 2])
        shank = np.arctan2((ankle - kn)[:, 0], -(ankle - kn)[:, 2])
        knee.append(np.rad2deg(thigh - shank))
    data = dataset_by_name("stairs_up")
    peak = np.rad2deg(data.angles[:, 2] - data.angles[:, 1]).max()
    assert np.max(knee) < peak + 10.0


def test_same_datasets_drive_all_body_sizes_and_step_length_scales_with_leg(flat_walk):
    """Sun & Metaxas 2001 §7: elevation data are size invariant. One dataset, four bodies:
    the step each produces, divided by its leg length, is the same (within 1 %)."""
    data = dataset_by_name("level_natural")
    body = Body.from_heights(HEIGHTS)
    k = HEIGHTS.size
    end = np.full(k, 0.5 - 1e-6)
    foot = StanceFoot.from_foothold(body, np.zeros((k, 3)), np.zeros(k), np.zeros(k))
    pose = elevwalker_pose(body, np.ones(k, bool), end, sample(data, end),
                           sample(data, end + 0.5), np.zeros(k), foot, np.zeros(k),
                           WarmStart.neutral(k))  # fmt: skip
    heel = foot_points(body, pose.positions, pose.rotations)[:, 1, 0]  # right heel lands
    step = heel[:, 0] + body.heel_offset
    ratio = step / body.leg_length
    assert np.ptp(ratio) / ratio.mean() < 0.01
    # and the animated crowd of four sizes walks without a single fallback
    _, frames, _ = flat_walk
    assert not any(f.fallback.any() for f in frames)
    travelled = frames[-1].root_position[:, 0] - frames[0].root_position[:, 0]
    assert np.all(np.diff(travelled) > -0.05)  # taller bodies are not slower


def test_trailing_foot_stays_on_the_ground_until_toe_off(flat_walk):
    """In double support the trailing foot rolls on the ground where it stood (ball, then
    toe tip) instead of lifting early; the contact flag says so. Where the data's hip is
    too far for the toe-tip pivot the foot gives way slightly (measured: at most 1.6 mm
    per 20 ms frame). An agent's first step has no trailing foot and is skipped."""
    body, frames, _ = flat_walk
    previous = None
    worst_slip = worst_height = 0.0
    for frame in frames[40:]:
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        pts = foot_points(body, frame.positions, rot)
        trailing = np.column_stack([~frame.stance_left, frame.stance_left]) & frame.contact
        tips = pts[:, :, 2]  # toe tips (k, 2, 3)
        if previous is not None:
            both = trailing & previous[1]
            if both.any():
                slip = np.linalg.norm(tips[..., :2] - previous[0][..., :2], axis=-1)
                worst_slip = max(worst_slip, float(slip[both].max()))
                worst_height = max(worst_height, float(np.abs(tips[..., 2])[both].max()))
        previous = (tips, trailing)
    assert worst_slip < 3e-3  # the toe tip barely slides
    assert worst_height < 2e-3  # and stays on the ground
