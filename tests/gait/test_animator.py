"""The Animator contract (docs/architecture.md, "crowdwalk.gait"): step commands in,
batched poses out; swing clearance over obstacles; robustness (fallback, no NaN)."""

from __future__ import annotations

import numpy as np
import pytest

from crowdwalk.body import (
    JOINT_NAMES,
    LEG_JOINTS,
    PARENTS,
    Body,
    forward_kinematics,
    quaternion_to_matrix,
)
from crowdwalk.errors import InputError
from crowdwalk.gait.animator import Animator, StepCommand
from crowdwalk.gait.elevwalker import GaitStyle, foot_points
from crowdwalk.style import Style

BLOCK = (0.30, 0.45, 0.10)  # x from, x to, height [m]


def _flat(xy):
    return np.zeros(len(xy))


def _block(xy):
    inside = (xy[:, 0] > BLOCK[0]) & (xy[:, 0] < BLOCK[1])
    return np.where(inside, BLOCK[2], 0.0)


def _command(agents, t, swing_foot, start, target, bezier=None, duration=0.6, heading=0.0):
    m = len(agents)
    start, target = np.asarray(start, float), np.asarray(target, float)
    d = target - start
    along = d[:, 0] * np.cos(heading) + d[:, 1] * np.sin(heading)
    return StepCommand(
        agent=np.asarray(agents), time=np.full(m, t), duration=np.full(m, duration),
        swing_foot=np.full(m, swing_foot), start=start, target=target,
        heading=np.full(m, heading), step_length=along, step_height=d[:, 2],
        swing_bezier=bezier,
    )  # fmt: skip


def _straight(animator, k, steps=3, sl=0.65, fps=50.0, start_y=0.045):
    frames = []
    for s in range(steps):
        left_stance = s % 2 == 0
        y = start_y if left_stance else -start_y
        start = np.column_stack([np.full(k, s * sl), np.full(k, y), np.zeros(k)])
        target = np.column_stack([np.full(k, (s + 1) * sl), np.full(k, -y), np.zeros(k)])
        animator.command(_command(np.arange(k), s * 0.6, 1 if left_stance else 0, start,
                                  target))  # fmt: skip
        for f in range(30):
            frames.append(animator.pose(s * 0.6 + f / fps))
    return frames


def test_pose_frame_contract():
    body = Body.from_heights([1.6, 1.8, 1.9])
    animator = Animator(body, ground=_flat)
    frames = _straight(animator, 3, steps=2)
    frame = frames[-1]
    k, nj = 3, len(JOINT_NAMES)
    assert frame.root_position.shape == (k, 3) and frame.root_quaternion.shape == (k, 4)
    assert frame.joints.shape == (k, nj, 4) and frame.positions.shape == (k, nj, 3)
    assert frame.contact.shape == (k, 2) and frame.fallback.shape == (k,)
    assert np.allclose(np.linalg.norm(frame.joints, axis=2), 1.0)
    assert np.allclose(frame.joints[:, 0], frame.root_quaternion)
    names, parents = animator.skeleton
    assert tuple(names) == JOINT_NAMES and np.array_equal(parents, PARENTS)
    # the quaternions reproduce the positions through forward kinematics
    positions, _ = forward_kinematics(body, frame.root_position,
                                      quaternion_to_matrix(frame.root_quaternion),
                                      quaternion_to_matrix(frame.joints))  # fmt: skip
    assert np.allclose(positions, frame.positions, atol=1e-9)
    # subsets of agents, any order
    sub = animator.pose(frame.time, np.array([2, 0]))
    assert np.array_equal(sub.agents, [2, 0])


def test_feet_land_on_the_commanded_footholds_and_the_root_moves_smoothly():
    body = Body.from_heights([1.75])
    animator = Animator(body, ground=_flat)
    frames = _straight(animator, 1, steps=4)
    for frame in frames[30::30]:  # first frame of each later step: the new stance foot
        side = 0 if frame.stance_left[0] else 1
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        heel = foot_points(body, frame.positions, rot)[0, side, 0]
        step = round(frame.time / 0.6)
        expected_x = step * 0.65 - body.heel_offset[0]
        assert heel[0] == pytest.approx(expected_x, abs=0.01)  # heel strike at the foothold
        assert heel[2] == pytest.approx(0.0, abs=1e-6)
    roots = np.array([f.root_position[0] for f in frames])
    speed = np.linalg.norm(np.diff(roots, axis=0), axis=1) * 50.0
    assert speed.max() < 2.0 * speed.mean()  # no pops at the step changes


def test_swing_follows_the_planner_bezier_over_a_block():
    """Item 6: a block between the footholds that the data-driven foot would hit
    (``lift_swing`` off: the planner's Bezier)."""
    body = Body.from_heights([1.75])
    animator = Animator(body, ground=_block, style=GaitStyle(lift_swing=False))
    a = float(body.ankle_height[0])
    start, target = np.array([[0.0, 0.045, 0.0]]), np.array([[0.75, -0.045, 0.0]])
    # the trailing (right) foot starts behind the stance foot
    animator.command(_command([0], -0.6, 1, [[-0.75, 0.045, 0.0]], [[0.0, -0.045, 0.0]]))
    bezier = np.array([[[-0.0, -0.045, a], [0.15, -0.045, a + 0.3], [0.6, -0.045, a + 0.3],
                        [0.75, -0.045, a]]])  # fmt: skip
    bezier[0, 0, 0] = 0.0
    animator.command(_command([0], 0.0, 1, start, target, bezier=bezier))
    assert animator.stats["bezier_steps"] == 1
    lowest = np.inf
    for f in range(30):
        frame = animator.pose(f / 50.0)
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        swing = foot_points(body, frame.positions, rot)[0, 1]
        gap = swing[:, 2] - _block(swing[:, :2])
        lowest = min(lowest, gap.min())
    assert lowest > -1e-3



def test_lift_swing_clears_a_block_from_the_data():
    """``GaitStyle.lift_swing`` (default): over the block the swing follows the data,
    raised by the anticipated lift, not the planner's Bezier; the sole stays above the
    block and the ankle peaks far below the Bezier's (30 cm control points)."""
    body = Body.from_heights([1.75])
    animator = Animator(body, ground=_block)
    a = float(body.ankle_height[0])
    animator.command(_command([0], -0.6, 1, [[-0.75, 0.045, 0.0]], [[0.0, -0.045, 0.0]]))
    bezier = np.array([[[0.0, -0.045, a], [0.15, -0.045, a + 0.3], [0.6, -0.045, a + 0.3],
                        [0.75, -0.045, a]]])  # fmt: skip
    animator.command(_command([0], 0.0, 1, [[0.0, 0.045, 0.0]], [[0.75, -0.045, 0.0]],
                              bezier=bezier))  # fmt: skip
    assert animator.stats["bezier_steps"] == 0 and animator.stats["lift_steps"] == 1
    lowest, top = np.inf, -np.inf
    for f in range(30):
        frame = animator.pose(f / 50.0)
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        swing = foot_points(body, frame.positions, rot)[0, 1]
        lowest = min(lowest, (swing[:, 2] - _block(swing[:, :2])).min())
        top = max(top, frame.positions[0, LEG_JOINTS[1, 2], 2])
    assert lowest > -1e-3
    assert top < a + 0.75 * 0.3  # the Bezier's summit


def test_the_swing_joins_the_planner_bezier_without_a_jump():
    """The swing ankle blends onto the Bezier (30 cm over a block) over half the swing and
    off it over the last 0.3 (issue 11 item 5): at 25 fps its second difference stays
    under 15 cm (a blend over 0.15 of the step, two frames, made 36 cm); ``lift_swing``
    off (the default follows the data, lifted)."""
    body = Body.from_heights([1.75])
    animator = Animator(body, ground=_block, style=GaitStyle(lift_swing=False))
    a = float(body.ankle_height[0])
    animator.command(_command([0], -0.6, 1, [[-0.75, 0.045, 0.0]], [[0.0, -0.045, 0.0]]))
    bezier = np.array([[[0.0, -0.045, a], [0.15, -0.045, a + 0.3], [0.6, -0.045, a + 0.3],
                        [0.75, -0.045, a]]])  # fmt: skip
    animator.command(_command([0], 0.0, 1, [[0.0, 0.045, 0.0]], [[0.75, -0.045, 0.0]],
                              bezier=bezier))  # fmt: skip
    ankle = np.array([animator.pose(f / 25.0).positions[0, LEG_JOINTS[1, 2]]
                      for f in range(16)])  # fmt: skip
    d2 = np.linalg.norm(ankle[2:] - 2 * ankle[1:-1] + ankle[:-2], axis=1)
    assert animator.stats["bezier_steps"] == 1
    assert d2.max() < 0.15

def test_non_converged_solves_fall_back_to_the_previous_pose_and_are_flagged():
    body = Body.from_heights([1.7, 1.7])
    animator = Animator(body, ground=_flat)
    frames = _straight(animator, 2, steps=1)
    before = frames[-1]
    animator.style = GaitStyle(tolerance=1e-15, max_iterations=1)  # cannot converge
    after = animator.pose(before.time + 0.02)
    assert after.fallback.all()
    assert np.array_equal(after.positions, before.positions)
    assert animator.stats["fallbacks"] == 2


def test_no_nan_reaches_the_output_even_from_broken_data():
    body = Body.from_heights([1.7, 1.8])
    animator = Animator(body, ground=_flat)
    frames = _straight(animator, 2, steps=1)
    animator._step.angles[1] = np.nan  # simulate a corrupted dataset for agent 1
    frame = animator.pose(frames[-1].time + 0.02)
    assert frame.fallback.tolist() == [False, True]
    for field in ("root_position", "root_quaternion", "joints", "positions"):
        assert np.isfinite(getattr(frame, field)).all()


def test_bad_commands_and_requests_are_rejected_with_clear_messages():
    body = Body.from_heights([1.7])
    animator = Animator(body)
    good = dict(agent=[0], time=[0.0], duration=[0.5], swing_foot=[1], start=[[0, 0, 0]],
                target=[[0.6, 0, 0]], heading=[0.0], step_length=[0.6], step_height=[0.0])
    with pytest.raises(InputError, match=r"^StepCommand\.duration must be > 0 \[s\]; got"):
        StepCommand(**{**good, "duration": [0.0]})
    with pytest.raises(InputError, match=r"^StepCommand\.swing_foot must be"):
        StepCommand(**{**good, "swing_foot": [2]})
    with pytest.raises(InputError, match=r"^StepCommand\.agent must be indices"):
        animator.command(StepCommand(**{**good, "agent": [3]}))
    with pytest.raises(InputError, match=r"^Animator\.agents must be agents that received"):
        animator.pose(0.0)
    with pytest.raises(InputError, match=r"^Animator\.body must be"):
        Animator("not a body")


def test_heading_change_turns_the_walker_smoothly_without_fallbacks():
    body = Body.from_heights([1.75])
    animator = Animator(body, ground=_flat)
    pos = np.array([0.0, 0.045, 0.0])
    heading = 0.0
    frames = []
    for s in range(6):
        heading += np.radians(25.0)
        d = np.array([np.cos(heading), np.sin(heading), 0.0])
        n = np.array([-d[1], d[0], 0.0])
        side = 1 if s % 2 == 0 else -1
        target = pos + 0.6 * d - side * 0.09 * n
        animator.command(_command([0], s * 0.6, 1 if s % 2 == 0 else 0, [pos], [target],
                                  heading=heading))  # fmt: skip
        for f in range(30):
            frames.append(animator.pose(s * 0.6 + f / 50.0))
        pos = target
    assert not any(f.fallback.any() for f in frames)
    yaw = [np.arctan2(*quaternion_to_matrix(f.root_quaternion)[0][:, 0][1::-1]) for f in frames]
    assert np.abs(np.diff(np.unwrap(yaw))).max() < np.radians(5.0)


def test_a_foot_placed_against_a_curb_rests_on_its_edge_instead_of_entering_it():
    """An unplanned walker may put its foot so close to a 15 cm curb that the toes would
    be inside it: the sole tilts up onto the edge, nothing goes below the ground."""
    body = Body.from_heights([1.75])
    toe = float(body.toe_offset[0])

    def curb(xy):
        return np.where(xy[:, 0] > 0.65 + toe - 0.03, 0.15, 0.0)

    animator = Animator(body, ground=curb)
    animator.command(_command([0], 0.0, 1, [[0.0, 0.045, 0.0]], [[0.65, -0.045, 0.0]]))
    animator.command(_command([0], 0.6, 0, [[0.65, -0.045, 0.0]], [[1.2, 0.045, 0.15]]))
    worst = 0.0
    for f in range(30):
        frame = animator.pose(0.6 + f / 50.0)
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        stance = foot_points(body, frame.positions, rot)[0, 1]  # right foot
        worst = max(worst, float((curb(stance[:, :2]) - stance[:, 2]).max()))
    assert worst < 5e-3


def test_sharp_corners_spin_on_the_stance_foot_without_fallbacks():
    """A 90° corner (MetaGait §6.1 toe-out and spin turns, plus the Animator's own spin
    when a command twists the stance hip by more than 30°)."""
    from crowdwalk.gait.metagait import animate_paths

    body = Body.from_heights([1.6, 1.9])
    paths = np.tile(np.array([[[0.0, 0.0], [2.0, 0.0], [2.0, 6.0]]]), (2, 1, 1))
    animator = Animator(body, ground=_flat)
    seen = {"spin": 0.0, "toe_out": 0.0}

    def watch(frame, animator):
        seen["spin"] = max(seen["spin"], float(np.abs(animator._stance.spin).max()))
        seen["toe_out"] = max(seen["toe_out"], float(np.abs(animator._stance.toe_out).max()))

    frames = animate_paths(body, paths, _flat, 1.2, 5.0, 25.0, animator=animator,
                           on_frame=watch)  # fmt: skip
    assert not any(f.fallback.any() for f in frames)
    assert seen["spin"] > np.radians(5.0) or seen["toe_out"] > np.radians(15.0)
    end = frames[-1].root_position
    assert np.all(np.abs(end[:, 0] - 2.0) < 0.3) and np.all(end[:, 1] > 2.0)  # turned north
    yaw = [np.arctan2(*quaternion_to_matrix(f.root_quaternion)[:, :, 0][:, 1::-1].T)
           for f in frames]  # fmt: skip
    assert np.abs(np.diff(np.unwrap(np.array(yaw), axis=0), axis=0)).max() < np.radians(15)


def _sole_depth(body, frame, ground, foot):
    """Deepest point [m] of one foot's sole (heel → ball → toe tip, 2 mm apart) below
    ``ground`` (a step function: dense samples find its edges)."""
    rot = forward_kinematics(body, frame.root_position,
                             quaternion_to_matrix(frame.root_quaternion),
                             quaternion_to_matrix(frame.joints))[1]  # fmt: skip
    heel, ball, tip = foot_points(body, frame.positions, rot)[0, foot]
    u = np.linspace(0.0, 1.0, 101)[:, None]
    sole = np.concatenate([heel + u * (ball - heel), ball + u * (tip - ball)])
    return float((ground(sole[:, :2]) - sole[:, 2]).max())


@pytest.mark.parametrize("case", ["curb up", "threshold"])
def test_unplanned_swing_sole_never_enters_a_curb_or_a_threshold(case):
    """Crowd steps the planner did not plan (shortened, positioning: no Bezier) whose
    trailing foot swings up a 15 cm curb, or over a 10 cm threshold between two level
    footholds: no point of the swing sole (heel to toe tip, not only the joints) goes more
    than 5 mm below the ground, over the whole step (before the whole-sole clearance:
    up to 2-8 cm, the toes or the sole's middle cutting the edge)."""
    body = Body.from_heights([1.75])
    if case == "curb up":
        def ground(xy):
            return np.where(xy[:, 0] > 0.98, 0.15, 0.0)

        # the stance foot just up the curb, the trailing foot below it swings up past
        # the edge (quickstart's raised sidewalk)
        steps = [(0.0, 0.45, 0.0), (0.45, 1.05, 0.15), (1.05, 1.70, 0.15)]
    else:
        def ground(xy):
            return np.where((xy[:, 0] > 0.50) & (xy[:, 0] < 0.80), 0.10, 0.0)

        steps = [(0.0, 0.30, 0.0), (0.30, 0.95, 0.0), (0.95, 1.55, 0.0)]
    animator = Animator(body, ground=ground)
    worst, y, t = 0.0, 0.045, 0.0
    z0 = 0.0
    for s, (x0, x1, z1) in enumerate(steps):
        foot = s % 2  # 0: the left foot swings
        start = [[x0, -y if foot == 0 else y, z0]]
        target = [[x1, y if foot == 0 else -y, z1]]
        animator.command(_command([0], t, foot, start, target, duration=0.6))
        for f in range(30):
            frame = animator.pose(t + f / 50.0)
            if s:
                worst = max(worst, _sole_depth(body, frame, ground, foot))
        t += 0.6
        z0 = z1
    assert worst <= 5e-3


def _swing_knee_peak(speed_blend):
    """Peak swing knee flexion [deg] of two identical 0.65 m steps of a 1.75 m body,
    commanded at Bovi's slowest (0.85 m/s) and fastest (1.96 m/s) level speeds."""
    from crowdwalk.gait.elevinterp import ElevInterp, ElevInterpConfig

    body = Body.from_heights([1.75, 1.75])
    from crowdwalk.gait.elevwalker import GaitStyle

    interp = ElevInterp(config=ElevInterpConfig(speed_blend=speed_blend))
    # the data's swing alone (no level toe-clearance lift, which evens the knees out)
    animator = Animator(body, ground=_flat, interp=interp,
                        style=GaitStyle(level_clearance=False))
    hip, knee, ankle = (JOINT_NAMES.index(n) for n in ("r_hip", "r_knee", "r_talocrural"))
    peak = np.zeros(2)
    for s in range(3):
        y = 0.045 if s % 2 == 0 else -0.045
        start = np.array([[s * 0.65, y, 0.0]] * 2)
        target = np.array([[(s + 1) * 0.65, -y, 0.0]] * 2)
        cmd = _command([0, 1], s * 0.6, 1 if s % 2 == 0 else 0, start, target)
        animator.command(StepCommand(**{**cmd.__dict__, "speed": np.array([0.85, 1.96])}))
        for f in range(30):
            p = animator.pose(s * 0.6 + f / 50.0).positions
            thigh, shank = p[:, knee] - p[:, hip], p[:, ankle] - p[:, knee]
            cos = np.sum(thigh * shank, 1) / np.linalg.norm(thigh, axis=1) / np.linalg.norm(
                shank, axis=1)
            peak = np.maximum(peak, np.degrees(np.arccos(np.clip(cos, -1, 1))))
    return peak


def test_speed_blend_changes_swing_knee_with_speed():
    """ElevInterp's speed blend (extension of §5): the same step walked faster takes the
    fast dataset's larger swing knee flexion (Bovi 2011 level_l − level_xs ≈ 3.8°); the
    paper's ElevInterp (blend off) animates both alike."""
    from crowdwalk.gait.datasets import load_datasets

    sets = {d.name: d.angles for d in load_datasets()}
    knee = {k: np.degrees(sets[k][:, 2] - sets[k][:, 1]).max() for k in ("level_xs", "level_l")}
    gap = knee["level_l"] - knee["level_xs"]
    slow, fast = _swing_knee_peak(True)
    assert fast - slow > 0.5 * gap
    slow0, fast0 = _swing_knee_peak(False)
    assert abs(fast0 - slow0) < 0.1


def test_a_spin_turn_pivots_on_the_ball_with_the_heel_up():
    """MetaGait's spin (§6.1) of 45 degrees on a 90-degree turn: the stance foot turns
    only once its heel is off the ground, about a ball that stays put, and has made the
    whole spin by the end of the step, a few degrees per frame."""
    from crowdwalk.gait.foot import foot_points as points

    body = Body.from_heights([1.75])
    animator = Animator(body, ground=_flat)
    animator.command(_command([0], 0.0, 1, [[0, 0.045, 0]], [[0.65, -0.045, 0]], duration=0.5))
    animator.command(_command([0], 0.5, 0, [[0.65, -0.045, 0]], [[1.3, 0.045, 0]],
                              duration=0.5))
    h = np.radians(90.0)
    target = np.array([[1.3 + 0.09, 0.045 + 0.65, 0.0]])
    step = _command([0], 1.0, 1, [[1.3, 0.045, 0]], target, duration=0.5, heading=h)
    animator.command(StepCommand(**{**step.__dict__, "spin": np.array([np.radians(45.0)])}))
    yaw, heel, ball = [], [], []
    for f in range(26):
        frame = animator.pose(1.0 + f / 50.0)
        assert not frame.fallback.any()
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        p = points(body, frame.positions, rot)[0, 0]  # the left (stance) foot
        yaw.append(np.degrees(np.arctan2(*(p[2] - p[0])[1::-1])))
        heel.append(p[0, 2])
        ball.append(p[1])
    yaw, heel, ball = np.array(yaw), np.array(heel), np.array(ball)
    turning = np.abs(np.diff(yaw)) > 0.05
    assert yaw[-1] - yaw[0] == pytest.approx(45.0, abs=1.0)
    assert heel[1:][turning].min() > 0.005  # the heel is up whenever the foot turns
    assert np.abs(np.diff(yaw)).max() < 12.0
    moving = ball[1:][turning]
    assert np.linalg.norm(moving[:, :2] - moving[0, :2], axis=1).max() < 0.002


def test_the_trailing_foot_keeps_its_yaw_in_push_off_in_a_turn():
    """After a 15-degree turn the trailing foot, pinned on its toes in push-off, does not
    turn with the body (the swing leg's IK used to yaw it by 20 degrees)."""
    from crowdwalk.gait.foot import foot_points as points

    body = Body.from_heights([1.75])
    animator = Animator(body, ground=_flat)
    turn = np.radians(15.0)
    d = np.array([np.cos(turn), np.sin(turn), 0.0])
    n = np.array([-d[1], d[0], 0.0])
    s1 = np.array([0.65, -0.045, 0.0])
    t1 = s1 + 0.65 * d + 0.09 * n
    animator.command(_command([0], 0.0, 1, [[0, 0.045, 0]], [s1], duration=0.5))
    animator.command(_command([0], 0.5, 0, [s1], [t1], duration=0.5, heading=turn))
    animator.command(_command([0], 1.0, 1, [t1], [t1 + 0.65 * d - 0.09 * n], duration=0.5,
                              heading=turn))
    yaw = []
    for f in range(12):
        frame = animator.pose(1.0 + f / 50.0)
        if not frame.contact[0, 1]:
            break
        rot = forward_kinematics(body, frame.root_position,
                                 quaternion_to_matrix(frame.root_quaternion),
                                 quaternion_to_matrix(frame.joints))[1]  # fmt: skip
        p = points(body, frame.positions, rot)[0, 1]  # the right (trailing) foot
        if p[1, 2] > 0.06:  # the ball well up: the foot stands on its toes
            break
        yaw.append(np.degrees(np.arctan2(*(p[2] - p[0])[1::-1])))
    assert len(yaw) >= 3
    assert np.ptp(yaw) <= 4.0


def _forward_velocity_jumps(style, sl=0.78, duration=0.433, steps=5):
    """|Δ forward root velocity| [m/s] across the heel strikes of a level walk (1.75 m
    body, 1.8 m/s), from root positions 0.5–4.5 ms either side of each strike."""
    animator = Animator(Body.from_heights([1.75]), ground=_flat, style=style)
    jumps = []
    for s in range(steps):
        left_stance = s % 2 == 0
        y = 0.045 if left_stance else -0.045
        t0 = s * duration
        if s >= 2:  # the root just before this heel strike, the previous step's end
            before = [animator.pose(t0 - d).root_position[0, 0] for d in (0.0045, 0.0005)]
        animator.command(_command([0], t0, 1 if left_stance else 0, [[s * sl, y, 0.0]],
                                  [[(s + 1) * sl, -y, 0.0]], duration=duration))
        if s >= 2:
            after = [animator.pose(t0 + d).root_position[0, 0] for d in (0.0005, 0.0045)]
            jumps.append(abs((after[1] - after[0]) - (before[1] - before[0])) / 0.004)
        for f in range(1, 11):  # frames through the step (warm starts, as in a run)
            animator.pose(t0 + f * duration / 11)
    return np.array(jumps)


def test_the_root_moves_on_at_the_heel_strike_as_the_trailing_leg_moved_it():
    """At 1.8 m/s the stance leg rolling on its ball drives the root forward at 2.1 m/s
    at the other heel strike, the new stance leg (on its heel) at 1.5: §4.1's swap alone
    jumps the root's forward velocity by 0.6 m/s (2.3 cm of pelvis second difference per
    25 fps frame). ``trailing_root`` hands the root over during double support."""
    assert np.all(_forward_velocity_jumps(GaitStyle()) < 0.15)
    assert np.all(_forward_velocity_jumps(GaitStyle(trailing_root=False)) > 0.3)


def _turning_walk(animator, k=3, fps=50.0):
    """Frames of k walkers taking a 15-degree turn (push-off yaw fixes, trailing root)."""
    turn = np.radians(15.0)
    d = np.array([np.cos(turn), np.sin(turn), 0.0])
    n = np.array([-d[1], d[0], 0.0])
    s0 = np.array([0.0, 0.045, 0.0])
    s1 = np.array([0.65, -0.045, 0.0])
    t1 = s1 + 0.65 * d + 0.09 * n
    t2 = t1 + 0.65 * d - 0.09 * n
    agents = np.arange(k)
    lanes = np.column_stack([np.zeros(k), np.arange(k) * 1.0, np.zeros(k)])
    frames = []
    for s, (foot, a, b, heading) in enumerate([(1, s0, s1, 0.0), (0, s1, t1, turn),
                                               (1, t1, t2, turn)]):  # fmt: skip
        animator.command(_command(agents, 0.5 * s, foot, a + lanes, b + lanes, duration=0.5,
                                  heading=heading))  # fmt: skip
        frames += [animator.pose(0.5 * s + f / fps) for f in range(25)]
    return frames


def test_a_frames_rewalks_take_its_walk_inputs_and_pose_the_same():
    """The yaw fixes, pin fixes and lifts of a frame re-walk agents whose walk arguments
    the frame's walk has found (:class:`_WalkInputs`: legs, heading, corrections, the
    trailing-root offset): they take them, and every pose is what finding them again
    gives."""
    body = Body.from_heights([1.6, 1.75, 1.9])
    taken, again = Animator(body, ground=_flat), Animator(body, ground=_flat)
    solved = {"taken": 0, "again": 0}

    def counting(animator, key):
        inner = animator._trailing_solved

        def solve(a, phase, free=None):
            solved[key] += a.size
            return inner(a, phase, free)
        return solve

    taken._trailing_solved = counting(taken, "taken")
    again._trailing_solved = counting(again, "again")
    rewalk = again._rewalk

    def found_again(a, phase, inputs, rows, **fixes):  # every re-walk from the state
        return rewalk(a, phase, None, rows, **fixes)

    again._rewalk = found_again
    fa, fb = _turning_walk(taken), _turning_walk(again)
    assert taken.stats["yaw_fixes"] > 0 and solved["taken"] < solved["again"]
    assert taken.stats == again.stats
    for a, b in zip(fa, fb, strict=True):
        for name in ("root_position", "joints", "positions", "contact", "fallback"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name


def test_a_commands_trailing_root_takes_its_root_joins_walk_and_poses_the_same():
    """At a step command the trailing-root offset at the heel strike takes its free walk
    from the root join's walk of the same agents (the same arguments): every pose and
    counter is what solving it again gives."""
    body = Body.from_heights([1.6, 1.75, 1.9])
    taken, again = Animator(body, ground=_flat), Animator(body, ground=_flat)
    given = {"taken": 0, "again": 0}

    def tracking(animator, key, drop):
        inner = animator._trailing_solved

        def solve(a, phase, free=None):
            given[key] += 0 if free is None else a.size
            return inner(a, phase, None if drop else free)
        return solve

    taken._trailing_solved = tracking(taken, "taken", False)
    again._trailing_solved = tracking(again, "again", True)
    k = 3
    agents = np.arange(k)
    lanes = np.column_stack([np.zeros(k), np.arange(k) * 1.0, np.zeros(k)])
    frames = {"taken": [], "again": []}
    for key, animator in (("taken", taken), ("again", again)):
        foot, start = 1, np.array([0.0, 0.045, 0.0])
        for s in range(4):
            target = start + np.array([0.65, -0.09 if foot else 0.09, 0.0])
            animator.command(_command(agents, 0.5 * s, foot, start + lanes, target + lanes,
                                      duration=0.5))
            frames[key] += [animator.pose(0.5 * s + f / 50.0) for f in range(25)]
            foot, start = 1 - foot, target
    assert given["taken"] > 0 and given["again"] == given["taken"]
    assert taken.stats == again.stats
    for a, b in zip(frames["taken"], frames["again"], strict=True):
        for name in ("root_position", "joints", "positions", "contact", "fallback"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name


def _varied_walk(style, lengths, duration=0.45, fps=25.0):
    """A 1.75 m body's level walk of the given step lengths [m]: the largest change (k-1,)
    [deg] of any followed elevation angle across each heel strike (the new stance leg
    against the old swing leg and vice versa, ±0.1 ms) and each step's root positions at
    ``fps`` (list of (f, 3) [m])."""
    animator = Animator(Body.from_heights([1.75]), ground=_flat, style=style)
    x, roots, jumps = 0.0, [], []
    one = np.array([0])
    for s, sl in enumerate(lengths):
        y = 0.045 if s % 2 == 0 else -0.045
        t0 = s * duration
        if s:
            st0, sw0, _, _ = animator.followed_angles(t0 - 1e-4, one)
        animator.command(_command([0], t0, 1 if s % 2 == 0 else 0, [[x, y, 0.0]],
                                  [[x + sl, -y, 0.0]], duration=duration))
        if s:
            st1, sw1, _, _ = animator.followed_angles(t0 + 1e-4, one)
            jumps.append(max(np.abs(st1 - sw0).max(), np.abs(sw1 - st0).max()))
        x += sl
        roots.append(np.array([animator.pose(t0 + f / fps).root_position[0]
                               for f in range(int(round(duration * fps)))]))
    return np.degrees(jumps), roots


def test_the_legs_cross_a_change_of_step_length_without_a_jump():
    """Each step's dataset has its own geometry at the heel strike that opens it (Eq. 10
    of its own length); the feet span the previous step's. ``step_crossfade`` fades the
    new dataset in over the step, so the followed angles are continuous at the swap
    (without it they jump by 18-24° between 0.55 and 0.75 m steps, and the root's join
    offset absorbs the rest)."""
    lengths = [0.7, 0.7, 0.55, 0.75, 0.55, 0.75, 0.7]
    jumps, _ = _varied_walk(GaitStyle(), lengths)
    assert jumps.max() < 0.5
    old, _ = _varied_walk(GaitStyle(step_crossfade=False), lengths)
    assert old[1:-1].min() > 5.0


def test_the_root_rejoins_the_data_smoothly_after_a_clamped_step():
    """A 0.25 m step is below what the data serve (clamped): the swing IK pulls its landing
    onto the target and the next step's root starts off the data by the difference
    (17 cm). ``clamped_join`` blends that out over the whole next step, not its first
    half: the root's second differences through that step are lower."""
    lengths = [0.7, 0.7, 0.7, 0.25, 0.7, 0.7]

    def worst_after_clamped(style):
        root = _varied_walk(style, lengths)[1][4]
        return np.linalg.norm(root[2:] - 2 * root[1:-1] + root[:-2], axis=1).max()

    assert worst_after_clamped(GaitStyle()) < 0.8 * worst_after_clamped(
        GaitStyle(clamped_join=False))


def _toe_off_velocity_jumps(style, sl=0.676, duration=0.508, steps=3):
    """|Δ horizontal swing-ankle velocity| [m/s] across each toe-off of a level walk
    (1.75 m body, 1.33 m/s), from ankle positions 0.5–4.5 ms either side of it, and the
    ankle's path (list of (8, 3) [m]) from toe-off to the landing."""
    animator = Animator(Body.from_heights([1.75]), ground=_flat, style=style)
    jumps, paths = [], []
    for s in range(steps):
        y = 0.045 if s % 2 == 0 else -0.045
        t0 = s * duration
        foot = 1 if s % 2 == 0 else 0
        animator.command(_command([0], t0, foot, [[s * sl, y, 0.0]],
                                  [[(s + 1) * sl, -y, 0.0]], duration=duration))
        for f in range(1, 6):  # frames up to the toe-off (warm starts, as in a run)
            animator.pose(t0 + f * 0.02)
        if s == 0:
            continue
        t_off = t0 + animator._swing.toe_off[0] * duration
        ankle = [animator.pose(t_off + d).positions[0, LEG_JOINTS[foot, 2], :2]
                 for d in (-0.0045, -0.0005, 0.0005, 0.0045)]
        jumps.append(np.linalg.norm((ankle[3] - ankle[2]) - (ankle[1] - ankle[0])) / 0.004)
        paths.append(np.array([animator.pose(t).positions[0, LEG_JOINTS[foot, 2]]
                               for t in np.linspace(t_off, t0 + duration, 8)]))
    return np.array(jumps), paths


def test_the_swing_ankle_leaves_toe_off_as_the_pinned_push_off_moved_it(monkeypatch):
    """Until toe-off the trailing ankle is pinned on the toe tip (0.8 m/s forward at
    1.33 m/s); the data's swing ankle is already at 2.2 m/s there, so following it jumps
    the velocity (3.4 m/s on the uneven park's 0.403 s steps: its foot spikes).
    ``toe_off_c1`` starts the swing with the part of the jump above ``_TOE_OFF_KEEP``
    carried by an offset; with nothing kept the jump is gone, and a walker whose jump
    is below it walks as without the switch."""
    import crowdwalk.gait.animator as animator_module

    kept, kept_paths = _toe_off_velocity_jumps(GaitStyle())
    off, off_paths = _toe_off_velocity_jumps(GaitStyle(toe_off_c1=False))
    assert np.all(off > 1.0) and np.all(off < animator_module._TOE_OFF_KEEP)
    for a, b in zip(kept_paths, off_paths, strict=True):
        assert np.abs(a - b).max() < 1e-9
    monkeypatch.setattr(animator_module, "_TOE_OFF_KEEP", 0.0)
    carried, _ = _toe_off_velocity_jumps(GaitStyle())
    assert np.all(carried < 0.2)


def _push_off_ball_slide(style, turn_deg=25.0, steps=4, sl=0.71, duration=0.456, width=0.1):
    """Largest horizontal move [m] of the trailing foot's ball, from where it stood at the
    end of its stance to its toe-off (while within 5 mm of that), on a walk whose every
    step turns by ``turn_deg`` (1.75 m body with the crowd's KLAW attributes at 1.56 m/s)."""
    animator = Animator(Body.from_heights([1.75]), ground=_flat, style=style,
                        attributes=Style.default(np.array([1.75]), np.array([1.56])))
    turn = np.radians(turn_deg)
    half = 0.5 * width
    foot_at = np.array([0.0, half, 0.0])
    worst = 0.0
    for s in range(steps):
        heading = s * turn
        d = np.array([np.cos(heading), np.sin(heading), 0.0])
        n = np.array([-d[1], d[0], 0.0])
        side = -1.0 if s % 2 == 0 else 1.0  # the swing foot's side of the path
        centre = foot_at + half * (1.0 if s % 2 == 0 else -1.0) * n
        target = centre + sl * d + half * side * n
        foot = 1 if s % 2 == 0 else 0
        t0 = duration * s
        # the foot that will trail, as the step before leaves it (its stance foot)
        before = animator.pose(t0 - 1e-4).positions[0, LEG_JOINTS[foot, 4]] if s else None
        animator.command(_command([0], t0, foot, [foot_at], [target], duration=duration,
                                  heading=heading))  # fmt: skip
        t_off = t0 + duration * animator._swing.toe_off[0]
        balls = np.array([animator.pose(t).positions[0, LEG_JOINTS[foot, 4]]
                          for t in np.linspace(t0, t_off, 12)])
        if s:
            low = balls[:, 2] < before[2] + 0.005
            worst = max(worst, np.linalg.norm(balls[low, :2] - before[:2], axis=1).max())
        for f in range(1, 6):
            animator.pose(t_off + f * (t0 + duration - t_off) / 6)
        foot_at = target
    return worst


def test_the_trailing_ball_stays_where_it_stood_in_a_turn():
    """After a turn the trailing foot is yawed away from ψ; the swing talocrural pitches
    it about a skew axis and it rolls, so its ball slid sideways off the pinned ankle
    (the corner's heel slides of 10-19 mm). ``pin_ball`` moves the ankle's goal until the
    ball is where the pin put it."""
    import crowdwalk.gait.animator as animator_module

    assert _push_off_ball_slide(GaitStyle()) < animator_module._PIN_TOLERANCE + 0.0005
    assert _push_off_ball_slide(GaitStyle(pin_ball=False)) > 0.008


def _level_toe_offs(style, steps=3, sl=0.62, duration=0.403):
    """Toe-off (fraction of the step) of each step after the first of a level walk (1.75 m
    body) and the Animator, for the switch tests below."""
    animator = Animator(Body.from_heights([1.75]), ground=_flat, style=style)
    out = []
    for s in range(steps):
        y = 0.045 if s % 2 == 0 else -0.045
        animator.command(_command([0], s * duration, 1 if s % 2 == 0 else 0,
                                  [[s * sl, y, 0.0]], [[(s + 1) * sl, -y, 0.0]],
                                  duration=duration))
        for f in range(1, 6):
            animator.pose(s * duration + f * 0.02)
        if s:
            out.append(float(animator._swing.toe_off[0]))
    return np.array(out), animator


def test_data_toe_off_lets_the_foot_go_where_the_data_have_lifted_it(monkeypatch):
    """``data_toe_off``: where the toe-off hand-over's cap leaves a jump on a short step
    (under ``_TOE_OFF_SHORT`` leg lengths), the trailing foot is released where the
    step's own data have lifted its swing sole ``_TOE_OFF_RISE`` above its height at the
    step's start, when that comes before 2 (stance fraction − 0.5), and the swing's ends
    are found again there (the ankle leaves the pin without a jump); where the cap
    leaves none (ordinary level steps), on longer steps and off, the toe-off is the
    stance fraction's. (A 5 mm rise, so that a level step reaches it; the cap made to
    bind by keeping nothing and carrying almost nothing.)"""
    import crowdwalk.gait.animator as animator_module

    monkeypatch.setattr(animator_module, "_TOE_OFF_RISE", 0.005)
    base, off_animator = _level_toe_offs(GaitStyle(data_toe_off=False))
    assert off_animator.stats["data_toe_offs"] == 0
    uncapped, animator = _level_toe_offs(GaitStyle(data_toe_off=True))
    assert animator.stats["data_toe_offs"] == 0
    np.testing.assert_array_equal(uncapped, base)
    monkeypatch.setattr(animator_module, "_TOE_OFF_KEEP", 0.0)
    monkeypatch.setattr(animator_module, "_TOE_OFF_ACCEL", 1e-3)
    base, _ = _level_toe_offs(GaitStyle(data_toe_off=False))
    moved, animator = _level_toe_offs(GaitStyle(data_toe_off=True))
    assert animator.stats["data_toe_offs"] == moved.size
    assert np.all(moved < base - 0.02)
    # at the new toe-off the data's swing sole has risen the threshold (the last step)
    a = np.array([0, 0])
    phases = 0.5 * np.array([0.0, moved[-1]])
    walked = animator._walk(a, phases, corrected=False)
    height = -animator._points_depth(a, animator._swing_sole(a, walked))
    assert height[1] - height[0] == pytest.approx(0.005, abs=0.002)
    # ... and the swing ankle (the last step swings the right foot) leaves the pin there
    around = animator._walk(a, 0.5 * moved[-1] + np.array([-1e-4, 1e-4]), corrected=True)
    ankle = around.positions[:, LEG_JOINTS[1, 2]]
    assert np.linalg.norm(ankle[1] - ankle[0]) < 2e-3
    # a step longer than _TOE_OFF_SHORT leg lengths keeps the stance fraction's toe-off
    # (these 0.62 m steps are 0.72 leg lengths of the 1.75 m body)
    monkeypatch.setattr(animator_module, "_TOE_OFF_SHORT", 0.5)
    kept, animator = _level_toe_offs(GaitStyle(data_toe_off=True))
    assert animator.stats["data_toe_offs"] == 0
    np.testing.assert_array_equal(kept, base)


def _stop_and_go(style, sl=0.7, duration=0.45, wait=0.3, fps=25.0):
    """A 1.75 m walker (1.56 m/s) takes three steps, stands ``wait`` [s] and walks two
    more: root positions (F, 3) [m], both ankles (F, 2, 3) [m] at frames 1/fps apart,
    the frames' times (F,) [s], and the stand's start and end [s]."""
    animator = Animator(Body.from_heights([1.75]), ground=_flat, style=style)
    starts = [s * duration for s in range(3)] + [3 * duration + wait + s * duration
                                                 for s in range(2)]
    stand = (3 * duration, 3 * duration + wait)
    times, roots, ankles = [], [], []
    t = 0.013
    for s, t0 in enumerate(starts):
        left_stance = s % 2 == 0
        y = 0.045 if left_stance else -0.045
        animator.command(_command([0], t0, 1 if left_stance else 0, [[s * sl, y, 0.0]],
                                  [[(s + 1) * sl, -y, 0.0]], duration=duration))
        end = starts[s + 1] if s + 1 < len(starts) else t0 + duration
        while t < end:
            frame = animator.pose(t)
            times.append(t)
            roots.append(frame.root_position[0])
            ankles.append(frame.positions[0, LEG_JOINTS[:, 2]])
            t += 1.0 / fps
    return np.array(roots), np.array(ankles), np.array(times), stand


def test_a_stopping_walker_settles_with_its_feet_planted_and_starts_again_smoothly():
    """Without ``stop_settle`` the pose freezes at the last heel strike: the root goes
    from 1.56 m/s to standing in one frame (4.0 cm of second difference at 25 fps; 6.7 at
    the restart). With it the root comes to rest at 10 m/s², both feet where they
    landed (2.6 cm, the stance leg's reach lowering the pelvis as it moves on), and the
    next step joins it C¹ (2.0 cm)."""
    for style, bound in ((GaitStyle(stop_settle=True), 0.03), (GaitStyle(), None)):
        roots, ankles, times, (t_stop, t_go) = _stop_and_go(style)
        d2 = np.linalg.norm(roots[2:] - 2.0 * roots[1:-1] + roots[:-2], axis=1)
        if bound is None:
            assert d2.max() > 0.04
            continue
        assert d2.max() < bound
        standing = (times > t_stop) & (times < t_go)
        assert standing.sum() >= 6
        feet = ankles[standing]
        assert np.abs(feet - feet[0]).max() < 1e-3  # both feet planted
        moved = np.linalg.norm(roots[standing][-1] - roots[standing][0])
        assert moved > 0.05  # the root carried on (it did not freeze)


def test_a_restart_from_a_frozen_stand_joins_the_root_from_rest():
    """Without ``stop_settle`` the stand freezes the pose; the next step then takes the
    data's root velocity at once (1.8 m/s in the restart's first whole frame, 6.7 cm of
    second difference at 25 fps). With ``restart_c1`` the root starts from rest and takes
    the data's velocity over the first half of the step, as a stair step's C¹ join does
    (0.7 m/s in that frame, 3.6 cm); the walk before the restart is the same poses."""
    base, _, times, (t_stop, t_go) = _stop_and_go(GaitStyle())
    roots, _, _, _ = _stop_and_go(GaitStyle(restart_c1=True))
    first = np.flatnonzero(times > t_go)[0]  # the restart's first frame
    speed = [np.linalg.norm(r[first + 1] - r[first]) * 25.0 for r in (base, roots)]
    assert speed[1] < 0.5 * speed[0]  # from rest, not at the data's speed at once
    go = times[1:-1] > t_go - 0.04  # second differences that see a restart frame
    d2 = [np.linalg.norm(r[2:] - 2.0 * r[1:-1] + r[:-2], axis=1)[go].max() for r in (base, roots)]
    assert d2[1] < d2[0]
    before = times <= t_go
    np.testing.assert_array_equal(roots[before], base[before])
    # with the settle on, its own C¹ restart is the one used (the switch changes nothing)
    settled = _stop_and_go(GaitStyle(stop_settle=True))[0]
    both = _stop_and_go(GaitStyle(stop_settle=True, restart_c1=True))[0]
    np.testing.assert_array_equal(both, settled)


def test_a_stop_posed_at_a_steady_frame_rate_needs_no_walk_of_its_own():
    """The step end a stop settles from (its root velocity, the landed ankle) is measured
    in the walker's last frame before the end, as rows of that frame's walk: the first
    frame of the stand makes no more ElevWalker calls than the standing frames after it
    (gait16's own measuring walk made one more)."""
    calls = []

    class Counting(Animator):
        def pose(self, t, agents=None):
            calls.append(0)
            return super().pose(t, agents)

        def _walk_from(self, *args, **kwargs):  # the walks and re-walks of a frame
            if calls:
                calls[-1] += 1
            return super()._walk_from(*args, **kwargs)

    animator = Counting(Body.from_heights([1.75]), ground=_flat,
                        style=GaitStyle(stop_settle=True))
    duration, sl = 0.45, 0.7
    for s in range(3):
        left_stance = s % 2 == 0
        y = 0.045 if left_stance else -0.045
        animator.command(_command([0], s * duration, 1 if left_stance else 0,
                                  [[s * sl, y, 0.0]], [[(s + 1) * sl, -y, 0.0]],
                                  duration=duration))
        t = 0.013 + np.ceil((s * duration - 0.013) * 25.0) / 25.0
        while t < (s + 1) * duration:
            animator.pose(t)
            t += 0.04
    first = len(calls)
    for _ in range(3):  # standing
        animator.pose(t)
        t += 0.04
    assert animator._settle.has[0]  # measured before the stand's first frame
    assert calls[first] <= calls[first + 1] == calls[first + 2]
