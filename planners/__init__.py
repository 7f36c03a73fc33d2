"""Footstep planners on a ground profile (Chen & Li 2003). Depends on numpy, scipy, numba.

``plan(profile, leg, speed, planner)`` plans the next ``n_steps`` footholds of one
walker; ``plan_batch`` plans for many at once; ``walk`` walks a whole profile by
receding horizon. Planners: ``best_first`` (the paper's FIND_INIT + best-first search as
written), ``best_first_multistart`` (the improved search: several starts, a wider
neighbourhood), ``fixed`` (unplanned neutral steps) and ``optimal`` (the exact optimum
over the same grid and horizon).
"""

from planners.config import EnergyWeights, PlannerConfig
from planners.energy import flat_efficiency
from planners.errors import ProfileError
from planners.leg import Leg
from planners.plan import PLANNERS, Plan, plan, plan_batch
from planners.profile import GroundProfile
from planners.turning import split_turn
from planners.walk import walk

__all__ = ["EnergyWeights", "GroundProfile", "Leg", "PLANNERS", "Plan", "PlannerConfig",
           "ProfileError", "flat_efficiency", "plan", "plan_batch", "split_turn", "walk"]
