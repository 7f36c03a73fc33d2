"""The crowd simulation: event-driven footstep-planning agents on route graphs."""

from pathlib import Path

from planners.kernel_cache import refresh as _refresh_kernel_cache

# numba's cache checks only a kernel's own source file, and the crowd's kernels call each
# other across modules (the steering kernels call clearance's and shape's): before any of
# them loads, a change of any crowd module clears the package's cache (planners.kernel_cache)
_refresh_kernel_cache(Path(__file__).resolve().parent)

from crowdwalk.crowd.simulation import CrowdParams, CrowdSimulation  # noqa: E402
from crowdwalk.crowd.steering import SteeringParams  # noqa: E402

__all__ = ["CrowdParams", "CrowdSimulation", "SteeringParams"]
