"""A walk along a whole profile by receding horizon: plan, take the first step, re-plan."""

from __future__ import annotations

import math

import numpy as np

from planners.config import PlannerConfig
from planners.errors import invalid
from planners.leg import Leg
from planners.plan import NO_FOOTHOLD, OK, Plan, plan
from planners.profile import GroundProfile

__all__ = ["walk"]

#: Counters of Plan.stats summed over the walk's plans.
_COUNTED = ("nodes_expanded", "legality_checks", "lattice_steps", "key_frame_solves",
            "swing_curves", "swing_curves_reused", "swing_adjustments", "time_s")


def walk(profile: GroundProfile, leg: Leg, speed: float, planner: str = "best_first",
         config: PlannerConfig | None = None, *, start: float = 0.0,
         stop: float | None = None) -> Plan:
    """Walk from ``start`` to ``stop`` [m] along ``profile``, one planned step at a time.

    Each step is the first step of a plan from the current stance foot (the previous
    stance foot trailing); a plan that cannot reach its horizon still gives its first
    legal step. The walk ends when the next step would pass ``stop`` (status ``"ok"``) or
    when no legal step exists (status ``"no legal foothold"``, with where and why).

    Parameters
    ----------
    profile : GroundProfile
    leg : Leg
    speed : float
        Target speed [m/s].
    planner : str
        One of :data:`planners.PLANNERS`.
    config : PlannerConfig, optional
    start : float
        Arc length of the first stance foot [m].
    stop : float, optional
        Where the walk ends [m]; default the end of the profile.

    Returns
    -------
    Plan
        Every step taken (footholds from ``start``), their energies, swing curves and
        phase durations; ``stats`` sums the counters of every plan made and counts them
        in ``plans`` (the plans whose first step was taken, and the last one, which
        passed ``stop`` or found no legal step).

    Raises
    ------
    ProfileError
        ``stop`` is less than one neutral step beyond ``start``.
    """
    stop = float(profile.s[-1]) if stop is None else float(stop)
    first = plan(profile, leg, speed, planner, config, origin=start)
    neutral = first.stats["neutral_step"]
    if not (math.isfinite(stop) and stop - start >= neutral):
        raise invalid("walk", "profile", f"at least one step ({neutral:.2f} m) long beyond "
                      f"the start s = {start:g} [m]", f"{stop - start:.2f} m")
    taken: list[Plan] = []
    totals = dict.fromkeys(_COUNTED, 0)
    totals["plans"] = 0

    def count(p: Plan) -> Plan:  # every plan made, whether its step is taken or not
        for key in _COUNTED:
            totals[key] += p.stats[key]
        totals["plans"] += 1
        return p

    current, s, status, message = count(first), start, OK, ""
    limit = int(np.ceil((stop - start) / first.stats["step_min"])) + 1
    for _ in range(limit):
        if current.step_lengths.size == 0:
            status, message = NO_FOOTHOLD, current.message
            break
        step = float(current.step_lengths[0])
        if s + step > stop + 1e-9:
            break
        taken.append(current)
        s += step
        current = count(plan(profile, leg, speed, planner, config, trailing=-step, origin=s))
    return _joined(taken, first, status, message, totals)


def _joined(taken: list[Plan], first: Plan, status: str, message: str, totals) -> Plan:
    """One Plan of the first step of every plan in ``taken``."""
    def column(name, shape):
        parts = [getattr(p, name)[:1] for p in taken]
        return np.concatenate(parts) if parts else np.zeros((0, *shape))

    s = np.concatenate([[first.footholds_s[0]], [p.footholds_s[1] for p in taken]])
    z = np.concatenate([[first.footholds_z[0]], [p.footholds_z[1] for p in taken]])
    lengths, energy = column("step_lengths", ()), column("E", ())
    stats = {**first.stats, **totals, "terminal_energy": 0.0, "reach": float(s[-1])}
    efficiency = float(lengths.sum() / energy.sum()) if lengths.size else 0.0
    return Plan(status, message, first.planner, s, z, lengths, column("step_heights", ()),
                column("swing_controls", (4, 2)), column("phase_durations", (3,)),
                column("En", ()), column("Ev", ()), column("Ej", ()), energy, efficiency,
                stats, first.speed, first.trailing_s, np.zeros(lengths.size))
