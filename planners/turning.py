"""Curved paths: spreading a heading change over several steps (§5.4, Fig. 8)."""

from __future__ import annotations

import math

import numpy as np

from planners.errors import invalid

__all__ = ["split_turn"]


def split_turn(heading_change: float, threshold: float = math.radians(45.0),
               first_foot: str = "left") -> tuple[np.ndarray, list[str]]:
    """Split a heading change into per-step foot rotations of at most ``threshold``.

    Parameters
    ----------
    heading_change : float
        Total change of walking direction [rad]; positive turns left (counter-clockwise).
    threshold : float
        Largest rotation of one foot placement [rad].
    first_foot : {"left", "right"}
        Foot that makes the next step.

    Returns
    -------
    rotations : ndarray, shape (k,)
        Heading increment of each successive foot placement [rad]; they sum to
        ``heading_change``.
    feet : list of str
        Which foot makes each placement.

    Notes
    -----
    §5.4: the leg on the inside of the turn opens first (turning left, the left foot);
    when the next stepping foot is the outside one it steps straight and the rotations
    start with the following step. A turn above the threshold is divided into
    ``ceil(|change| / threshold)`` equal rotations over consecutive steps; e.g. 180 deg
    with a 45 deg threshold takes four rotations (Fig. 8).
    """
    for name, value in (("heading_change", heading_change), ("threshold", threshold)):
        if not math.isfinite(value):
            raise invalid("split_turn", name, "finite [rad]", value)
    if threshold <= 0:
        raise invalid("split_turn", "threshold", "> 0 [rad]", threshold)
    if first_foot not in ("left", "right"):
        raise invalid("split_turn", "first_foot", "'left' or 'right'", first_foot)
    if heading_change == 0:
        return np.zeros(0), []
    count = max(1, math.ceil(abs(heading_change) / threshold - 1e-12))
    inside = "left" if heading_change > 0 else "right"
    rotations = [heading_change / count] * count
    if first_foot != inside:
        rotations = [0.0, *rotations]
    other = {"left": "right", "right": "left"}
    feet = [first_foot if i % 2 == 0 else other[first_foot] for i in range(len(rotations))]
    return np.array(rotations), feet
