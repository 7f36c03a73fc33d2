"""Phase timing of a step from Table 1 of Chen & Li (§5.3)."""

from __future__ import annotations

import numpy as np

__all__ = ["phase_fractions", "phase_durations"]

#: Flat-ground phase fractions T1, T2, T3 (Table 1, after Winter 1990).
FLAT_FRACTIONS = (0.44, 0.28, 0.28)


def phase_fractions(rise: np.ndarray, leg_length) -> np.ndarray:
    """Fractions (..., 3) of a step spent in phases T1, T2, T3 [-].

    Parameters
    ----------
    rise : array_like
        Signed height change of the step [m].
    leg_length : float or array_like
        Hip-to-ankle length [m].

    Notes
    -----
    Table 1 prints the same expression ``44 - 30 h / leg length`` (%) in every cell of
    the up- and downhill rows, which cannot sum to 100 %. We read it as: T1 becomes
    ``44 - 30 |h| / l`` % and the freed time goes in equal parts to T2 and T3 (the
    double-support and push-off phases lengthen on stairs and slopes, Tsutsuguchi 2000).
    """
    x = 0.30 * np.abs(np.asarray(rise, dtype=float)) / np.asarray(leg_length, dtype=float)
    x = np.minimum(x, 0.30)  # keep T1 >= 14 %
    t1, t2, t3 = FLAT_FRACTIONS
    return np.stack([t1 - x, t2 + 0.5 * x, t3 + 0.5 * x], axis=-1)


def phase_durations(step_length, speed, rise, leg_length) -> np.ndarray:
    """Durations (..., 3) of phases T1, T2, T3 [s] of steps walked at ``speed`` [m/s].

    The step takes ``step_length / speed`` [s] (the walker keeps its target speed along
    the path, as in Eq. 1) split by :func:`phase_fractions`.
    """
    duration = np.asarray(step_length, dtype=float) / np.asarray(speed, dtype=float)
    return duration[..., None] * phase_fractions(rise, leg_length)
