"""The steps a crowd decides: :class:`StepBatch`, the one type from a decided step to the
gait engine and to every sink (docs/architecture.md, "Steps, gait engines and sinks").

A module of its own (numpy only) so that ``crowd/``, ``gait/``, ``record`` and any sink
import it without cycles.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

__all__ = ["FOOTSTEP_COLUMNS", "StepBatch"]

#: Columns of ``footsteps.csv`` in order (the one definition). Units: time [s] (the heel
#: strike that ends the step); x, y, z [m] (ankle foothold, world frame); step_length,
#: step_height [m]; energy [J/kg, per step]; heading [rad]; kind is the
#: :class:`~crowdwalk.terrain.TerrainKind` value under the foothold; on_obstacle is 1 when
#: the foothold is on an obstacle that could have been stepped over; toe_out [rad] (the
#: landing foot's, outward positive) and spin [rad] (the stance foot's spin turn about its
#: ball, counter-clockwise positive) are MetaGait's (Sun & Metaxas 2001, §6.1).
FOOTSTEP_COLUMNS = (
    "agent",
    "step",
    "time",
    "foot",
    "x",
    "y",
    "z",
    "step_length",
    "step_height",
    "energy",
    "planner",
    "group",
    "heading",
    "kind",
    "on_obstacle",
    "toe_out",
    "spin",
)


@dataclass(frozen=True, eq=False)
class StepBatch:
    """Steps that k agents start in one tick (struct-of-arrays, one row per step).

    Attributes
    ----------
    agent : (k,) int
        Agent index.
    step : (k,) int
        The agent's step count including this step (1 for its first step).
    start_time : (k,) float
        Heel strike (or end of the wait) at which the step starts [s].
    duration : (k,) float
        Heel strike to the next heel strike [s], > 0.
    foot : (k,) int
        The foot that swings: 0 left, 1 right.
    start : (k, 3) float
        Foothold of the stance foot (ankle foothold with its lateral offset, world
        frame) [m].
    target : (k, 3) float
        Foothold where the swing foot lands [m].
    stance_centre : (k, 2) float
        Centre-line point of the stance foot's ankle (the walking line; the step's
        length is measured from it) [m].
    heading : (k,) float
        Walking direction at the end of the step, from +x [rad].
    length : (k,) float
        Step length along the walking direction, ankle to ankle [m] (> 0).
    rise : (k,) float
        Height of the new foothold above the stance foothold [m].
    energy : (k,) float
        Energy of the step (Chen & Li Eq. 4) [J/kg].
    planner : (k,) str
        Planner of the agent (``planners.PLANNERS``).
    group : (k,) str
        The agent's group name.
    swing_bezier : (k, 4, 3) float
        The planner's collision-free Bezier control points of the swing ankle, world
        xyz [m]; rows of NaN for steps the planner did not plan (shortened and
        positioning steps).
    kind : (k,) int
        :class:`~crowdwalk.terrain.TerrainKind` under the new foothold.
    on_obstacle : (k,) bool
        The new foothold is on an obstacle short enough to have been stepped over.
    toe_out : (k,) float
        Toe-out of the landing (swing) foot from the walking direction, outward positive
        [rad] (MetaGait, :func:`crowdwalk.gait.metagait.orient_steps`).
    spin : (k,) float
        Spin turn of the stance foot about its ball during this step, counter-clockwise
        positive [rad] (MetaGait; 0 for most steps).
    """

    agent: np.ndarray
    step: np.ndarray
    start_time: np.ndarray
    duration: np.ndarray
    foot: np.ndarray
    start: np.ndarray
    target: np.ndarray
    stance_centre: np.ndarray
    heading: np.ndarray
    length: np.ndarray
    rise: np.ndarray
    energy: np.ndarray
    planner: np.ndarray
    group: np.ndarray
    swing_bezier: np.ndarray
    kind: np.ndarray
    on_obstacle: np.ndarray
    toe_out: np.ndarray
    spin: np.ndarray

    def __len__(self) -> int:
        return int(self.agent.shape[0])

    @property
    def time(self) -> np.ndarray:
        """Heel strike that ends each step (k,) [s]."""
        return self.start_time + self.duration

    @classmethod
    def concat(cls, batches: Sequence[StepBatch]) -> StepBatch:
        """The steps of ``batches`` one after another (one batch: itself)."""
        if len(batches) == 1:
            return batches[0]
        return cls(**{f.name: np.concatenate([getattr(b, f.name) for b in batches])
                      for f in fields(cls)})

    def take(self, rows: np.ndarray) -> StepBatch:
        """The steps at ``rows`` (integer or boolean array)."""
        return StepBatch(**{f.name: getattr(self, f.name)[rows] for f in fields(self)})

    def footstep_columns(self) -> dict[str, np.ndarray]:
        """The rows of ``footsteps.csv``: :data:`FOOTSTEP_COLUMNS` -> (k,) arrays."""
        return {
            "agent": self.agent, "step": self.step, "time": self.time,
            "foot": np.where(self.foot == 0, "left", "right"),
            "x": self.target[:, 0], "y": self.target[:, 1], "z": self.target[:, 2],
            "step_length": self.length, "step_height": self.rise, "energy": self.energy,
            "planner": self.planner, "group": self.group, "heading": self.heading,
            "kind": self.kind, "on_obstacle": self.on_obstacle.astype(int),
            "toe_out": self.toe_out, "spin": self.spin,
        }
