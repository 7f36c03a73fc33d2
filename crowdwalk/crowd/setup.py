"""The ready-made parts a crowd simulation runs with, built once per run."""

from __future__ import annotations

from dataclasses import dataclass

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.footsteps import FootstepPlanner
from crowdwalk.crowd.legs import LegTable
from crowdwalk.crowd.params import CrowdParams
from crowdwalk.crowd.routing import Routes

__all__ = ["CrowdParts", "build_parts"]


@dataclass(frozen=True, eq=False)
class CrowdParts:
    """What :class:`~crowdwalk.crowd.simulation.CrowdSimulation` is given.

    Attributes
    ----------
    legs : LegTable
        Planning legs (2 cm body-height classes).
    clearance : ClearanceField
        Distance to the walkable area's boundary [m].
    footsteps : FootstepPlanner
        The footstep planner in the crowd (batched, cached).
    routes : Routes
        The agents' route polylines.
    """

    legs: LegTable
    clearance: ClearanceField
    footsteps: FootstepPlanner
    routes: Routes


def build_parts(world, population, *, params: CrowdParams,
                planner_config=None) -> CrowdParts:
    """The parts for ``population`` on ``world`` (``planner_config`` None: Chen & Li's
    ``planning_horizon`` steps ahead, steps down to ``min_step_ratio`` leg lengths)."""
    if planner_config is None:
        from planners import PlannerConfig

        # Chen & Li plan "three or four" steps ahead (§4.2); three is an order of
        # magnitude cheaper on stairs than four, and the crowd re-plans often. The step
        # range reaches down to 0.15 leg lengths (planners' default 0.30): in queues
        # and when arriving close to a riser people take short steps.
        planner_config = PlannerConfig(n_steps=params.planning_horizon,
                                       min_step_ratio=params.min_step_ratio)
    legs = LegTable(population.body_height)
    clearance = ClearanceField.from_area(world.routes.walkable_area)
    footsteps = FootstepPlanner(world.terrain, legs.legs, config=planner_config,
                                horizon=planner_config.n_steps, clearance=clearance)
    return CrowdParts(legs=legs, clearance=clearance, footsteps=footsteps,
                      routes=Routes(world.routes, population))
