"""The crowd simulation: event-driven footstep-planning agents on route graphs."""

from crowdwalk.crowd.simulation import CrowdParams, CrowdSimulation
from crowdwalk.crowd.steering import SteeringParams

__all__ = ["CrowdParams", "CrowdSimulation", "SteeringParams"]
