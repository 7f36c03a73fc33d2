"""Stick figures: tubes around every bone, one mesh for all agents, updated in place."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from crowdwalk.errors import InputError
from crowdwalk.viz.figures import StickFigures, bone_pairs
from crowdwalk.viz.synthetic import SKELETON_PARENTS, walking_pose

# joint positions on a 1 mm grid: a bone is either degenerate (coincident joints) or at
# least 1 mm long; the direction of a sub-micrometre bone is numerical noise
poses = st.integers(1, 4).flatmap(
    lambda k: arrays(np.int64, (k, len(SKELETON_PARENTS), 3), elements=st.integers(-5000, 5000))
).map(lambda a: a / 1000.0)


def _tube_points(figures, k):
    s, b = figures.sides, len(figures.bones)
    pts = np.asarray(figures.mesh.points).reshape(k, figures.points_per_agent, 3)
    return pts[:, : 2 * s * b].reshape(k, b, 2, s, 3)


@settings(max_examples=40, deadline=None)
@given(poses)
def test_tube_rings_lie_at_the_radius_around_each_bone_end(positions):
    figures = StickFigures(SKELETON_PARENTS, head_joint=13, radius=0.04)
    figures.update(positions)
    k = len(positions)
    rings = _tube_points(figures, k)
    ends = np.stack([positions[:, figures.bones[:, 0]], positions[:, figures.bones[:, 1]]], 2)
    offset = rings - ends[:, :, :, None, :]
    np.testing.assert_allclose(np.linalg.norm(offset, axis=-1), 0.04, rtol=1e-4)
    axis = ends[:, :, 1] - ends[:, :, 0]
    length = np.linalg.norm(axis, axis=-1)
    ok = length > 1e-3
    unit = axis[ok] / length[ok][:, None]
    along = np.einsum("bkc,bc->bk", offset[ok].reshape(-1, 2 * figures.sides, 3), unit)
    assert np.all(np.abs(along) < 1e-3)  # rings are perpendicular to the bone


@settings(max_examples=30, deadline=None)
@given(poses, arrays(np.float64, 3, elements=st.floats(-100, 100, allow_nan=False)))
def test_translating_the_poses_translates_the_mesh(positions, shift):
    figures = StickFigures(SKELETON_PARENTS, head_joint=13)
    before = np.array(figures.update(positions).points, dtype=float)
    after = np.array(figures.update(positions + shift).points, dtype=float)
    np.testing.assert_allclose(after, before + shift, atol=1e-3)


def test_same_agent_count_updates_the_same_mesh_in_place():
    figures = StickFigures(SKELETON_PARENTS, head_joint=13)
    first = walking_pose(np.zeros(3))
    mesh = figures.update(first, values=[4, 5, 6])
    cells, vtk_points = mesh.n_cells, mesh.GetPoints()
    moved = figures.update(first + [1.0, 0.0, 0.0])  # values kept
    assert moved is mesh and mesh.GetPoints() is vtk_points and mesh.n_cells == cells
    assert np.isclose(mesh.bounds[0], figures.mesh.bounds[0])
    assert np.all(mesh.point_data["value"].reshape(3, -1) == [[4], [5], [6]])
    # a different agent count rebuilds the cells of the same mesh object
    again = figures.update(walking_pose(np.zeros(5)))
    assert again is mesh and mesh.n_cells == cells // 3 * 5


def test_normals_are_unit_and_head_sits_above_the_head_joint():
    figures = StickFigures(SKELETON_PARENTS, head_joint=13, head_radius=0.1)
    positions = walking_pose(np.array([0.3]))
    mesh = figures.update(positions)
    np.testing.assert_allclose(np.linalg.norm(mesh.point_data["Normals"], axis=1), 1, rtol=1e-5)
    head = np.asarray(mesh.points)[2 * figures.sides * len(figures.bones):]
    np.testing.assert_allclose(head.mean(axis=0), positions[0, 13] + [0, 0, 0.1], atol=1e-3)
    assert head[:, 2].max() == pytest.approx(positions[0, 13, 2] + 0.2, abs=1e-3)


def test_no_agents_gives_an_empty_mesh():
    figures = StickFigures(SKELETON_PARENTS, head_joint=13)
    assert figures.update(np.zeros((0, len(SKELETON_PARENTS), 3))).n_points == 0


def test_bad_input_names_owner_field_and_value():
    with pytest.raises(InputError, match=r"StickFigures\.positions must be shaped"):
        StickFigures(SKELETON_PARENTS, head_joint=13).update(np.zeros((2, 3, 3)))
    with pytest.raises(InputError, match=r"StickFigures\.parents must be"):
        bone_pairs(np.array([-1, 5]))
    with pytest.raises(InputError, match=r"StickFigures\.head_joint"):
        StickFigures(SKELETON_PARENTS, head_joint=99)
