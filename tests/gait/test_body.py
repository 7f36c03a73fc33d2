"""Body: anthropometric proportions, H-Anim names, Inman axes, batched kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.body import (
    JOINT,
    JOINT_NAMES,
    PARENTS,
    SUBTALAR_AXIS,
    TALOCRURAL_AXIS,
    Body,
    axis_angle_matrix,
    forward_kinematics,
    matrix_to_quaternion,
    mirrored_axis,
    quaternion_to_matrix,
    rotation_z,
)
from crowdwalk.errors import InputError

HEIGHTS = st.floats(1.2, 2.2)


def _standing(body: Body):
    n = len(body)
    root = np.column_stack([np.zeros(n), np.zeros(n), body.hip_height])
    local = np.broadcast_to(np.eye(3), (n, len(JOINT_NAMES), 3, 3)).copy()
    return forward_kinematics(body, root, np.broadcast_to(np.eye(3), (n, 3, 3)), local)


def test_winter_proportions():
    body = Body.from_heights([1.75])
    assert body.thigh[0] == pytest.approx(0.245 * 1.75)
    assert body.shank[0] == pytest.approx(0.246 * 1.75)
    assert body.ankle_height[0] == pytest.approx(0.039 * 1.75)
    assert body.heel_offset[0] + body.toe_offset[0] == pytest.approx(0.152 * 1.75)
    # hip height = thigh + shank + ankle height (Winter: 0.530 H)
    assert body.leg_length[0] == pytest.approx(body.hip_height[0])


@settings(max_examples=40, deadline=None)
@given(st.lists(HEIGHTS, min_size=1, max_size=5))
def test_lengths_scale_with_height(heights):
    body = Body.from_heights(heights)
    h = np.asarray(heights)
    for field in ("thigh", "shank", "foot_length", "upper_arm", "hip_separation"):
        ratio = getattr(body, field) / h
        assert np.allclose(ratio, ratio[0])


def test_hanim_level_1_names_and_paper_dofs():
    loa1 = {"HumanoidRoot", "sacroiliac", "l_hip", "l_knee", "l_talocrural", "r_hip",
            "r_knee", "r_talocrural", "vl5", "skullbase", "l_shoulder", "l_elbow",
            "l_wrist", "r_shoulder", "r_elbow", "r_wrist"}  # fmt: skip
    assert loa1 <= set(JOINT_NAMES)
    # The paper's foot: subtalar and first metatarsophalangeal joints (LOA 2 names).
    assert {"l_subtalar", "r_subtalar", "l_metatarsal", "r_metatarsal"} <= set(JOINT_NAMES)
    assert PARENTS[0] == -1 and np.all(PARENTS[1:] < np.arange(1, len(PARENTS)))
    assert JOINT_NAMES[PARENTS[JOINT["l_knee"]]] == "l_hip"


def test_standing_pose_feet_on_the_ground_and_head_on_top():
    body = Body.from_heights([1.6, 1.9])
    positions, _ = _standing(body)
    for side in ("l", "r"):
        assert np.allclose(positions[:, JOINT[f"{side}_metatarsal"], 2], 0.0, atol=1e-12)
        assert np.allclose(positions[:, JOINT[f"{side}_talocrural"], 2], body.ankle_height)
    top = positions[:, JOINT["skullbase"], 2] + body.head
    assert np.allclose(top, body.height)


def test_inman_axes():
    # Talocrural axis ~8° below the horizontal laterally; subtalar 42° above horizontal,
    # 23° medial of the foot's long axis (Inman 1976).
    assert np.degrees(np.arcsin(-TALOCRURAL_AXIS[2])) == pytest.approx(
        np.degrees(np.arctan(np.tan(np.radians(8)) * np.cos(np.radians(6)))), abs=0.5)
    assert np.degrees(np.arcsin(SUBTALAR_AXIS[2])) == pytest.approx(42.0)
    assert np.degrees(np.arctan2(-SUBTALAR_AXIS[1], SUBTALAR_AXIS[0])) == pytest.approx(23.0)


@settings(max_examples=40, deadline=None)
@given(st.floats(-2.0, 2.0))
def test_mirrored_axis_gives_mirror_motion(theta):
    mirror = np.diag([1.0, -1.0, 1.0])
    for axis in (TALOCRURAL_AXIS, SUBTALAR_AXIS):
        left = axis_angle_matrix(axis, np.array([theta]))[0]
        right = axis_angle_matrix(mirrored_axis(axis), np.array([theta]))[0]
        assert np.allclose(mirror @ left @ mirror, right)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_quaternion_round_trip(seed):
    from scipy.spatial.transform import Rotation

    matrices = Rotation.random(16, random_state=seed).as_matrix()
    q = matrix_to_quaternion(matrices)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    assert np.all(q[:, 0] >= 0)
    assert np.allclose(quaternion_to_matrix(q), matrices, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(HEIGHTS, st.floats(-np.pi, np.pi), st.floats(-5, 5), st.floats(-5, 5))
def test_forward_kinematics_is_rigid_under_yaw_and_translation(height, yaw, dx, dy):
    body = Body.from_heights([height])
    rng = np.random.default_rng(0)
    local = axis_angle_matrix(np.array([0.0, 1.0, 0.0]), rng.uniform(-0.5, 0.5, 20))[None]
    root = np.array([[0.0, 0.0, 1.0]])
    base, _ = forward_kinematics(body, root, np.eye(3)[None], local)
    turn = rotation_z(np.array([yaw]))
    moved, _ = forward_kinematics(body, root + [dx, dy, 0.0], turn, local)
    expected = (base - root[:, None]) @ turn[0].T + root[:, None] + [dx, dy, 0.0]
    assert np.allclose(moved, expected)
    # bone lengths are the body's offsets whatever the pose
    bones = np.linalg.norm(moved[0, 1:] - moved[0, PARENTS[1:]], axis=1)
    assert np.allclose(bones, np.linalg.norm(body.offsets()[0, 1:], axis=1))


@pytest.mark.parametrize("bad", [[0.2], [float("nan")], [3.0], []])
def test_bad_heights_are_rejected_with_a_clear_message(bad):
    with pytest.raises(InputError, match=r"^Body\.heights must be .*; got"):
        Body.from_heights(bad)
