"""Foot geometry shared by ElevWalker and the Animator: unit directions, angle wrapping,
the stance foot's contact (:class:`StanceFoot`) and pose (§4.1 foot–floor model), and the
feet's heel, ball and toe-tip points."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crowdwalk.body import LEG_JOINTS, Body, rotation_y, rotation_z

__all__ = ["direction", "wrap_angle", "mat_vec", "two_link_knee", "StanceFoot",
           "stance_foot_pose", "foot_points", "column_or", "SPIN_HEEL_LIFT"]

#: Heel height above its ground at which a spin turn (Sun & Metaxas §6.1) starts [m].
SPIN_HEEL_LIFT = 0.008


def column_or(steps, name: str, default: np.ndarray) -> np.ndarray:
    """``steps.name`` (m,) where present and finite, else ``default`` (m,)."""
    value = getattr(steps, name, None)
    if value is None:
        return np.asarray(default, float)
    value = np.asarray(value, float)
    return np.where(np.isfinite(value), value, default)


def direction(yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """Unit vectors (k, 3) with heading ``yaw`` and upward pitch ``pitch`` [rad]."""
    cp = np.cos(pitch)
    return np.stack([cp * np.cos(yaw), cp * np.sin(yaw), np.sin(pitch)], axis=-1)


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles [rad] wrapped to [-π, π)."""
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def two_link_knee(hip: np.ndarray, ankle: np.ndarray, thigh: np.ndarray, shank: np.ndarray,
                  forward: np.ndarray) -> np.ndarray:
    """Knee positions (k, 3) [m] of two-link legs from ``hip`` to ``ankle`` (k, 3) [m].

    The knee bends toward ``forward`` (k, 3), projected off the hip–ankle line; the
    hip–ankle distance is clamped to the leg's reach [|thigh − shank|, 0.99999 (thigh +
    shank)] (k,) [m], so a leg asked to reach too far is straight, never undefined.
    """
    d = ankle - hip
    dist = np.linalg.norm(d, axis=1)
    u = d / np.maximum(dist, 1e-12)[:, None]
    reach = np.clip(dist, np.abs(thigh - shank) + 1e-6, 0.99999 * (thigh + shank))
    f = forward - np.sum(forward * u, axis=1, keepdims=True) * u
    f = f / np.maximum(np.linalg.norm(f, axis=1, keepdims=True), 1e-12)
    a = (thigh**2 - shank**2 + reach**2) / (2.0 * reach)  # hip to the knee's foot on the line
    return hip + a[:, None] * u + np.sqrt(np.maximum(thigh**2 - a**2, 0.0))[:, None] * f


def mat_vec(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Batched matrix @ vector: (k,3,3) @ (k,3) or (3,) → (k,3)."""
    if v.ndim == 1:
        return m @ v
    return np.einsum("kab,kb->ka", m, v)


@dataclass(frozen=True, eq=False)
class StanceFoot:
    """Where the stance foot touches the ground, for k agents.

    Attributes
    ----------
    ball : numpy.ndarray
        (k, 3) world point under the first metatarsal head [m]; fixed during a step.
    yaw : numpy.ndarray
        (k,) direction the foot points, from +x [rad].
    slope : numpy.ndarray
        (k,) pitch of the ground along the foot, positive uphill [rad].
    """

    ball: np.ndarray
    yaw: np.ndarray
    slope: np.ndarray

    @classmethod
    def from_foothold(
        cls, body: Body, foothold: np.ndarray, yaw: np.ndarray, slope: np.ndarray
    ) -> StanceFoot:
        """The contact of a foot placed flat with its ankle above ``foothold`` (k, 3) [m]
        (the ``planners`` convention: a foothold is the ground point below the ankle)."""
        d = direction(yaw, slope)
        return cls(np.asarray(foothold, float) + body.ball_offset[:, None] * d, yaw, slope)

    def heel(self, body: Body) -> np.ndarray:
        """(k, 3) world point under the back of the heel when the foot is flat [m]."""
        d = direction(self.yaw, self.slope)
        return self.ball - (body.heel_offset + body.ball_offset)[:, None] * d


def stance_foot_pose(body: Body, foot: StanceFoot, pitch: np.ndarray):
    """Foot orientation, ankle position and toe angle from the foot–floor model (§4.1)."""
    k = len(body)
    if k and np.ndim(pitch) == 1:  # the code below, compiled (numpy's values)
        from crowdwalk.gait.posing_kernels import as_rows as f
        from crowdwalk.gait.posing_kernels import stance_foot

        return stance_foot(f(foot.yaw, (k,)), f(foot.slope, (k,)), f(pitch, (k,)),
                           f(foot.ball, (k, 3)), f(body.heel_offset, (k,)),
                           f(body.ball_offset, (k,)), f(body.ankle_height, (k,)))
    r_foot = rotation_z(foot.yaw) @ rotation_y(-pitch)
    on_heel = pitch >= foot.slope
    k = len(body)
    z = np.zeros(k)
    heel_to_ankle = np.stack([body.heel_offset, z, body.ankle_height], axis=1)
    ball_to_ankle = np.stack([-body.ball_offset, z, body.ankle_height], axis=1)
    pivot = np.where(on_heel[:, None], foot.heel(body), foot.ball)
    ankle = pivot + mat_vec(r_foot, np.where(on_heel[:, None], heel_to_ankle, ball_to_ankle))
    toe = np.where(on_heel, 0.0, pitch - foot.slope)  # toes stay flat on the ground
    return r_foot, ankle, toe


def foot_points(body: Body, positions: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """Heel, ball and toe-tip world points of both feet, (k, 2, 3, 3) [m].

    Axis 1 is left/right, axis 2 heel/ball/toe, from the joint positions and orientations
    of :func:`crowdwalk.body.forward_kinematics`.
    """
    k = len(body)
    out = np.empty((k, 2, 3, 3))
    z = np.zeros(k)
    heel_local = np.stack([-body.heel_offset, z, -body.ankle_height], axis=1)
    tip_local = np.stack([body.toe_offset - body.ball_offset, z, z], axis=1)
    for s in range(2):
        tc, sub, mtp = LEG_JOINTS[s, 2], LEG_JOINTS[s, 3], LEG_JOINTS[s, 4]
        out[:, s, 0] = positions[:, tc] + mat_vec(rotations[:, sub], heel_local)
        out[:, s, 1] = positions[:, mtp]
        out[:, s, 2] = positions[:, mtp] + mat_vec(rotations[:, mtp], tip_local)
    return out
