"""Pose sources and the timeline that blends between stored output frames."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.errors import InputError
from crowdwalk.viz.sources import ArrayPoses, PoseTimeline, blend_frames, frame_index


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 30), st.floats(0, 1), st.integers(0, 2**32 - 1))
def test_blend_moves_shared_agents_and_keeps_leavers(n, alpha, seed):
    rng = np.random.default_rng(seed)
    ids0 = rng.permutation(40)[: n + 1]
    ids1 = rng.permutation(40)[: rng.integers(0, 40)]
    p0 = rng.normal(size=(len(ids0), 3, 3))
    p1 = rng.normal(size=(len(ids1), 3, 3))
    out = blend_frames(ids0, p0, ids1, p1, alpha)
    for i, agent in enumerate(ids0):
        hit = np.flatnonzero(ids1 == agent)
        expected = p0[i] + alpha * (p1[hit[0]] - p0[i]) if hit.size else p0[i]
        np.testing.assert_allclose(out[i], expected, atol=1e-12)


def test_timeline_holds_or_blends_between_frames():
    times = np.array([0.0, 0.5, 1.0])
    ids = [np.array([1, 2]), np.array([2, 1]), np.array([2])]
    pos = [np.zeros((2, 1, 3)), np.array([[[2.0, 0, 0]], [[4.0, 0, 0]]]), np.ones((1, 1, 3))]
    poses = ArrayPoses(times, ids, pos, np.array([-1]))
    smooth, held = PoseTimeline(poses), PoseTimeline(poses, interpolate=False)
    index, got_ids, got = smooth.at_time(0.25)
    assert index == 0 and got_ids.tolist() == [1, 2]
    np.testing.assert_allclose(got[:, 0, 0], [2.0, 1.0])  # agent 1 → 4, agent 2 → 2
    np.testing.assert_allclose(held.at_time(0.25)[2][:, 0, 0], [0.0, 0.0])
    index, got_ids, got = smooth.at_time(0.75)  # agent 1 leaves: holds its last pose
    assert index == 1 and got_ids.tolist() == [2, 1]
    np.testing.assert_allclose(got[:, 0, 0], [1.5, 4.0])
    assert smooth.at_time(5.0)[0] == 2 and smooth.at_time(-1.0)[0] == 0


def test_frame_index_is_the_frame_at_or_before():
    times = np.array([0.0, 0.04, 0.08])
    assert [frame_index(times, t) for t in (-1, 0, 0.039, 0.04, 0.07999999999, 9)] == [
        0, 0, 0, 1, 2, 2,
    ]


def test_array_poses_checks_lengths_and_order():
    with pytest.raises(InputError, match=r"ArrayPoses\.times must be strictly increasing"):
        ArrayPoses(np.array([0.0, 0.0]), [np.zeros(0)] * 2, [np.zeros((0, 1, 3))] * 2, [-1])
    with pytest.raises(InputError, match=r"ArrayPoses\.ids must be one entry per frame"):
        ArrayPoses(np.array([0.0]), [], [], [-1])
