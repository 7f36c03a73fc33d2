"""Segment distances (swept bodies) against shapely."""

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.crowd.geometry import moving_distance, point_segment_distance, segment_distance

coord = st.integers(-500, 500).map(lambda v: v / 100)  # cm grid: GEOS dislikes subnormals
point = st.tuples(coord, coord)


@settings(max_examples=60, deadline=None)
@given(point, point, point, point)
def test_segment_distance_matches_shapely(p0, p1, q0, q1):
    d = segment_distance(*(np.array(v, float) for v in (p0, p1, q0, q1)))
    ref = shapely.LineString([p0, p1]).distance(shapely.LineString([q0, q1])) if (
        p0 != p1 and q0 != q1) else shapely.distance(
        shapely.LineString([p0, p1]) if p0 != p1 else shapely.Point(p0),
        shapely.LineString([q0, q1]) if q0 != q1 else shapely.Point(q0))
    assert abs(float(d) - ref) < 1e-7


def test_broadcasting_shapes():
    p = np.zeros((3, 1, 2))
    q = np.ones((1, 4, 2))
    assert segment_distance(p, p + 1, q, q + 2).shape == (3, 4)
    assert point_segment_distance(np.array([0.0, 1.0]), np.zeros(2), np.array([2.0, 0.0])) == 1.0


@settings(max_examples=60, deadline=None)
@given(point, point, point, point, st.floats(0.0, 2.0), st.floats(0.0, 2.0))
def test_moving_distance_is_the_closest_approach_in_time(a, va, b, vb, ta, tb):
    a, va, b, vb = (np.array(v, float) for v in (a, va, b, vb))
    d = moving_distance(a, va, np.float64(ta), b, vb, np.float64(tb))
    t = np.linspace(0.0, 2.5, 5001)[:, None]
    pa = a + va * np.minimum(t, ta)
    pb = b + vb * np.minimum(t, tb)
    sampled = np.linalg.norm(pa - pb, axis=1).min()
    assert d <= sampled + 1e-9
    assert d >= sampled - 2.5 / 5000 * (np.linalg.norm(va) + np.linalg.norm(vb)) - 1e-9
