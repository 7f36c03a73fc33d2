"""Steering targets at a door (crowd.routing.steering_targets): the opt-in lane keeping
and lining up choose targets whose straight line keeps a body clear of the door posts."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import shapely

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.navigation import RouteTable
from crowdwalk.crowd.params import CrowdParams, crowd_model
from crowdwalk.crowd.routing import steering_targets

# a 4 m wide corridor along +x with a 0.2 m thick wall at x = 2.0-2.2 and a door
# |y| < 0.45 in it; the route is the corridor's centre line y = 0
AREA = shapely.box(-2, -2, 6, 2).difference(
    shapely.union(shapely.box(2.0, 0.45, 2.2, 2), shapely.box(2.0, -2, 2.2, -0.45)))


def line():
    """A route table of one straight route along +x, x = -10 ... 10 m (arc length x + 10)."""
    table = RouteTable()
    table.add(np.array([[-10.0, 0.0], [10.0, 0.0]]))
    return table


def least_clearance(field, a, b):
    """Least clearance [m] along the straight lines a -> b (k, 2), densely sampled."""
    f = np.linspace(0.0, 1.0, 201)
    pts = a[:, None, :] + f[None, :, None] * (b - a)[:, None, :]
    return field(pts.reshape(-1, 2)).reshape(len(a), -1).min(axis=1)


def targets(params, xy):
    field = ClearanceField.from_area(AREA)
    k = len(xy)
    target, _ = steering_targets(line(), route=np.zeros(k, int), progress=xy[:, 0] + 10.0,
                                 xy=xy, heading=np.zeros(k), radius=np.full(k, 0.2),
                                 clearance=field, params=params)
    return field, target


def test_a_walker_beside_a_door_lines_up_with_it_instead_of_grazing_the_post():
    # walkers 0.8-1.0 m before the wall and 0.7-0.9 m off the door's axis: the lane ahead
    # runs into the wall, and no lane beside the axis clears the post
    xy = np.array([[1.0, 0.9], [1.2, 0.8], [1.1, -0.7]])
    plain = crowd_model("free")  # lane_keep and line_up off (S175, the default, has both)
    field, t0 = targets(plain, xy)
    _, t1 = targets(replace(plain, line_up=True), xy)
    before = least_clearance(field, xy, t0)
    after = least_clearance(field, xy, t1)
    assert (before < 0.2).all()  # the line to the point 2 m ahead grazes a door post
    assert np.allclose(t1[:, 1], 0.0)  # lined up: a point on the centre line
    assert (t1[:, 0] > 2.0).all()  # through the door, not back
    assert (after > before + 0.1).all() and (after >= 0.1).all()


def test_lane_keeping_keeps_a_walker_off_axis_where_its_lane_fits_the_door():
    # 0.9 m off the axis, 1.9 m before the wall: the lane ahead ends in the wall, one
    # 0.2 m off the axis fits the door
    xy = np.array([[0.1, 0.9], [0.1, -0.9]])
    plain = crowd_model("free")  # lane_keep and line_up off (S175, the default, has both)
    field, t0 = targets(plain, xy)
    _, t1 = targets(replace(plain, lane_keep=True), xy)
    assert np.allclose(t0[:, 1], 0.0)  # without: everybody aims at the centre line
    assert np.allclose(np.abs(t1[:, 1]), 0.2)  # the widest lane that fits
    assert (np.sign(t1[:, 1]) == np.sign(xy[:, 1])).all()  # on the walker's side
    assert (field(t1) >= 0.2).all()


def test_lining_up_never_aims_under_the_walkers_own_body():
    # a dead end 0.3 m ahead of a walker on the centre line: every centre-line point
    # ahead is in or too near the wall, only its own projection clears; aiming there (a
    # few centimetres off) gave no direction and a lone walker beside RiMEA 9's door
    # stood there for 300 s
    field = ClearanceField.from_area(shapely.box(-2, -2, 2, 2))
    xy = np.array([[1.7, 0.0], [1.65, 0.03]])
    k = len(xy)
    params = CrowdParams(lane_keep=True, line_up=True)
    target, _ = steering_targets(line(), route=np.zeros(k, int), progress=xy[:, 0] + 10.0,
                                 xy=xy, heading=np.zeros(k), radius=np.full(k, 0.2),
                                 clearance=field, params=params)
    assert (np.linalg.norm(target - xy, axis=1) >= 0.2).all(), target
