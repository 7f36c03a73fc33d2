"""Footstep planners on a ground profile (Chen & Li 2003). Depends on numpy, scipy, numba.

``plan(profile, leg, speed, planner)`` plans the next ``n_steps`` footholds of one
walker; ``plan_batch`` plans for many at once; ``walk`` walks a whole profile by
receding horizon. Planners: ``best_first`` (the paper's FIND_INIT + best-first search as
written), ``best_first_multistart`` (the improved search: several starts, a wider
neighbourhood), ``fixed`` (unplanned neutral steps) and ``optimal`` (the exact optimum
over the same grid and horizon).
"""

from planners.kernel_cache import refresh as _refresh_kernel_cache

# before any kernel loads from numba's cache, which checks only the kernel's own file
_refresh_kernel_cache()

from planners.config import EnergyWeights, PlannerConfig  # noqa: E402
from planners.energy import flat_efficiency  # noqa: E402
from planners.errors import ProfileError  # noqa: E402
from planners.leg import Leg  # noqa: E402
from planners.plan import PLANNERS, Plan, plan, plan_batch  # noqa: E402
from planners.profile import GroundProfile  # noqa: E402
from planners.turning import split_turn  # noqa: E402
from planners.walk import walk  # noqa: E402

__all__ = ["EnergyWeights", "GroundProfile", "Leg", "PLANNERS", "Plan", "PlannerConfig",
           "ProfileError", "flat_efficiency", "plan", "plan_batch", "split_turn", "walk"]
