"""The planar two-link leg and its foot."""

from __future__ import annotations

import math
from dataclasses import dataclass

from planners.errors import invalid

__all__ = ["Leg"]

# Segment lengths as fractions of body height, Winter (2009) "Biomechanics and Motor
# Control of Human Movement", Fig. 4.1: hip (greater trochanter) to knee 0.245 H, knee to
# ankle 0.246 H, ankle height 0.039 H, foot length 0.152 H. The ankle sits about a
# quarter of the foot length ahead of the heel (Winter's foot: heel-to-ankle 0.039 H of
# a 0.152 H foot).
THIGH_RATIO = 0.245
SHANK_RATIO = 0.246
ANKLE_HEIGHT_RATIO = 0.039
FOOT_LENGTH_RATIO = 0.152
HEEL_FRACTION = 0.25


@dataclass(frozen=True)
class Leg:
    """Sagittal leg geometry [m].

    Parameters
    ----------
    thigh : float
        Hip to knee [m].
    shank : float
        Knee to ankle [m].
    foot_length : float
        Heel to toe [m].
    heel_offset : float
        How far the heel is behind the ankle [m].
    toe_offset : float
        How far the toe is ahead of the ankle [m].
    ankle_height : float
        Ankle above the sole [m].
    """

    thigh: float
    shank: float
    foot_length: float
    heel_offset: float
    toe_offset: float
    ankle_height: float = 0.068

    def __post_init__(self) -> None:
        for field in ("thigh", "shank", "foot_length", "toe_offset", "ankle_height"):
            value = getattr(self, field)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise invalid("Leg", field, "finite and > 0 [m]", value)
        h = self.heel_offset
        if not (isinstance(h, int | float) and math.isfinite(h) and h >= 0):
            raise invalid("Leg", "heel_offset", "finite and >= 0 [m]", h)
        if self.heel_offset + self.toe_offset > self.foot_length * (1 + 1e-9):
            raise invalid("Leg", "toe_offset", f"<= foot_length - heel_offset "
                          f"= {self.foot_length - self.heel_offset:g} [m]", self.toe_offset)

    @classmethod
    def from_body_height(cls, height: float = 1.75) -> Leg:
        """Leg of a person ``height`` tall [m], from Winter's anthropometric ratios."""
        if not (isinstance(height, int | float) and math.isfinite(height)
                and 0.5 <= height <= 2.5):
            raise invalid("Leg", "body_height", "finite and in [0.5, 2.5] [m]", height)
        foot = FOOT_LENGTH_RATIO * height
        return cls(
            thigh=THIGH_RATIO * height,
            shank=SHANK_RATIO * height,
            foot_length=foot,
            heel_offset=HEEL_FRACTION * foot,
            toe_offset=(1 - HEEL_FRACTION) * foot,
            ankle_height=ANKLE_HEIGHT_RATIO * height,
        )

    @property
    def length(self) -> float:
        """Hip to ankle with a straight knee [m]."""
        return self.thigh + self.shank

    @property
    def hip_height(self) -> float:
        """Hip above the sole when standing straight [m]."""
        return self.thigh + self.shank + self.ankle_height
