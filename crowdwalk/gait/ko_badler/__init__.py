"""Ko & Badler (1992): measured walk data generalised to any body and step length.

``walkdata`` holds W(S, sl) and its parts, ``generalize`` the paper's φ_ρ (§2), ψ (§4)
and their combination (§5).
"""

from crowdwalk.gait.ko_badler.generalize import (
    achieved_step_length,
    ankle_at_heel_strike,
    ankle_at_toe_off,
    body_generalization,
    generalization,
    hip_height_at_heel_strike,
    mu,
    step_length_generalization,
)
from crowdwalk.gait.ko_badler.walkdata import (
    BodyCondition,
    GaitLaw,
    StepStart,
    TimedSequence,
    WalkData,
    interpolation,
    load_prototype,
)

__all__ = [
    "BodyCondition",
    "GaitLaw",
    "StepStart",
    "TimedSequence",
    "WalkData",
    "interpolation",
    "load_prototype",
    "mu",
    "hip_height_at_heel_strike",
    "ankle_at_toe_off",
    "ankle_at_heel_strike",
    "achieved_step_length",
    "step_length_generalization",
    "body_generalization",
    "generalization",
]
