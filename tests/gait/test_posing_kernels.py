"""The compiled posing kernels give the numpy code's values (docs/architecture.md, "Posing
speed"): bit for bit where numpy's 3x3 products are the fma chain they reproduce (this
machine's OpenBLAS), within an ulp per product elsewhere."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from crowdwalk.body import Body, rotation_x, rotation_y, rotation_z
from crowdwalk.gait import posing_kernels as pk
from crowdwalk.gait.datasets import _sample_kernel, _sample_numpy, pelvis_motion
from crowdwalk.gait.foot import StanceFoot, stance_foot_pose
from crowdwalk.terrain.features import _covers_polygon, _in_bbox, _is_box

RNG = np.random.default_rng(16)


def _numpy_products_are_fma_chains() -> bool:
    a, b = RNG.normal(size=(200, 3, 3)), RNG.normal(size=(200, 3, 3))
    out = np.empty((3, 3))
    got = np.empty_like(a)
    for i in range(len(a)):
        pk._mm(a[i], b[i], out)
        got[i] = out
    return np.array_equal(got, a @ b)


EXACT = _numpy_products_are_fma_chains()


def _same(got, want):
    """Bitwise equal where numpy's products are fma chains, else within 1e-14."""
    got, want = np.asarray(got), np.asarray(want)
    if EXACT:
        assert got.dtype == want.dtype and np.array_equal(got, want)
    else:
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)


def test_products_are_numpys():
    a, b = RNG.normal(size=(500, 3, 3)), RNG.normal(size=(500, 3, 3))
    out, tout = np.empty_like(a), np.empty_like(a)
    for i in range(len(a)):
        pk._mm(a[i], b[i], out[i])
        pk._tmm(a[i], b[i], tout[i])
    _same(out, a @ b)
    _same(tout, np.swapaxes(a, 1, 2) @ b)
    # the rounded sum of three products is not what numpy computes here
    plain = sum(a[:, :, j, None] * b[:, None, j, :] for j in range(3))
    if EXACT:
        assert not np.array_equal(plain, out)


def test_pelvis_rotations_are_numpys_chain():
    yaw, lst, tilt = (RNG.uniform(-np.pi, np.pi, 1000) for _ in range(3))
    _same(pk.pelvis_rotations(yaw, lst, tilt),
          rotation_z(yaw) @ rotation_x(lst) @ rotation_y(tilt))


def test_upper_body_is_the_numpy_code():
    k, nj = 300, 20
    local = RNG.normal(size=(k, nj, 3, 3))
    want = local.copy()
    r_pelvis = rotation_z(RNG.uniform(-3, 3, k)) @ rotation_y(RNG.uniform(-0.3, 0.3, k))
    yaw_a, sway, tilt, heading = (RNG.uniform(-1, 1, k) for _ in range(4))
    arm_out, swing, elbow = (RNG.uniform(-1, 1, (k, 2)) for _ in range(3))
    # the numpy code the kernel replaced (elevwalker._styled_upper_body before pose16)
    yaw = rotation_z(yaw_a)
    trunk = yaw @ rotation_x(sway) @ rotation_y(tilt)
    want[:, 3] = np.swapaxes(r_pelvis, 1, 2) @ trunk
    want[:, 4] = np.swapaxes(trunk, 1, 2) @ rotation_z(heading)
    for s, (sh, el) in enumerate(((5, 6), (7, 8))):
        upper = yaw @ rotation_x(arm_out[:, s]) @ rotation_y(swing[:, s])
        want[:, sh] = np.swapaxes(trunk, 1, 2) @ upper
        want[:, el] = rotation_y(elbow[:, s])
    pk.upper_body(local, r_pelvis, yaw_a, sway, tilt, heading, arm_out, swing, elbow, 3, 4,
                  np.array([5, 7]), np.array([6, 8]))
    _same(local, want)


def test_stance_foot_is_the_numpy_code():
    k = 2000
    body = Body.from_heights(RNG.uniform(1.5, 1.95, k))
    foot = StanceFoot(RNG.normal(size=(k, 3)), RNG.uniform(-3, 3, k), RNG.uniform(-0.2, 0.2, k))
    pitch = RNG.uniform(-0.6, 0.6, k)
    got = stance_foot_pose(body, foot, pitch)
    # the numpy code (foot.stance_foot_pose before pose16)
    r_foot = rotation_z(foot.yaw) @ rotation_y(-pitch)
    on_heel = pitch >= foot.slope
    z = np.zeros(k)
    heel_to_ankle = np.stack([body.heel_offset, z, body.ankle_height], axis=1)
    ball_to_ankle = np.stack([-body.ball_offset, z, body.ankle_height], axis=1)
    pivot = np.where(on_heel[:, None], foot.heel(body), foot.ball)
    ankle = pivot + np.einsum("kab,kb->ka", r_foot,
                              np.where(on_heel[:, None], heel_to_ankle, ball_to_ankle))
    toe = np.where(on_heel, 0.0, pitch - foot.slope)
    _same(got[0], r_foot)
    np.testing.assert_allclose(got[1], ankle, rtol=0, atol=1e-14)  # einsum's order may vary
    assert np.array_equal(got[2], toe)
    assert on_heel.any() and (~on_heel).any()


def test_smoothstep_keeps_clip_semantics():
    x = np.concatenate([RNG.normal(0.5, 1.0, 10_000),
                        [0.0, -0.0, 1.0, 1e-300, -1e-300, np.inf, -np.inf, np.nan]])
    c = np.clip(x, 0.0, 1.0)
    want = c * c * (3.0 - 2.0 * c)
    got = pk.smoothstep(x)
    assert np.array_equal(got.view(np.uint64), want.view(np.uint64))  # signs of zero too
    assert pk.smoothstep(x.reshape(-1, 8)).shape == (len(x) // 8, 8)


def test_sample_kernel_wraps_indices_as_the_numpy_code():
    curves = RNG.normal(size=(7, 100, 4))
    t = np.concatenate([RNG.uniform(-3, 3, 20_000), np.arange(-300, 301) / 100,
                        [1 - 2**-53, -1e-20, 0.0, -0.0, 0.5, 1.5, 2.0]])
    rows = RNG.integers(0, 7, t.size).astype(np.intp)
    out = np.empty((t.size, 4))
    _sample_kernel(curves, t, rows, out)
    assert np.array_equal(out, _sample_numpy(curves, t, rows))


def test_pelvis_shapes_in_one_pass_are_the_two_series():
    t = RNG.uniform(0, 1, 5000)
    m = pelvis_motion()
    lst, rot = m.shapes(t)
    assert np.array_equal(lst, m.list_shape(t)) and np.array_equal(rot, m.rotation_shape(t))


@pytest.mark.parametrize("ring, box", [
    ([[0, 25], [80, 25], [80, 50], [0, 50]], True),
    ([[0.1, 0.3], [1.7, 0.3], [1.7, 2.9], [0.1, 2.9]], True),
    ([[0, 0], [1, 0], [1, 1], [0.5, 1.2], [0, 1]], False),
    ([[0, 0], [2, 1], [1, 3], [-1, 2]], False),  # a rotated rectangle
])
def test_box_polygons_cover_their_closed_bbox(ring, box):
    poly = Polygon(ring)
    shapely.prepare(poly)
    b = poly.bounds
    assert _is_box(poly, b) is box
    edge_x = [b[0], b[2], np.nextafter(b[0], -np.inf), np.nextafter(b[2], np.inf)]
    xs = np.concatenate([RNG.uniform(b[0] - 1, b[2] + 1, 20_000), np.repeat(edge_x, 50)])
    ys = np.concatenate([RNG.uniform(b[1] - 1, b[3] + 1, 20_000),
                         np.tile(np.linspace(b[1] - 0.1, b[3] + 0.1, 50), 4)])
    xy = np.column_stack([xs, ys])
    want = _in_bbox(xy, b)
    want[want] = shapely.intersects_xy(poly, xy[want, 0], xy[want, 1])
    assert np.array_equal(_covers_polygon(poly, b, xy), want)


def _numpy_is_libm(ufunc, math_fn, *samples) -> bool:
    libm = np.array([math_fn(*v) for v in zip(*samples, strict=True)])
    return np.array_equal(ufunc(*samples), libm)


def _shifted_stance_leg_numpy(l1, l2, phi_shank, phi_thigh, heading, offset):
    """``elevwalker._shifted_stance_leg`` before pose16, in numpy, for thigh and shank
    lengths l1, l2 (k,) [m] (the reference of ``posing_kernels.shifted_stance_leg``)."""
    ch, sh = np.cos(heading), np.sin(heading)
    # Data hip relative to the ankle in sagittal coordinates (forward, up).
    fwd = -l2 * np.sin(phi_shank) - l1 * np.sin(phi_thigh)
    up = l2 * np.cos(phi_shank) + l1 * np.cos(phi_thigh)
    fwd = fwd + offset[:, 0] * ch + offset[:, 1] * sh
    up = up + offset[:, 2]
    dist = np.clip(np.hypot(fwd, up), np.abs(l1 - l2) + 1e-6, 0.999 * (l1 + l2))
    line = np.arctan2(-fwd, up)  # elevation of the hip→ankle line
    at_hip = np.arccos(np.clip((l1**2 + dist**2 - l2**2) / (2 * l1 * dist), -1.0, 1.0))
    at_ankle = np.arccos(np.clip((l2**2 + dist**2 - l1**2) / (2 * l2 * dist), -1.0, 1.0))
    return line - at_ankle, line + at_hip


def test_shifted_stance_leg_is_the_numpy_code():
    """pose16's kernel against :func:`_shifted_stance_leg_numpy`: bitwise where
    numpy's hypot and arccos are libm's (which numba calls); on a CPU whose numpy uses its
    own SIMD loops (AVX-512: they differ in ~1 % and ~10 % of values) the kernel differs
    from the numpy code in ~7 % of elevations, by at most one ulp of 1 (2.2e-16 rad measured
    on 100,000 rows); the bound asserted is two ulps of π."""
    import math

    n = 20000
    l1 = RNG.uniform(0.38, 0.5, n)
    l2 = l1 * RNG.uniform(0.85, 1.05, n)
    phi_shank, phi_thigh = RNG.uniform(-0.6, 0.6, n), RNG.uniform(-0.5, 0.5, n)
    heading = RNG.uniform(-np.pi, np.pi, n)
    offset = RNG.normal(0.0, 0.03, (n, 3))
    offset[:50] *= 100.0  # hip out of reach: the clipped distance
    want = _shifted_stance_leg_numpy(l1, l2, phi_shank, phi_thigh, heading, offset)
    got = pk.shifted_stance_leg(l1, l2, phi_shank, phi_thigh, heading, offset)
    c = RNG.uniform(-1.0, 1.0, 5000)
    x, y = RNG.uniform(-1.0, 1.0, 5000), RNG.uniform(0.5, 1.0, 5000)
    libm = _numpy_is_libm(np.arccos, math.acos, c) and _numpy_is_libm(np.hypot, math.hypot, x, y)
    for g, w in zip(got, want, strict=True):
        assert np.isfinite(g).all()
        if libm:
            assert np.array_equal(g, w)
        else:
            np.testing.assert_allclose(g, w, rtol=0, atol=2 * np.spacing(np.pi))
