"""Footstep planners on a ground profile (Chen & Li). Depends on numpy/scipy only."""

from planners.errors import ProfileError
from planners.leg import Leg
from planners.profile import GroundProfile

__all__ = ["GroundProfile", "Leg", "ProfileError"]
