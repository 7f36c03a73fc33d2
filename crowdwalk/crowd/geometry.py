"""Vectorised 2-D geometry for the crowd: segment–segment distances (swept bodies)."""

from __future__ import annotations

import numpy as np

__all__ = ["distance", "moving_distance", "point_segment_distance", "segment_distance",
           "step_distance"]


def distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a - b| [m] of points (..., 2), broadcast; result (...). The value of
    ``np.linalg.norm(a - b, axis=-1)`` bit for bit (the same products, one sum, one square
    root), computed per coordinate: without the reduction over a last axis of 2, which
    numpy does slowly (a third of the steering's soft terms)."""
    dx = a[..., 0] - b[..., 0]
    dy = a[..., 1] - b[..., 1]
    dx *= dx
    dy *= dy
    dx += dy
    return np.sqrt(dx, out=dx)


def _distance_to(apx, apy, abx, aby) -> np.ndarray:
    """Distance [m] from points at offsets ``ap`` from segment starts to segments of
    direction ``ab`` (components, broadcast); in place where it can (large temporaries
    cost page faults)."""
    denom = abx * abx + aby * aby
    t = np.atleast_1d(apx * abx)  # an array (not a scalar) for the in-place steps below
    t += apy * aby
    t /= np.where(denom > 0, denom, 1.0)
    np.minimum(np.maximum(t, 0.0, out=t), 1.0, out=t)  # the nearest point's parameter
    dx = np.atleast_1d(t * abx)  # the offset from the nearest point
    np.subtract(apx, dx, out=dx)
    t *= aby
    np.subtract(apy, t, out=t)
    dx *= dx
    t *= t
    dx += t
    return np.sqrt(dx, out=dx).reshape(np.broadcast_shapes(np.shape(apx), np.shape(abx)))


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance [m] from points ``p`` to segments ``a``–``b``; arrays (..., 2) broadcast,
    result (...)."""
    return _distance_to(p[..., 0] - a[..., 0], p[..., 1] - a[..., 1],
                        b[..., 0] - a[..., 0], b[..., 1] - a[..., 1])


def segment_distance(
    p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray
) -> np.ndarray:
    """Smallest distance [m] between segments ``p0``–``p1`` and ``q0``–``q1``.

    Arrays (..., 2) broadcast against each other; result (...). Degenerate segments
    (points) are allowed. Zero when the segments cross.
    """
    # p0-p1's direction is shared by the distances of q0 and q1 to it and the crossing
    rx, ry = p1[..., 0] - p0[..., 0], p1[..., 1] - p0[..., 1]
    sx, sy = q1[..., 0] - q0[..., 0], q1[..., 1] - q0[..., 1]
    ax, ay = q0[..., 0] - p0[..., 0], q0[..., 1] - p0[..., 1]  # q0 - p0
    d = np.minimum(point_segment_distance(p0, q0, q1), point_segment_distance(p1, q0, q1))
    d = np.minimum(d, _distance_to(ax, ay, rx, ry))
    d = np.minimum(d, _distance_to(q1[..., 0] - p0[..., 0], q1[..., 1] - p0[..., 1], rx, ry))
    denom = rx * sy - ry * sx
    ok = np.abs(denom) > 1e-15
    safe = np.where(ok, denom, 1.0)
    t = (ax * sy - ay * sx) / safe
    u = (ax * ry - ay * rx) / safe
    crossing = ok & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    return np.where(crossing, 0.0, d)


def _closest_on_piece(r0: np.ndarray, w: np.ndarray, span: np.ndarray) -> np.ndarray:
    """min over s in [0, span] of |r0 + w s| (arrays (..., 2), span (...))."""
    ww = w[..., 0] * w[..., 0] + w[..., 1] * w[..., 1]
    s = np.clip(-(r0[..., 0] * w[..., 0] + r0[..., 1] * w[..., 1]) / np.where(ww > 0, ww, 1.0),
                0.0, span)
    return np.hypot(r0[..., 0] + s * w[..., 0], r0[..., 1] + s * w[..., 1])


def moving_distance(a: np.ndarray, va: np.ndarray, ta: np.ndarray, b: np.ndarray,
                    vb: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Closest approach [m] of two points that move from now on (time 0) and then stand.

    Point A is at ``a`` now and moves with velocity ``va`` [m/s] for ``ta`` [s] (>= 0),
    then stands; likewise B (``b``, ``vb``, ``tb``). Arrays (..., 2) and (...) broadcast;
    result (...): the least distance between them at any time >= 0 (exact: the relative
    position is piecewise linear in time with breaks at ``ta`` and ``tb``).
    """
    t1 = np.minimum(ta, tb)
    t2 = np.maximum(ta, tb)
    r0 = a - b
    w1 = va - vb
    d = _closest_on_piece(r0, w1, t1)
    r1 = r0 + t1[..., None] * w1
    w2 = np.where((ta < tb)[..., None], -vb, va)  # after the first stops, the other moves
    d = np.minimum(d, _closest_on_piece(r1, w2, t2 - t1))
    return d  # the last piece (both standing) is the end of the second one


def step_distance(start: np.ndarray, end: np.ndarray, duration: np.ndarray,
                  elapsed: np.ndarray, q_now: np.ndarray, q_end: np.ndarray,
                  q_remaining: np.ndarray) -> np.ndarray:
    """Closest approach [m], from now on, of a body stepping and a neighbour (both stand at
    their ends afterwards): :func:`moving_distance` of steps given by their ends.

    The body moves linearly from ``start`` to ``end`` (..., 2) [m] over ``duration`` (...)
    [s], of which ``elapsed`` (...) [s] have passed (its heel strike was that long ago);
    the neighbour moves from ``q_now`` to ``q_end`` in the ``q_remaining`` (...) [s] it
    has left (0: standing). Arrays broadcast; result (...).
    """
    gone = np.minimum(elapsed, duration)
    velocity = (end - start) / duration[..., None]
    q_velocity = (q_end - q_now) / np.where(q_remaining > 0, q_remaining, 1.0)[..., None]
    return moving_distance(start + gone[..., None] * velocity, velocity, duration - gone,
                           q_now, q_velocity, q_remaining)
