"""Legality of a foothold and of a step (§4.2, §5.2), vectorised, with reasons."""

from __future__ import annotations

from enum import IntFlag

import numpy as np

from planners.config import PlannerConfig
from planners.profile import GroundProfile

__all__ = ["Reason", "foot_support", "describe", "snap_to_support"]


class Reason(IntFlag):
    """Why a step is illegal (bit flags; 0 means legal)."""

    EDGE = 1  #: a stair edge, riser or block side lies under the foot
    SLOPE = 2  #: the ground under the foot is too steep or uneven
    STEP_HEIGHT = 4  #: the height change of the step exceeds the limit
    KNEE_REACH = 8  #: a key frame is out of the leg's reach or knee-flexion limit
    SWING = 16  #: no Bezier swing curve clears the ground inside the legal region
    UNREACHED = 32  #: not evaluated: no legal sequence of steps reaches its stance foothold


_TEXT = {
    Reason.EDGE: "the foot would stand across an edge or riser",
    Reason.SLOPE: "the ground under the foot is too steep or uneven",
    Reason.STEP_HEIGHT: "the height change exceeds the largest step rise",
    Reason.KNEE_REACH: "the knee cannot reach a key frame",
    Reason.SWING: "the swing foot cannot clear the ground",
    Reason.UNREACHED: "no legal step reaches its stance foothold",
}


def describe(reason: int) -> str:
    """Human-readable text of the most important flag in ``reason``."""
    for flag in (Reason.STEP_HEIGHT, Reason.EDGE, Reason.SLOPE, Reason.KNEE_REACH,
                 Reason.SWING, Reason.UNREACHED):
        if reason & flag:
            return _TEXT[flag]
    return "legal"


def foot_support(ankle_s: np.ndarray, profile: GroundProfile, heel_offset, toe_offset,
                 config: PlannerConfig) -> np.ndarray:
    """Whether a foot placed with its ankle at ``ankle_s`` [m] is fully supported.

    The foot spans heel to toe, widened by ``edge_margin`` [m]. Legal when (§4.2) no
    vertical change larger than ``support_tolerance`` lies strictly inside the span
    (heel and toe on the same tread: never across a stair edge, never on a riser), no
    ground pokes more than ``support_tolerance`` above the higher of heel and toe, and
    the heel-to-toe slope is at most ``max_foot_slope``.

    Returns
    -------
    reason : ndarray of int, shape of ``ankle_s``
        0 where supported, else :class:`Reason` flags (EDGE, SLOPE).
    """
    heel = ankle_s - heel_offset
    toe = ankle_s + toe_offset
    lo = heel - config.edge_margin
    hi = toe + config.edge_margin
    jump_s, jump_dz = profile.jumps
    big = jump_s[np.abs(jump_dz) > config.support_tolerance]
    edges = np.searchsorted(big, hi, side="left") - np.searchsorted(big, lo, side="right")
    eps = 1e-9  # a riser exactly at the heel or toe is beside the foot, not under it
    highest, z_heel, z_toe = profile.span_heights(heel + eps, toe - eps)
    bump = highest - np.maximum(z_heel, z_toe)
    slope = np.abs(z_toe - z_heel) / (toe - heel)
    uneven = (bump > config.support_tolerance) | (slope > config.max_foot_slope)
    return np.where(edges > 0, int(Reason.EDGE), 0) | np.where(uneven, int(Reason.SLOPE), 0)


def snap_to_support(ankle_s: np.ndarray, window, profile: GroundProfile, heel_offset,
                    toe_offset, config: PlannerConfig, neighbours: int = 3) -> np.ndarray:
    """Move each foothold by at most ``window`` [m] to the nearest supported position.

    Candidates are the foothold itself and the positions that put the heel or the toe
    exactly ``edge_margin`` clear of one of the ``neighbours`` nearest edges on each
    side. Footholds with no supported candidate inside the window stay where they are.

    Parameters
    ----------
    ankle_s : ndarray, shape (A, N)
        Footholds [m].
    window : float or ndarray broadcastable to (A, N)
        Largest move [m].
    heel_offset, toe_offset : float or ndarray, shape (A, 1)
        Foot geometry [m].

    Returns
    -------
    ndarray, shape (A, N)
        Snapped footholds [m].
    """
    jump_s, jump_dz = profile.jumps
    edges = jump_s[np.abs(jump_dz) > config.support_tolerance]
    if edges.size == 0:
        return ankle_s
    m = config.edge_margin + 1e-9  # 1 nm inside, so rounding cannot put the foot back
    heel = np.broadcast_to(np.asarray(heel_offset, dtype=float), ankle_s.shape)
    toe = np.broadcast_to(np.asarray(toe_offset, dtype=float), ankle_s.shape)
    # a supported foothold stays (no move is shorter); only the others look for one
    bad = foot_support(ankle_s, profile, heel, toe, config) != 0
    if not bad.any():
        return ankle_s
    at = ankle_s[bad]  # (B,)
    i = np.searchsorted(edges, at)
    picks = np.clip(i[:, None] + np.arange(-neighbours, neighbours)[None, :], 0,
                    edges.size - 1)
    e = edges[picks]  # (B, 2*neighbours)
    heel, toe = heel[bad][:, None], toe[bad][:, None]
    candidates = np.concatenate([at[:, None], e + heel + m, e - toe - m], axis=-1)
    shift = np.abs(candidates - at[:, None])
    limit = np.broadcast_to(np.asarray(window, dtype=float), ankle_s.shape)[bad]
    # only the candidates within the window are tested (most edges are further away)
    near = shift <= limit[:, None]
    rows, cols = np.nonzero(near)
    supported = np.zeros(near.shape, dtype=bool)
    supported[rows, cols] = foot_support(candidates[rows, cols], profile, heel[rows, 0],
                                         toe[rows, 0], config) == 0
    cost = np.where(supported, shift, np.inf)
    best = np.argmin(cost, axis=-1)
    rows = np.arange(at.size)
    out = ankle_s.copy()
    out[bad] = np.where(np.isfinite(cost[rows, best]), candidates[rows, best], at)
    return out
