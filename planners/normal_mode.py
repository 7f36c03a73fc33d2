"""Normal-mode walking: step length and step frequency as functions of speed and leg length.

People choose their step length from their speed and size. Alexander (1984) showed that,
in dimensionless form, step length over leg length is a power of the dimensionless speed
``v / sqrt(g L)`` for bipeds of every size:

    SL / L = COEFFICIENT * (v / sqrt(g L)) ** EXPONENT                          (1)

(Alexander RM (1984), *The gaits of bipedal and quadrupedal animals*, Int J Robotics Res
3(2):49-59: stride/L = 2.3 (v^2/gL)^0.3, i.e. step/L = 1.15 (v/sqrt(gL))^0.6.) This module
uses Eq. (1) with its two constants refitted to the WBDS treadmill trials (Fukuchi CA,
Fukuchi RK, Duarte M (2018), *A public dataset of overground and treadmill walking
kinematics and kinetics in healthy individuals*, PeerJ 6:e4640; 43 adults aged 21-72,
1.47-1.92 m tall, 6 speeds each, 258 trials): coefficient 1.1233, exponent 0.5169,
residual SD 0.0407 L (3.45 cm), R^2 0.90, no bias above 0.5 cm in any speed category. It
is validated on a different population and protocol, the five speed categories of
Schwartz, Rozumalski & Trost (2008, J Biomech 41:1639, children walking overground): every
category mean lies within 0.85 SD of Eq. (1) (``scripts/fit_normal_mode.py`` reproduces
fit and validation; ``crowdwalk/data/README.md`` has the tables). This is KLAW's "normal
mode" (Bruderlin & Calvert 1989), whose own formulae are not at hand.

Step frequency follows as ``f = v / SL``. Given any one of speed, step length and step
frequency (and the leg length) the other two follow in closed form. Every function takes
and returns arrays (numpy broadcasting); scalars give 0-d results.

``leg_length`` is the WBDS anthropometric leg length, about ``LEG_TO_HEIGHT`` = 0.513 of
body height (median of the 43 subjects); :func:`leg_length_of` gives it for a
:class:`planners.Leg`.
"""

from __future__ import annotations

import numpy as np

from planners.errors import invalid
from planners.leg import SHANK_RATIO, THIGH_RATIO, Leg

__all__ = ["CADENCE_RESIDUAL_SD", "COEFFICIENT", "EXPONENT", "FROUDE_SPEED_RANGE",
           "LEG_TO_HEIGHT", "RESIDUAL_SD", "leg_length_from_height", "leg_length_of",
           "speed_from_step_frequency", "speed_from_step_length", "step_frequency",
           "step_length"]

G = 9.81  # [m/s^2]
COEFFICIENT = 1.1233  # Eq. (1), WBDS fit
EXPONENT = 0.5169  # Eq. (1), WBDS fit
RESIDUAL_SD = 0.0407  # SD of measured SL/L about Eq. (1) [leg lengths]
CADENCE_RESIDUAL_SD = 0.115  # SD of measured cadence about v / SL [steps/s] (6.9 /min)
FROUDE_SPEED_RANGE = (0.128, 0.589)  # v / sqrt(g L) covered by the WBDS trials
LEG_TO_HEIGHT = 0.513  # WBDS leg length / body height, median


def _checked(name: str, value, *, positive: bool) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    ok = np.isfinite(array) & ((array > 0) if positive else (array >= 0))
    if not np.all(ok):
        bad = array[~ok].ravel()[0] if array.ndim else array
        constraint = "finite and > 0" if positive else "finite and >= 0"
        unit = {"leg_length": "[m]", "speed": "[m/s]", "step_length": "[m]",
                "step_frequency": "[steps/s]", "height": "[m]"}[name]
        raise invalid("normal_mode", name, f"{constraint} {unit}", float(bad))
    return array


def step_length(speed, leg_length) -> np.ndarray:
    """Normal-mode step length [m] at walking speed ``speed`` [m/s], Eq. (1).

    Parameters
    ----------
    speed : array_like
        Walking speed [m/s], >= 0.
    leg_length : array_like
        Leg length [m] (WBDS measure, about 0.513 of body height), broadcast with speed.
    """
    v = _checked("speed", speed, positive=False)
    leg = _checked("leg_length", leg_length, positive=True)
    return COEFFICIENT * leg * (v / np.sqrt(G * leg)) ** EXPONENT


def step_frequency(speed, leg_length) -> np.ndarray:
    """Normal-mode step frequency [steps/s] at ``speed`` [m/s]: ``v / SL``.

    Equal to ``sqrt(g / L) / COEFFICIENT * (v / sqrt(g L)) ** (1 - EXPONENT)``, which
    is also defined (0) at zero speed.
    """
    v = _checked("speed", speed, positive=False)
    leg = _checked("leg_length", leg_length, positive=True)
    return np.sqrt(G / leg) / COEFFICIENT * (v / np.sqrt(G * leg)) ** (1.0 - EXPONENT)


def speed_from_step_length(step_length, leg_length) -> np.ndarray:
    """Walking speed [m/s] whose normal-mode step is ``step_length`` [m] (Eq. 1 inverted)."""
    sl = _checked("step_length", step_length, positive=False)
    leg = _checked("leg_length", leg_length, positive=True)
    return np.sqrt(G * leg) * (sl / (COEFFICIENT * leg)) ** (1.0 / EXPONENT)


def speed_from_step_frequency(step_frequency, leg_length) -> np.ndarray:
    """Walking speed [m/s] whose normal-mode step frequency is ``step_frequency`` [steps/s]."""
    f = _checked("step_frequency", step_frequency, positive=False)
    leg = _checked("leg_length", leg_length, positive=True)
    f_hat = f * COEFFICIENT / np.sqrt(G / leg)
    return np.sqrt(G * leg) * f_hat ** (1.0 / (1.0 - EXPONENT))


def leg_length_from_height(height) -> np.ndarray:
    """WBDS leg length [m] of a body ``height`` tall [m] (median ratio 0.513)."""
    return LEG_TO_HEIGHT * _checked("height", height, positive=True)


def leg_length_of(leg: Leg) -> float:
    """WBDS leg length [m] for a planner :class:`Leg` built from Winter's ratios.

    ``Leg.length`` (hip to ankle) is 0.491 of body height; the WBDS measure 0.513.
    """
    return LEG_TO_HEIGHT / (THIGH_RATIO + SHANK_RATIO) * leg.length
