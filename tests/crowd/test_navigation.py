"""The concatenated route table: projection, points ahead, shared routes."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.crowd.navigation import RouteTable


def test_projection_and_point_ahead_on_two_routes():
    table = RouteTable()
    a = table.add([[0, 0], [10, 0]])
    b = table.add([[0, 0], [0, 5], [5, 5]])
    assert table.add(np.array([[0.0, 0], [10, 0]])) == a  # identical routes are shared
    route = np.array([a, b])
    seg, s, off = table.project(route, table.start[route], np.array([[3.0, 1.0], [1.0, 5.2]]))
    np.testing.assert_allclose(s - table.s0[route], [3.0, 6.0])
    np.testing.assert_allclose(off, [1.0, 0.2])
    np.testing.assert_allclose(table.point_at(route, s + 2), [[5, 0], [3, 5]])
    np.testing.assert_allclose(table.point_at(route, s + 100), [[10, 0], [5, 5]])  # clipped
    np.testing.assert_allclose(table.length(route), [10, 10])


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(-200, 200), st.integers(-200, 200)), min_size=2,
                max_size=8, unique=True), st.floats(0, 1))
def test_point_at_lies_on_the_polyline(points, fraction):
    import shapely

    table = RouteTable()
    points = [(x / 10, y / 10) for x, y in points]  # a 10 cm grid
    rid = table.add(np.array(points))
    line = shapely.LineString(points)
    s = table.s0[rid] + fraction * table.length(np.array([rid]))[0]
    p = table.point_at(np.array([rid]), np.array([s]))[0]
    assert line.distance(shapely.Point(p)) < 1e-6
    assert abs(line.project(shapely.Point(p)) - fraction * line.length) < 1e-6 or \
        not line.is_simple
