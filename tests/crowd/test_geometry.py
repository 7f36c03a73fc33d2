"""Segment distances (swept bodies) against shapely."""

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.crowd.geometry import point_segment_distance, segment_distance

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
