"""The planning legs of a crowd: one ``planners.Leg`` per 2 cm body-height class, and
their segment lengths gathered per agent as arrays."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from crowdwalk.body import Body

__all__ = ["LegColumns", "LegTable"]


@dataclass(frozen=True, eq=False)
class LegColumns:
    """Legs of k agents as (k,) arrays [m] (what the planners' vectorised functions accept
    in place of a ``planners.Leg``); ``length`` = thigh + shank."""

    thigh: np.ndarray
    shank: np.ndarray
    foot_length: np.ndarray
    heel_offset: np.ndarray
    toe_offset: np.ndarray
    ankle_height: np.ndarray
    length: np.ndarray


class LegTable:
    """Planning legs of n agents in 2 cm body-height classes (about 1 % of leg length).

    Parameters
    ----------
    body_height : (n,) float
        The agents' body heights [m].

    Attributes
    ----------
    legs : list of planners.Leg
        One leg per class (:meth:`crowdwalk.body.Body.planning_legs`).
    index : (n,) int
        Each agent's class.
    """

    def __init__(self, body_height: np.ndarray) -> None:
        heights, self.index = np.unique(np.round(np.asarray(body_height) / 0.02) * 0.02,
                                        return_inverse=True)
        self.legs = Body.from_heights(heights).planning_legs()
        self._columns = {f.name: np.array([getattr(leg, f.name) for leg in self.legs])
                         for f in fields(LegColumns)}

    def of(self, agents: np.ndarray) -> LegColumns:
        """The legs of ``agents`` (k,)."""
        k = self.index[agents]
        return LegColumns(**{name: col[k] for name, col in self._columns.items()})
