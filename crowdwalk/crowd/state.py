"""The agents' state between ticks, struct-of-arrays (:class:`AgentState`)."""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["AgentState", "WAITING", "ACTIVE", "ARRIVED"]

WAITING, ACTIVE, ARRIVED = 0, 1, 2


class AgentState:
    """Struct-of-arrays state of n agents (one array per field, leading dimension n)."""

    def __init__(self, n: int) -> None:
        self.status = np.full(n, WAITING, dtype=np.int8)
        self.pos0 = np.zeros((n, 2))  # body position at the start of the current step [m]
        self.pos1 = np.zeros((n, 2))  # ... at its end [m]
        self.z0 = np.zeros(n)
        self.z1 = np.zeros(n)
        self.t0 = np.zeros(n)  # start of the current step or wait [s]
        self.t1 = np.zeros(n)  # its end = next decision [s]
        self.heading = np.zeros(n)  # [rad]
        self.yaw0 = np.zeros(n)  # torso facing at the start of the current step [rad]
        self.yaw1 = np.zeros(n)  # ... at its end (turns linearly in time; unwrapped) [rad]
        self.stance = np.zeros((n, 2))  # centre-line point of the newest foothold [m]
        self.stance_z = np.zeros(n)
        self.trail = np.zeros((n, 2))  # centre-line point of the previous foothold [m]
        self.trail_z = np.zeros(n)
        self.foot = np.zeros(n, dtype=np.int8)  # foot that swings next: 0 left, 1 right
        self.stance_foot = np.zeros((n, 3))  # foothold of the stance foot (with offset) [m]
        self.animated = np.zeros(n, bool)  # has received a step command
        self.route = np.zeros(n, dtype=np.int64)
        self.segment = np.zeros(n, dtype=np.int64)
        self.progress = np.zeros(n)  # global route arc length [m]
        self.best_progress = np.full(n, -np.inf)  # furthest route arc length reached [m]
        self.progress_time = np.zeros(n)  # when it last grew by ``progress_step`` [s]
        self.gain_time = np.zeros(n)  # the same, not reset by a look for a new route [s]
        self.steps = np.zeros(n, dtype=np.int64)
        self.distance = np.zeros(n)  # walked by the body [m]
        self.energy = np.zeros(n)  # [J/kg]
        self.climb = np.zeros(n)  # total rise [m]
        self.wait = np.zeros(n)  # total standing time [s]
        self.stuck = np.zeros(n)  # standing time since the last step [s]
        self.start_time = np.full(n, np.nan)
        self.arrival_time = np.full(n, np.nan)
        self.plans = np.zeros(n, dtype=np.int64)
        self.plan_failures = np.zeros(n, dtype=np.int64)
        self.shortened = np.zeros(n, dtype=np.int64)
        self.reroutes = np.zeros(n, dtype=np.int64)

    def position(self, t: float, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Body positions (k, 2) [m] and heights (k,) [m] of agents ``idx`` at time t."""
        return _position(float(t), np.asarray(idx, np.int64), self.t0, self.t1, self.pos0,
                         self.pos1, self.z0, self.z1)

    def yaw(self, t: float, idx: np.ndarray) -> np.ndarray:
        """Torso facing (k,) [rad] of agents ``idx`` at time t (not wrapped)."""
        return _between(float(t), np.asarray(idx, np.int64), self.t0, self.t1, self.yaw0,
                        self.yaw1)


@nb.njit(cache=True, nogil=True, inline="always")
def _fraction(t, t0, t1):
    """How far [0, 1] a step from t0 to t1 [s] has gone at t (a step of no length: by
    the seconds since t0)."""
    span = t1 - t0
    f = (t - t0) / (span if span > 0 else 1.0)
    return 0.0 if f < 0.0 else 1.0 if f > 1.0 else f


@nb.njit(cache=True, nogil=True)
def _position(t, idx, t0, t1, pos0, pos1, z0, z1):
    xy = np.empty((idx.size, 2))
    z = np.empty(idx.size)
    for k in range(idx.size):
        i = idx[k]
        f = _fraction(t, t0[i], t1[i])
        xy[k, 0] = pos0[i, 0] + f * (pos1[i, 0] - pos0[i, 0])
        xy[k, 1] = pos0[i, 1] + f * (pos1[i, 1] - pos0[i, 1])
        z[k] = z0[i] + f * (z1[i] - z0[i])
    return xy, z


@nb.njit(cache=True, nogil=True)
def _between(t, idx, t0, t1, a, b):
    out = np.empty(idx.size)
    for k in range(idx.size):
        i = idx[k]
        out[k] = a[i] + _fraction(t, t0[i], t1[i]) * (b[i] - a[i])
    return out
