"""Vectorised 2-D geometry for the crowd: segment–segment distances (swept bodies)."""

from __future__ import annotations

import numpy as np

__all__ = ["point_segment_distance", "segment_distance"]


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance [m] from points ``p`` to segments ``a``–``b``; arrays (..., 2) broadcast,
    result (...)."""
    abx, aby = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    apx, apy = p[..., 0] - a[..., 0], p[..., 1] - a[..., 1]
    denom = abx * abx + aby * aby
    t = np.atleast_1d(apx * abx)  # an array (not a scalar) for the in-place steps below
    t += apy * aby
    t /= np.where(denom > 0, denom, 1.0)
    np.minimum(np.maximum(t, 0.0, out=t), 1.0, out=t)  # the nearest point's parameter
    # the offset from the nearest point, in place (large temporaries cost page faults)
    dx = np.atleast_1d(t * abx)
    np.subtract(apx, dx, out=dx)
    t *= aby
    np.subtract(apy, t, out=t)
    dx *= dx
    t *= t
    dx += t
    return np.sqrt(dx, out=dx).reshape(np.broadcast_shapes(np.shape(apx), np.shape(abx)))


def segment_distance(
    p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray
) -> np.ndarray:
    """Smallest distance [m] between segments ``p0``–``p1`` and ``q0``–``q1``.

    Arrays (..., 2) broadcast against each other; result (...). Degenerate segments
    (points) are allowed. Zero when the segments cross.
    """
    d = np.minimum(
        np.minimum(point_segment_distance(p0, q0, q1), point_segment_distance(p1, q0, q1)),
        np.minimum(point_segment_distance(q0, p0, p1), point_segment_distance(q1, p0, p1)),
    )
    r, s = p1 - p0, q1 - q0
    denom = _cross(r, s)
    qp = q0 - p0
    ok = np.abs(denom) > 1e-15
    safe = np.where(ok, denom, 1.0)
    t = _cross(qp, s) / safe
    u = _cross(qp, r) / safe
    crossing = ok & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    return np.where(crossing, 0.0, d)
