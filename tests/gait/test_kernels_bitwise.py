"""The compiled gait kernels give bitwise the values of the numpy code they replace."""

from __future__ import annotations

import numpy as np
import pytest

from crowdwalk import body as B
from crowdwalk.body import Body
from crowdwalk.gait import datasets as D
from crowdwalk.style import Style

RNG = np.random.default_rng(0)
T = np.concatenate([RNG.uniform(-3, 3, 4000),
                    [0.0, -0.0, 1 - 1e-17, -1e-17, 0.99999999999, 2.0, -1.0]])


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _sample_numpy(curves, t, rows=None):
    t = np.asarray(t, float)
    n = curves.shape[-2]
    u = np.mod(t, 1.0) * n
    i1 = np.floor(u).astype(np.intp)
    s = (u - i1)[..., None]
    i0, i2, i3 = (i1 - 1) % n, (i1 + 1) % n, (i1 + 2) % n
    i1 = i1 % n
    if curves.ndim == 2:
        p0, p1, p2, p3 = curves[i0], curves[i1], curves[i2], curves[i3]
    else:
        rows = np.arange(curves.shape[0]) if rows is None else np.asarray(rows)
        i0, i1, i2, i3 = np.broadcast_arrays(i0, i1, i2, i3, rows)[:4]
        p0, p1, p2, p3 = (curves[rows, i] for i in (i0, i1, i2, i3))
    s2 = s * s
    s3 = s2 * s
    return 0.5 * (2.0 * p1 + (p2 - p0) * s + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s2
                  + (3.0 * p1 - p0 - 3.0 * p2 + p3) * s3)


def test_sample_kernel_equals_the_numpy_code():
    c2, c3 = RNG.normal(size=(100, 4)), RNG.normal(size=(50, 100, 4))
    rows = RNG.integers(0, 50, T.size)
    cases = [(c2, T, None), (c2, T[:12].reshape(3, 4), None), (c2, 0.3, None),
             (c3, T[:50], None), (c3, T, rows), (c3, 0.25, None)]
    for curves, t, r in cases:
        assert _same(D.sample(curves, t, rows=r), _sample_numpy(curves, t, r))


def _series_numpy(coef, harmonics, t):
    t = np.asarray(t, float)[..., None]
    k = np.asarray(harmonics, float)
    return np.sum(coef[0::2] * np.cos(2 * np.pi * k * t)
                  + coef[1::2] * np.sin(2 * np.pi * k * t), axis=-1)


def test_shape_harmonics_kernel_equals_the_numpy_code():
    pm, tm = D.pelvis_motion(), D.trunk_motion()
    for coef, h in ((pm.list_coefficients, pm.harmonics),
                    (pm.rotation_coefficients, pm.harmonics),
                    (tm.tilt_coefficients, tm.tilt_harmonics),
                    (tm.rotation_coefficients, tm.rotation_harmonics)):
        for t in (T, T[:12].reshape(3, 4), 0.3):
            assert _same(D.PelvisMotion._series(coef, h, t), _series_numpy(coef, h, t))


def _elementary_numpy(angle, i, j):
    angle = np.asarray(angle, float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    k = 3 - i - j
    out[..., k, k] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


@pytest.mark.parametrize("ij", [(1, 2), (2, 0), (0, 1)])
def test_rotation_kernel_equals_the_numpy_code(ij):
    for a in (5 * T, T[:12].reshape(3, 4), 0.7, np.array([np.nan, -0.0, 1e300])):
        assert _same(B._elementary(a, *ij), _elementary_numpy(a, *ij))


def test_style_take_equals_building_the_rows():
    h = RNG.uniform(1.5, 1.9, 30)
    style = Style.default(h, RNG.uniform(0.8, 1.5, 30))
    for index in (np.array([3, 0, 29, 3]), np.arange(30) % 2 == 0, np.array([], int)):
        got = style.take(index)
        want = {k: getattr(style, k)[index] for k in style.__dataclass_fields__}
        assert isinstance(got, Style)
        for k, v in want.items():
            assert _same(getattr(got, k), v)
    body = Body.from_heights(h)
    got = body.take(np.array([5, 1]))
    for k in body.__dataclass_fields__:
        assert _same(getattr(got, k), getattr(body, k)[np.array([5, 1])])


def _step_of_numpy(stance, swing, leg):
    from crowdwalk.gait.elevinterp import LEG_FIELDS, _dimension, _segment

    thigh, shank, ankle_h, heel, toe = (
        np.asarray(_dimension(leg, k), dtype=float)[..., None] for k in LEG_FIELDS)
    f_st = stance[..., 0:1]
    u_st = np.concatenate([np.cos(f_st), np.sin(f_st)], axis=-1)
    n_st = np.concatenate([-np.sin(f_st), np.cos(f_st)], axis=-1)
    on_toe = f_st <= 0.0
    pivot_x = np.where(on_toe, toe, -heel)
    pivot = np.concatenate([pivot_x, np.zeros_like(pivot_x)], axis=-1)
    ankle = pivot + np.where(on_toe, -toe, heel) * u_st + ankle_h * n_st
    hip = ankle - shank * _segment(stance[..., 1]) - thigh * _segment(stance[..., 2])
    ankle_sw = hip + thigh * _segment(swing[..., 2]) + shank * _segment(swing[..., 1])
    f_sw = swing[..., 0:1]
    u_sw = np.concatenate([np.cos(f_sw), np.sin(f_sw)], axis=-1)
    n_sw = np.concatenate([-np.sin(f_sw), np.cos(f_sw)], axis=-1)
    heel_sw = ankle_sw - heel * u_sw - ankle_h * n_sw
    toe_sw = ankle_sw + toe * u_sw - ankle_h * n_sw
    on_heel = f_sw >= 0.0
    length = np.where(on_heel, heel_sw[..., 0:1] + heel, toe_sw[..., 0:1] - toe)
    height = np.where(on_heel, heel_sw[..., 1:2], toe_sw[..., 1:2])
    return np.concatenate([length, height], axis=-1)


def test_step_measure_kernel_equals_the_numpy_code():
    from crowdwalk.gait.elevinterp import SagittalLeg, step_of

    stance, swing = RNG.normal(0, 0.5, (500, 4)), RNG.normal(0, 0.5, (500, 4))
    stance[:5, 0], swing[5:10, 0] = 0.0, -0.0
    legs = SagittalLeg.from_body_height(RNG.uniform(1.4, 2.0, 500))
    for st, sw, leg in ((stance, swing, legs), (stance, swing, SagittalLeg.from_body_height(1.7)),
                        (stance[0], swing[0], SagittalLeg.from_body_height(1.7)),
                        (stance[:, :3], swing[0], legs)):
        assert _same(step_of(st, sw, leg), _step_of_numpy(st, sw, leg))
