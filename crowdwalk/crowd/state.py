"""The agents' state between ticks, struct-of-arrays (:class:`AgentState`)."""

from __future__ import annotations

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
        span = self.t1[idx] - self.t0[idx]
        f = np.clip((t - self.t0[idx]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
        xy = self.pos0[idx] + f[:, None] * (self.pos1[idx] - self.pos0[idx])
        return xy, self.z0[idx] + f * (self.z1[idx] - self.z0[idx])

    def yaw(self, t: float, idx: np.ndarray) -> np.ndarray:
        """Torso facing (k,) [rad] of agents ``idx`` at time t (not wrapped)."""
        span = self.t1[idx] - self.t0[idx]
        f = np.clip((t - self.t0[idx]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
        return self.yaw0[idx] + f * (self.yaw1[idx] - self.yaw0[idx])
