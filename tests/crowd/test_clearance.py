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


def test_the_block_bound_is_never_above_the_sampled_clearance():
    field = _field()
    xy = np.random.default_rng(5).uniform([-0.9, -0.9], [30.9, 20.9], (300_000, 2))
    g = ((xy - field.origin) / field.cell).astype(int) // 8
    assert (field.block_least[g[:, 1], g[:, 0]] <= field(xy)).all()
    assert (field.block_least > 1.0).any()  # and it does bound points away from the walls


def _walls_numpy(field, position, stance, ends, dirs, lengths, radius, foot_clearance):
    """The steering's wall test as numpy computed it before the kernel."""
    r = np.minimum(radius, field(position) - 1e-6)[:, None, None]
    at_end, halfway = field(ends), field(0.5 * (ends + position[:, None, None, :]))
    span = 0.25 * np.linalg.norm(ends - position[:, None, None, :], axis=-1)
    quarters = np.full(ends.shape[:-1], np.inf)
    i, c, l = np.nonzero(halfway < np.broadcast_to(r, halfway.shape) + span)
    p0, p1 = position[i], ends[i, c, l]
    quarters[i, c, l] = np.minimum(field(0.75 * p0 + 0.25 * p1), field(0.25 * p0 + 0.75 * p1))
    halfway = np.minimum(halfway, quarters)
    ok = (at_end >= r) & (halfway >= r)
    foot = stance[:, None, None, :] + lengths[None, None, :, None] * dirs[:, :, None, :]
    return ok & (field(foot) >= foot_clearance), np.minimum(at_end, halfway)


def test_step_walls_decide_as_sampling_everything():
    field = _field()
    rng = np.random.default_rng(11)
    m, n_c = 3000, 12
    lengths = np.array([0.15, 0.3, 0.45, 0.6, 0.75, 0.9])
    position = rng.uniform([-0.5, -0.5], [30.5, 20.5], (m, 2))  # some at and in the walls
    stance = position + rng.uniform(-0.2, 0.2, (m, 2))
    angle = rng.uniform(-np.pi, np.pi, (m, n_c))
    dirs = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    ends = stance[:, None, None, :] + 0.5 * lengths[None, None, :, None] * dirs[:, :, None, :]
    radius = rng.uniform(0.15, 0.3, m)
    reach = radius + rng.uniform(0.0, 0.2, m)
    ok, near = field.step_walls(position, stance, ends, dirs, lengths, radius, reach, 0.05)
    want_ok, want_near = _walls_numpy(field, position, stance, ends, dirs, lengths, radius,
                                      0.05)
    free = np.cumprod(ok, axis=2).sum(axis=2)
    want_free = np.cumprod(want_ok, axis=2).sum(axis=2)
    assert (want_free == 0).any() and (want_free == 6).any() and ((want_free % 6) > 0).any()
    np.testing.assert_array_equal(free, want_free)
    # where tested (up to the first blocked length) the same nearness to the walls
    tested = np.arange(6) <= np.minimum(free, 5)[..., None]
    np.testing.assert_array_equal((near < reach[:, None, None])[tested],
                                  (want_near < reach[:, None, None])[tested])
