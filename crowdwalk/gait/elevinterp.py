"""ElevInterp: elevation-angle datasets for a requested step length and height.

Sun & Metaxas (2001), §5. Placeholder header; the interpolator follows below.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from crowdwalk.errors import invalid

__all__ = ["LegLike", "SagittalLeg", "step_of"]


class LegLike(Protocol):
    """Anything with sagittal leg dimensions [m], floats or (n,) arrays (e.g. ``body.Body``)."""

    thigh: float | np.ndarray
    shank: float | np.ndarray
    ankle_height: float | np.ndarray
    heel_offset: float | np.ndarray
    toe_offset: float | np.ndarray


@dataclass(frozen=True)
class SagittalLeg:
    """Sagittal leg dimensions [m] for :func:`step_of` (floats or (n,) arrays).

    ``thigh`` hip→knee, ``shank`` knee→ankle, ``ankle_height`` ankle centre above the
    sole, ``heel_offset`` / ``toe_offset`` horizontal distance from the ankle to the back
    of the heel / the toe tip along the sole.
    """

    thigh: float | np.ndarray
    shank: float | np.ndarray
    ankle_height: float | np.ndarray
    heel_offset: float | np.ndarray
    toe_offset: float | np.ndarray

    @classmethod
    def from_body_height(cls, height: float | np.ndarray) -> SagittalLeg:
        """Segment lengths from body height [m] with Winter (2009, Fig. 4.1) proportions.

        thigh 0.245 H, shank 0.246 H, ankle height 0.039 H, foot length 0.152 H of which
        a quarter lies behind the ankle (heel) and three quarters ahead (toe).
        """
        h = np.asarray(height, dtype=float)
        if not np.all(np.isfinite(h) & (h > 0)):
            raise invalid("SagittalLeg", "height", "finite and > 0 [m]", height)
        if h.ndim == 0:
            h = float(h)
        return cls(0.245 * h, 0.246 * h, 0.039 * h, 0.038 * h, 0.114 * h)

    @property
    def length(self) -> float | np.ndarray:
        """Leg length: thigh + shank + ankle height [m]."""
        return self.thigh + self.shank + self.ankle_height


def _segment(phi: np.ndarray) -> np.ndarray:
    """Unit vector proximal→distal for an elevation angle [rad]; shape phi.shape + (2,)."""
    return np.stack([np.sin(phi), -np.cos(phi)], axis=-1)


def step_of(stance: np.ndarray, swing: np.ndarray, leg: LegLike) -> np.ndarray:
    """Step length and height a pair of leg silhouettes produces (Eq. 10, extended).

    Sagittal forward kinematics from the stance foot's ground contact up the stance leg
    and down the swing leg (Sun & Metaxas 2001, Eq. 10, Fig. 11). Deviations from Eq. 10:
    the pelvis terms are dropped (both hips project onto the same sagittal point, so the
    pelvis segment cancels), and the feet follow the foot–floor model of §4.1 — a foot
    with a negative elevation rolls on its toe, with a positive one on its heel. Step
    length and height are measured between *footholds* (the ground point below the ankle
    once the foot is flat, the ``planners`` convention): the stance foothold is the
    origin, the swing foothold is where the swing foot lands.

    Parameters
    ----------
    stance, swing : numpy.ndarray
        Shape (..., ≥3) elevation angles [rad], columns foot, shank, thigh(, pelvis):
        stance leg at ``t = 0.5`` and swing leg at ``t = 0`` (heel strike) for a dataset.
    leg : LegLike
        Leg dimensions [m], floats or arrays broadcastable to ``stance.shape[:-1]``.

    Returns
    -------
    numpy.ndarray
        Shape (..., 2): step length and step height [m].
    """
    stance = np.asarray(stance, dtype=float)
    swing = np.asarray(swing, dtype=float)
    thigh, shank, ankle_h, heel, toe = (
        np.asarray(getattr(leg, k), dtype=float)[..., None]
        for k in ("thigh", "shank", "ankle_height", "heel_offset", "toe_offset")
    )
    # Stance foot: pivot on the toe (foot pitched down) or on the heel, pivot fixed.
    f_st = stance[..., 0:1]
    u_st = np.concatenate([np.cos(f_st), np.sin(f_st)], axis=-1)  # heel→toe
    n_st = np.concatenate([-np.sin(f_st), np.cos(f_st)], axis=-1)  # sole normal, up
    on_toe = f_st <= 0.0
    pivot_x = np.where(on_toe, toe, -heel)
    pivot = np.concatenate([pivot_x, np.zeros_like(pivot_x)], axis=-1)
    ankle = pivot + np.where(on_toe, -toe, heel) * u_st + ankle_h * n_st
    hip = ankle - shank * _segment(stance[..., 1]) - thigh * _segment(stance[..., 2])
    # Swing leg down from the hip.
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
