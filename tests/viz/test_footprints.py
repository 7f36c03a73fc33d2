"""Footprints: walking directions, outlines at the footholds, lift along the ground
normal, stacking, time windows and fading."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.errors import InputError
from crowdwalk.viz.footprints import FootprintMesh, Footsteps, foot_outline, walking_headings


def _straight_walk(heading, n, start=(0.0, 0.0), step=0.7, width=0.18):
    """Alternating left/right footholds of one agent walking along heading [rad]."""
    d = np.array([np.cos(heading), np.sin(heading)])
    left = np.array([-d[1], d[0]])
    k = np.arange(n)
    side = np.where(k % 2 == 0, 0.5, -0.5) * width
    return np.asarray(start) + step * k[:, None] * d + side[:, None] * left


@settings(max_examples=50, deadline=None)
@given(st.floats(-np.pi, np.pi), st.integers(2, 12), st.floats(-50, 50), st.floats(-50, 50))
def test_headings_follow_the_walking_direction(heading, n, x0, y0):
    xy = _straight_walk(heading, n, (x0, y0))
    got = walking_headings(np.zeros(n, int), np.arange(n) * 0.5, xy)
    err = np.angle(np.exp(1j * (got - heading)))
    # the lateral alternation tilts one-sided ends by at most atan(width / step)
    assert np.all(np.abs(err[1:-1]) < 1e-9)
    assert np.all(np.abs(err) <= np.arctan(0.18 / 0.7) + 1e-9)


def test_headings_do_not_mix_agents_and_ignore_row_order():
    a = _straight_walk(0.0, 4)
    b = _straight_walk(np.pi / 2, 4, (10.0, 0.0))
    agent = np.r_[np.zeros(4, int), np.ones(4, int)]
    time = np.r_[np.arange(4), np.arange(4)] * 0.5
    xy = np.vstack([a, b])
    order = np.random.default_rng(0).permutation(8)
    got = walking_headings(agent[order], time[order], xy[order])
    expected = walking_headings(agent, time, xy)
    np.testing.assert_allclose(got, expected[order])
    np.testing.assert_allclose(expected[1:3], 0.0, atol=1e-12)
    np.testing.assert_allclose(expected[5:7], np.pi / 2, atol=1e-12)


def _steps(n=6, heading=0.3):
    xy = _straight_walk(heading, n)
    return Footsteps(np.zeros(n, int), np.arange(n) * 0.5, np.column_stack([xy, np.ones(n)]),
                     np.linspace(10, 20, n), np.array(["best_first", "fixed"] * (n // 2)))


def test_outlines_point_along_the_heading_at_the_foothold():
    steps = _steps(heading=0.3)
    mesh = FootprintMesh(steps, lift=0.01, stack=0.0).mesh
    outline = foot_outline()
    v = len(outline)
    pts = np.asarray(mesh.points).reshape(len(steps), v, 3)
    np.testing.assert_allclose(pts[:, :, 2], 1.01, atol=1e-6)
    toe, heel = pts[:, 4, :2], pts[:, 0, :2]
    direction = toe - heel
    np.testing.assert_allclose(np.arctan2(direction[:, 1], direction[:, 0]), steps.heading,
                               atol=1e-6)
    # the ankle foothold lies on the heel–toe line, heel_offset from the heel
    along = np.linalg.norm(steps.position[:, :2] - heel, axis=1)
    np.testing.assert_allclose(along, -outline[0, 0], atol=1e-6)


@settings(max_examples=30, deadline=None)
@given(st.floats(0.0, 0.6), st.floats(-np.pi, np.pi))
def test_outlines_lie_in_the_tangent_plane_lifted_along_the_normal(tilt, azimuth):
    steps = _steps(n=4)
    normal = np.array([np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth),
                       np.cos(tilt)])
    fp = FootprintMesh(steps, normals=np.tile(normal, (4, 1)), lift=0.01, stack=0.004)
    pts = np.asarray(fp.mesh.points, dtype=float).reshape(4, fp.vertices_per_step, 3)
    height = np.einsum("svc,c->sv", pts - steps.position[:, None], normal)
    # every vertex at its footprint's lift above the ground plane, later ones higher
    np.testing.assert_allclose(height - height[:, :1], 0.0, atol=1e-5)
    np.testing.assert_allclose(height[:, 0], 0.01 + 0.004 * np.arange(4) / 3, atol=1e-5)


def test_footprints_fade_with_age_towards_the_faded_colour():
    from crowdwalk.viz.footprints import FADED

    steps = _steps(n=10)  # placed every 0.5 s from 0 to 4.5 s
    fp = FootprintMesh(steps)
    red = np.tile([220, 20, 20], (10, 1))
    fp.set_colors(red)
    fp.show_window(-np.inf, 4.5, fade=2.0)
    rgb = fp.mesh.point_data["rgb"].reshape(10, -1, 3)[:, 0].astype(float)
    distance = np.linalg.norm(rgb - FADED, axis=1)
    assert np.all(np.diff(distance) >= -1.0)  # older is closer to the faded colour
    np.testing.assert_allclose(rgb[-1], red[-1], atol=1)  # just placed: full colour
    np.testing.assert_allclose(rgb[:6] - rgb[0], 0.0, atol=1)  # 2 s and older: all alike
    # stepping back in time restores the colours of what is young again
    fp.show_window(-np.inf, 1.0, fade=2.0)
    rgb = fp.mesh.point_data["rgb"].reshape(10, -1, 3)[:, 0].astype(float)
    np.testing.assert_allclose(rgb[2], red[2], atol=1)
    assert np.linalg.norm(rgb[0] - FADED) < np.linalg.norm(rgb[1] - FADED)


def test_time_window_keeps_only_footprints_placed_in_it():
    steps = _steps(n=10)
    fp = FootprintMesh(steps)
    per_step = fp.mesh.n_cells // 10
    assert fp.show_window(1.0, 2.0) == 3  # placed at 1.0, 1.5, 2.0 s
    assert fp.mesh.n_cells == 3 * per_step
    assert fp.show_window(-np.inf, 0.2) == 1
    assert fp.show_window(10.0, 20.0) == 0 and fp.mesh.n_cells == 0
    assert fp.show_window(-np.inf, np.inf) == 10 and fp.mesh.n_cells == 10 * per_step


def test_missing_columns_and_ragged_arrays_are_rejected():
    with pytest.raises(InputError, match=r"Footsteps\.columns must be a table with the columns"):
        Footsteps.from_table({"agent": [1], "time": [0.0]})
    with pytest.raises(InputError, match=r"Footsteps\.energy must be of length 2"):
        Footsteps(np.zeros(2), np.zeros(2), np.zeros((2, 3)), np.zeros(3), np.array(["a", "b"]))


@pytest.mark.parametrize("coarse", [False, True])
def test_outlines_are_convex_and_contain_the_foothold(coarse):
    import shapely

    outline = foot_outline(coarse=coarse)
    polygon = shapely.Polygon(outline)
    assert polygon.is_valid and polygon.convex_hull.area == pytest.approx(polygon.area)
    assert polygon.contains(shapely.Point(0.0, 0.0))  # the ankle foothold is on the sole
    steps = _steps(n=4)
    fp = FootprintMesh(steps, coarse=coarse)
    assert fp.mesh.n_cells == 4 * (len(outline) - 2)
    assert fp.mesh.area == pytest.approx(4 * polygon.area, rel=1e-5)
