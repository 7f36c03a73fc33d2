"""The footstep planner in the crowd: ground profiles along the agents' local paths,
batched ``planners.plan_batch`` calls, and the first planned step of each plan.

Chen & Li (§4.2) plan the next n steps and the walker takes them; in a crowd the local
path changes at every heel strike (neighbours move), so each deciding agent re-plans and
takes only the first step of its plan (receding horizon). The planner is the cost centre,
so identical planning problems are answered from a cache: the key is the planner, the
leg, the speed and the ground profile *relative to the stance foot* (s, z − z₀ rounded to
1 mm). On level ground every step of an agent is the same problem, so an agent plans on
flat ground once; on stairs the profile differs with the position on the flight and the
planner runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PlannedSteps", "FootstepPlanner"]

_BEHIND = 1.0  # [m] of ground behind the stance foot in the profile (trailing swing foot)
_QUANTUM = 1e-3  # [m] rounding of the profile in the cache key


@dataclass(frozen=True)
class PlannedSteps:
    """First planned step of m agents (struct-of-arrays).

    Attributes
    ----------
    ok : (m,) bool
        A legal step was found.
    step_length : (m,) float
        Ankle-to-ankle step length along the local path [m].
    step_height : (m,) float
        Height of the new foothold above the stance foothold [m].
    swing : (m, 4, 2) float
        Swing-ankle Bezier control points (s, z) relative to the stance ankle (s = 0,
        z = 0) [m]; NaN when the planner gave none.
    energy : (m,) float
        Energy of the step [J/kg].
    from_cache : (m,) bool
        The plan came from the cache.
    """

    ok: np.ndarray
    step_length: np.ndarray
    step_height: np.ndarray
    swing: np.ndarray
    energy: np.ndarray
    from_cache: np.ndarray


def _first_step(plan) -> tuple:
    """(ok, step_length, step_height, swing (4,2) relative, energy) of a Plan."""
    if getattr(plan, "status", "ok") != "ok" or len(plan.step_lengths) == 0:
        return (False, 0.0, 0.0, np.full((4, 2), np.nan), 0.0)
    s0, z0 = float(plan.footholds_s[0]), float(plan.footholds_z[0])
    swing = np.full((4, 2), np.nan)
    ctrl = getattr(plan, "swing_controls", None)
    if ctrl is not None and len(ctrl):
        swing = np.asarray(ctrl[0], dtype=float) - [s0, z0]
    energy = _step_energy(plan)
    return (True, float(plan.step_lengths[0]), float(plan.footholds_z[1] - z0), swing, energy)


def _step_energy(plan) -> float:
    """Energy of the plan's first step [J/kg] (the planner's E of Eq. 4)."""
    for name in ("energies", "energy", "E"):
        value = getattr(plan, name, None)
        if value is None:
            continue
        if isinstance(value, dict):
            value = value.get("E", next(iter(value.values())))
        elif hasattr(value, "E"):
            value = value.E
        arr = np.asarray(value, dtype=float).reshape(-1)
        if arr.size:
            return float(arr[0])
    return float("nan")


class FootstepPlanner:
    """Plans the next step of many agents at once.

    Parameters
    ----------
    terrain : crowdwalk.terrain.Terrain
        Ground (``profile(polyline)``).
    legs : sequence of planners.Leg
        Distinct legs; agents refer to them by index.
    lookahead : float
        Length of the local path ahead of the stance foot [m] (covers the planner's
        n steps of at most ``max_step_ratio`` leg lengths).
    config : planners.PlannerConfig or None
        Planner configuration (None: the planners' defaults).
    """

    def __init__(self, terrain, legs, lookahead: float = 4.5, config=None) -> None:
        self.terrain = terrain
        self.legs = list(legs)
        self.lookahead = float(lookahead)
        self.config = config
        self._cache: dict[bytes, tuple] = {}
        self.calls = 0
        self.hits = 0

    def plan(
        self,
        stance: np.ndarray,
        stance_z: np.ndarray,
        direction: np.ndarray,
        leg: np.ndarray,
        speed: np.ndarray,
        planner: np.ndarray,
        trailing: np.ndarray | None = None,
    ) -> PlannedSteps:
        """Plan the first step of m agents.

        Parameters
        ----------
        stance : (m, 2)
            Centre-line point of the stance foot's ankle [m].
        stance_z : (m,)
            Height of the stance foothold [m].
        direction : (m, 2)
            Unit walking direction of the local path.
        leg : (m,) int
            Index into ``legs``.
        speed : (m,)
            Walking speed given to the planner [m/s].
        planner : (m,) str
            Planner name per agent (``planners.PLANNERS``).
        trailing : (m,) float, optional
            Arc length of the trailing (swing) foot behind the stance foot [m], < 0.
        """
        from planners import plan_batch

        m = stance.shape[0]
        ok = np.zeros(m, bool)
        sl = np.zeros(m)
        sh = np.zeros(m)
        swing = np.full((m, 4, 2), np.nan)
        energy = np.zeros(m)
        cached = np.zeros(m, bool)
        if trailing is None:
            trailing = np.full(m, -0.6)
        trailing = np.clip(np.round(np.asarray(trailing, float), 3), -2.9, -0.01)
        keys: list[bytes] = []
        profiles = []
        lines = np.stack([stance - _BEHIND * direction, stance + self.lookahead * direction],
                         axis=1)  # (m, 2, 2): one straight local path per agent
        if hasattr(self.terrain, "profiles"):
            arrays = self.terrain.profiles(lines)  # one batched terrain pass
        else:
            arrays = [self.terrain.profile_arrays(line) for line in lines]
        for i in range(m):  # cache keys and profile objects are per agent
            s, z = arrays[i]
            s = s - _BEHIND
            z = z - stance_z[i]
            key = b"|".join([
                str(planner[i]).encode(), np.int64(leg[i]).tobytes(),
                np.round(speed[i], 3).tobytes(), trailing[i].tobytes(),
                np.round(s / _QUANTUM).astype(np.int64).tobytes(),
                np.round(z / _QUANTUM).astype(np.int64).tobytes(),
            ])
            keys.append(key)
            profiles.append((s, z))
        todo = [i for i in range(m) if keys[i] not in self._cache]
        self.calls += m
        self.hits += m - len(todo)
        if todo:
            from planners import GroundProfile

            by_planner: dict[str, list[int]] = {}
            for i in todo:
                by_planner.setdefault(str(planner[i]), []).append(i)
            for name, idx in by_planner.items():
                unique: dict[bytes, int] = {}
                for i in idx:
                    unique.setdefault(keys[i], i)
                first = list(unique.values())
                plans = plan_batch(
                    [GroundProfile(*profiles[i]) for i in first],
                    [self.legs[leg[i]] for i in first],
                    [float(speed[i]) for i in first],
                    planner=name,
                    config=self.config,
                    trailing=[float(trailing[i]) for i in first],
                )
                for i, plan in zip(first, plans, strict=True):
                    self._cache[keys[i]] = _first_step(plan)
        planned_now = set(todo)
        for i in range(m):
            hit = self._cache[keys[i]]
            ok[i], sl[i], sh[i], swing[i], energy[i] = hit
            cached[i] = i not in planned_now
        return PlannedSteps(ok, sl, sh, swing, energy, cached)
