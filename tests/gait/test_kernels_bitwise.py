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


def test_sample_kernel_equals_the_numpy_code():
    c2, c3 = RNG.normal(size=(100, 4)), RNG.normal(size=(50, 100, 4))
    rows = RNG.integers(0, 50, T.size)
    cases = [(c2, T, None), (c2, T[:12].reshape(3, 4), None), (c2, 0.3, None),
             (c3, T[:50], None), (c3, T, rows), (c3, 0.25, None)]
    for curves, t, r in cases:
        want = D._sample_numpy(np.asarray(curves), np.asarray(t, float), r)
        assert _same(D.sample(curves, t, rows=r), want)


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


@pytest.mark.parametrize("ij", [(1, 2), (2, 0), (0, 1)])
def test_rotation_kernel_equals_the_numpy_code(ij):
    for a in (5 * T, T[:12].reshape(3, 4), 0.7, np.array([np.nan, -0.0, 1e300])):
        assert _same(B._elementary(a, *ij), B._elementary_numpy(np.asarray(a, float), *ij))


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


def test_step_measure_kernel_equals_the_numpy_code():
    from crowdwalk.gait.elevinterp import (
        LEG_FIELDS,
        SagittalLeg,
        _dimension,
        _step_of_numpy,
        step_of,
    )

    def numpy_step(stance, swing, leg):
        dims = [np.asarray(_dimension(leg, k), dtype=float) for k in LEG_FIELDS]
        return _step_of_numpy(np.asarray(stance, float), np.asarray(swing, float), dims)

    stance, swing = RNG.normal(0, 0.5, (500, 4)), RNG.normal(0, 0.5, (500, 4))
    stance[:5, 0], swing[5:10, 0] = 0.0, -0.0
    legs = SagittalLeg.from_body_height(RNG.uniform(1.4, 2.0, 500))
    for st, sw, leg in ((stance, swing, legs), (stance, swing, SagittalLeg.from_body_height(1.7)),
                        (stance[0], swing[0], SagittalLeg.from_body_height(1.7)),
                        (stance[:, :3], swing[0], legs)):
        assert _same(step_of(st, sw, leg), numpy_step(st, sw, leg))
