"""The crowd's speed model: how long a step takes.

Deviation from Chen & Li, whose Table 1 shortens the phases equally for up- and downhill:
the step duration is step length / speed with the agent's free speed scaled on stairs by
Weidmann's (1993) measured horizontal stair speeds (0.610 m/s up, 0.694 m/s down against
1.34 m/s level) and on slopes by Tobler's (1993) hiking function; a level step never
takes less than 1/cadence at the free speed (Fukuchi et al. 2018 cadence fit), so short
steps in a queue are slow steps, not a shuffle at high cadence.
"""

from __future__ import annotations

import numpy as np

__all__ = ["STAIR_UP_FACTOR", "STAIR_DOWN_FACTOR", "step_durations"]

#: Weidmann (1993): horizontal speed on stairs, up and down, over level speed 1.34 m/s.
STAIR_UP_FACTOR = 0.610 / 1.34
STAIR_DOWN_FACTOR = 0.694 / 1.34


def step_durations(length: np.ndarray, rise: np.ndarray, *, free_speed: np.ndarray,
                   min_step_time: np.ndarray, stair_rise: float) -> np.ndarray:
    """Durations (k,) [s] of steps of ``length`` and ``rise`` (k,) [m] by walkers of
    ``free_speed`` (k,) [m/s] whose level steps take at least ``min_step_time`` (k,) [s];
    a rise beyond ``stair_rise`` [m] is a stair step."""
    grade = rise / np.maximum(length, 1e-6)
    factor = np.where(rise > stair_rise, STAIR_UP_FACTOR,
                      np.where(rise < -stair_rise, STAIR_DOWN_FACTOR,
                               1.0 / np.maximum(1.0, np.exp(3.5 * (np.abs(grade + 0.05)
                                                                   - 0.05)))))
    stair = np.abs(rise) > stair_rise
    return np.where(stair, length / (free_speed * factor),
                    np.maximum(length / (free_speed * factor), min_step_time))
