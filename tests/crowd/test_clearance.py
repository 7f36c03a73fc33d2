"""The clearance field's numba sampler gives scipy's bilinear values bit for bit."""

import numpy as np
import shapely
from scipy import ndimage

from crowdwalk.crowd.clearance import ClearanceField


def _scipy(field: ClearanceField, xy: np.ndarray) -> np.ndarray:
    g = (xy - field.origin) / field.cell
    return ndimage.map_coordinates(field.distance, [g[..., 1].ravel(), g[..., 0].ravel()],
                                   order=1, mode="constant", cval=-10.0).reshape(xy.shape[:-1])


def _field() -> ClearanceField:
    room = shapely.Polygon([(0, 0), (30, 0), (30, 10), (12, 10), (12, 20), (0, 20)])
    return ClearanceField.from_area(room.difference(shapely.Point(5, 5).buffer(2)))


def test_sampling_equals_scipy_map_coordinates_bit_for_bit():
    field = _field()
    rng = np.random.default_rng(3)
    ny, nx = field.distance.shape
    nodes = np.stack(np.meshgrid(field.origin[0] + field.cell * np.arange(-2, nx + 2),
                                 field.origin[1] + field.cell * np.arange(-2, ny + 2)), -1)
    for xy in (rng.uniform(-3.0, 35.0, (200_000, 2)),  # inside, near walls, off the grid
               nodes, nodes + [1e-13, -1e-13],  # on nodes, the grid's last ones, just off
               rng.uniform(0.0, 30.0, (50, 7, 2)),  # any leading shape
               np.array([[np.nan, 1.0], [1.0, np.inf], [-np.inf, 2.0]])):
        ours, theirs = field(xy), _scipy(field, xy)
        assert ours.shape == xy.shape[:-1]
        assert np.array_equal(ours.view(np.int64), theirs.view(np.int64))
    assert np.all(field(np.array([[np.nan, 1.0], [-5.0, 1.0]])) == -10.0)  # not walkable
