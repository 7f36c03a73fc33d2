"""GroundProfile: validation, heights at vertical changes, exact range maxima."""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from planners import GroundProfile, ProfileError
from planners.profile import RASTER_CELL, cell_index
from planners.swing import TABLE_LEVELS, _cell, _raster_max, _raster_vertices


@pytest.mark.parametrize(
    ("s", "z", "field", "value"),
    [
        ([], [], "GroundProfile.s", "[]"),
        ([0.0, 1.0], [0.0, np.nan], "GroundProfile.z", "z[1]=nan"),
        ([0.0, np.inf], [0.0, 0.0], "GroundProfile.s", "s[1]=inf"),
        ([0.0, 2.0, 1.0], [0.0, 0.0, 0.0], "GroundProfile.s", "s[1]=2 > s[2]=1"),
        ([0.0, 1.0], [0.0], "GroundProfile.z", "1"),
    ],
)
def test_bad_profiles_raise_value_errors_naming_field_and_value(s, z, field, value):
    with pytest.raises(ProfileError) as info:
        GroundProfile(s, z)
    assert isinstance(info.value, ValueError)
    assert str(info.value).startswith(field + " must be")
    assert value in str(info.value)


def test_vertical_change_is_right_continuous_and_flat_beyond_the_ends():
    p = GroundProfile([0.0, 1.0, 1.0, 2.0], [0.0, 0.0, 0.3, 0.5])
    assert p.height(1.0) == pytest.approx(0.3)
    assert p.height(0.999) == pytest.approx(0.0)
    assert p.height(1.5) == pytest.approx(0.4)
    assert p.height(-5.0) == 0.0 and p.height(9.0) == pytest.approx(0.5)
    js, dz = p.jumps
    assert js.tolist() == [1.0] and dz == pytest.approx([0.3])


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0, 5), st.floats(-1, 1)), min_size=2, max_size=12),
       st.lists(st.tuples(st.floats(-1, 6), st.floats(0, 2)), min_size=1, max_size=10))
# a drop within rounding of a 0.01 m raster cell's edge (found by hypothesis): the
# raster's query rounded onto the next cell and missed it
@example(vertices=[(0.04, 0.0), (0.04, -1.0)], intervals=[(0.04, 0.0)])
def test_max_height_is_exact_against_brute_force(vertices, intervals):
    vertices.sort(key=lambda v: v[0])
    p = GroundProfile([v[0] for v in vertices], [v[1] for v in vertices])
    a = np.array([i[0] for i in intervals])
    b = a + np.array([i[1] for i in intervals])
    got = p.max_height(a, b)
    for ai, bi, g in zip(a, b, got, strict=True):
        inside = (p.s >= ai) & (p.s <= bi)
        dense = p.height(np.linspace(ai, bi, 200)).max()
        expect = max(dense, p.z[inside].max() if inside.any() else -np.inf)
        assert g == pytest.approx(expect, abs=1e-12)
    # the conservative raster never underestimates
    raster = p.raster(-1.5, 8.5, 0.01)
    assert np.all(raster.max_height(a, b) >= got - 1e-12)


def test_shifted_translates_heights():
    p = GroundProfile.stairs(0.17, 0.3, 3)
    q = p.shifted(1.5, -0.2)
    x = np.linspace(-1, 4, 51)
    assert np.allclose(q.height(x + 1.5), p.height(x) - 0.2)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-3, 3), st.floats(-1, 1)), min_size=2, max_size=15),
       st.floats(-4, 1), st.floats(0.1, 8), st.sampled_from([0.01, 1 / 256, 0.1]),
       st.booleans())
def test_raster_cells_equal_the_exact_range_maxima(vertices, start, width, cell, jump_first):
    vertices.sort(key=lambda v: v[0])
    s = np.array([v[0] for v in vertices])
    if jump_first:  # a vertical change right at the profile's start
        s[1] = s[0]
    p = GroundProfile(s, [v[1] for v in vertices])
    stop = start + width
    raster = p.raster(start, stop, cell)
    count = max(1, int(np.ceil((stop - start) / cell)))
    edges = start + cell * np.arange(count + 1)
    # bitwise: the raster finds the cells from the vertices instead of searching every edge
    assert np.array_equal(raster.heights, p.max_height(edges[:-1], edges[1:]))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(-3, 3), st.floats(-1, 1)), min_size=2, max_size=12),
       st.lists(st.tuples(st.floats(-4, 4), st.floats(-0.5, 2)), min_size=1, max_size=10))
def test_span_heights_are_the_range_maximum_and_both_end_heights(vertices, intervals):
    vertices.sort(key=lambda v: v[0])
    p = GroundProfile([v[0] for v in vertices], [v[1] for v in vertices])
    a = np.array([i[0] for i in intervals])
    b = a + np.array([i[1] for i in intervals])  # some intervals empty (b < a)
    highest, at_a, at_b = p.span_heights(a, b)
    assert np.array_equal(highest, p.max_height(a, b))
    assert np.array_equal(at_a, p.height(a)) and np.array_equal(at_b, p.height(b))


def _drop_below_edge(edge=3.0, start=-1.5):
    """A profile that drops 0.2 m one ulp before the raster edge ``edge`` [m], and its
    raster from ``start`` (there ``x - start`` of the drop rounds up onto the edge)."""
    x = np.nextafter(edge, -np.inf)
    p = GroundProfile([0.0, x, x, 5.0], [0.2, 0.2, 0.0, 0.0])
    return p, p.raster(start, 5.0, RASTER_CELL), x


def test_raster_query_starting_just_before_a_cell_edge_keeps_the_cell_before_it():
    # old: ((x - start) * 256) rounded onto the edge's cell, missing the drop's top
    p, raster, x = _drop_below_edge()
    a, b = np.array([x]), np.array([3.2])
    assert p.max_height(a, b)[0] == 0.2
    assert raster.max_height(a, b)[0] == 0.2
    assert raster.vertices_between(a, b)[0] >= 2


def test_compiled_raster_query_agrees_with_the_vectorised_one_at_cell_edges():
    p, raster, x = _drop_below_edge()
    table = np.ascontiguousarray(raster.table(TABLE_LEVELS))
    scale = 1.0 / raster.cell
    assert _raster_max(x, 3.2, raster.start, raster.cell, scale, table) == 0.2
    # every query ending one ulp either side of an edge, or on it, gives the same cell
    # maximum and vertex count in both
    edges = raster.start + raster.cell * np.arange(raster.heights.size + 1)
    ends = np.concatenate([np.nextafter(edges, -np.inf), edges, np.nextafter(edges, np.inf)])
    lo = np.concatenate([ends[:-1], ends[1:]])
    hi = np.concatenate([ends[1:], ends[1:] + 0.05])
    lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
    want = raster.max_height(lo, hi)
    got = [_raster_max(a, b, raster.start, raster.cell, scale, table)
           for a, b in zip(lo, hi, strict=True)]
    assert np.array_equal(got, want)
    want_v = raster.vertices_between(lo, hi)
    got_v = [_raster_vertices(a, b, raster.start, raster.cell, scale, raster.vertex_cum)
             for a, b in zip(lo, hi, strict=True)]
    assert np.array_equal(got_v, want_v)


@settings(max_examples=60, deadline=None)
@given(st.floats(-4, 1), st.sampled_from([0.01, 1 / 256, 0.1, 0.3]),
       st.lists(st.tuples(st.integers(0, 400), st.integers(-2, 2)), min_size=1,
                max_size=20))
def test_cell_index_is_the_exact_cell_of_points_at_and_near_edges(start, cell, points):
    count = 300
    edges = start + cell * np.arange(count + 1)  # as GroundProfile.raster computes them
    x = np.array([edges[min(k, count)] for k, _ in points])
    for i, (_, ulps) in enumerate(points):
        for _ in range(abs(ulps)):
            x[i] = np.nextafter(x[i], np.sign(ulps) * np.inf)
    got = cell_index(x, start, cell, count)
    # exact: the last cell whose left edge (as computed) is <= x, 0 before the raster
    want = np.clip(np.searchsorted(edges[:count], x, side="right") - 1, 0, count - 1)
    assert np.array_equal(got, want)
    compiled = [_cell(xi, start, cell, 1.0 / cell, count) for xi in x]
    assert np.array_equal(compiled, want)
