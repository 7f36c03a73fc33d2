"""The steps a crowd decides: :class:`StepBatch`, the one type from a decided step to the
gait engine and to every sink (docs/architecture.md, "Steps, gait engines and sinks").

A module of its own (numpy only) so that ``crowd/``, ``gait/``, ``record`` and any sink
import it without cycles.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

__all__ = ["FOOTSTEP_COLUMNS", "FootstepTable", "StepBatch"]


@dataclass(frozen=True, eq=False)
class FootstepTable:
    """Foot placements of a run, one row per step (struct of arrays, n rows): what
    ``footsteps.csv`` holds, in its column order, and what :meth:`crowdwalk.record.Run.
    footsteps` returns to compare, gait-report, the viewer and the tests.

    Attributes
    ----------
    agent : (n,) int
        Agent id (index into the population).
    step : (n,) int
        The agent's step count including this step (1 for its first).
    time : (n,) float
        Heel strike that ends the step [s].
    foot : (n,) str
        The foot that lands: ``"left"`` or ``"right"``.
    x, y, z : (n,) float
        Ankle foothold where it lands, world frame [m].
    step_length : (n,) float
        Step length along the walking direction, ankle to ankle [m].
    step_height : (n,) float
        Height of the new foothold above the stance foothold [m].
    energy : (n,) float
        Energy of the step (Chen & Li Eq. 4) [J/kg].
    planner : (n,) str
        The agent's planner (``planners.PLANNERS``).
    group : (n,) str
        The agent's group name.
    heading : (n,) float
        Walking direction at the end of the step, from +x [rad].
    kind : (n,) int
        :class:`~crowdwalk.terrain.TerrainKind` value under the foothold.
    on_obstacle : (n,) int
        1 when the foothold is on an obstacle that could have been stepped over, else 0.
    toe_out : (n,) float
        Toe-out of the landing foot from the walking direction, outward positive [rad]
        (MetaGait, Sun & Metaxas 2001 §6.1).
    spin : (n,) float
        Spin turn of the stance foot about its ball during the step, counter-clockwise
        positive [rad] (MetaGait §6.1; 0 for most steps).
    """

    agent: np.ndarray
    step: np.ndarray
    time: np.ndarray
    foot: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    step_length: np.ndarray
    step_height: np.ndarray
    energy: np.ndarray
    planner: np.ndarray
    group: np.ndarray
    heading: np.ndarray
    kind: np.ndarray
    on_obstacle: np.ndarray
    toe_out: np.ndarray
    spin: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.agent)
        for f in fields(self):
            if np.shape(getattr(self, f.name)) != (n,):
                raise ValueError(f"FootstepTable.{f.name}: shape (n,) = ({n},) expected, "
                                 f"got {np.shape(getattr(self, f.name))}")

    def __len__(self) -> int:
        return int(len(self.agent))

    @property
    def position(self) -> np.ndarray:
        """Footholds (n, 3) [m]."""
        return np.column_stack([self.x, self.y, self.z])

    def take(self, rows: np.ndarray) -> FootstepTable:
        """The rows ``rows`` (integer or boolean array), in that order."""
        return FootstepTable(**{f.name: getattr(self, f.name)[rows] for f in fields(self)})

    def of_agent(self, agent: int) -> FootstepTable:
        """The rows of agent ``agent``, in file order."""
        return self.take(self.agent == agent)

    def columns(self) -> dict[str, np.ndarray]:
        """Column name (:data:`FOOTSTEP_COLUMNS`, in order) -> (n,) array, for writers."""
        return {name: getattr(self, name) for name in FOOTSTEP_COLUMNS}

    @classmethod
    def from_text(cls, header: Sequence[str], rows: Sequence[Sequence[str]]) -> FootstepTable:
        """From CSV text: ``header`` (the column names, :data:`FOOTSTEP_COLUMNS` in any
        order) and ``rows`` of strings; ``foot``, ``planner`` and ``group`` stay strings,
        ``agent``, ``step``, ``kind`` and ``on_obstacle`` become int, the rest float.
        Columns added after a run was written (:data:`LATER_COLUMNS`) are NaN when
        absent. Raises ValueError naming the other missing columns."""
        missing = [c for c in FOOTSTEP_COLUMNS if c not in header and c not in LATER_COLUMNS]
        if missing:
            raise ValueError(f"columns {missing} missing from the header")
        cols = list(zip(*rows, strict=True)) if rows else [() for _ in header]
        by_name = dict(zip(header, cols, strict=True))
        n = len(rows)
        out = {}
        for name in FOOTSTEP_COLUMNS:
            values = by_name.get(name, np.full(n, np.nan))
            if name in _TEXT_COLUMNS:
                out[name] = np.array(values, dtype=str)
            elif name in _INT_COLUMNS:
                out[name] = np.array(values, dtype=float).astype(int)
            else:
                out[name] = np.array(values, dtype=float)
        return cls(**out)


#: Columns of ``footsteps.csv`` in order: the fields of :class:`FootstepTable` (the one
#: definition; units there).
FOOTSTEP_COLUMNS = tuple(f.name for f in fields(FootstepTable))
#: Columns that runs written before MetaGait's orientation (issue 11) lack: read as NaN.
LATER_COLUMNS = frozenset({"toe_out", "spin"})
_TEXT_COLUMNS = frozenset({"foot", "planner", "group"})
_INT_COLUMNS = frozenset({"agent", "step", "kind", "on_obstacle"})


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

    def footstep_columns(self) -> FootstepTable:
        """The rows of ``footsteps.csv`` these steps make."""
        return FootstepTable(
            agent=self.agent, step=self.step, time=self.time,
            foot=np.where(self.foot == 0, "left", "right"),
            x=self.target[:, 0], y=self.target[:, 1], z=self.target[:, 2],
            step_length=self.length, step_height=self.rise, energy=self.energy,
            planner=self.planner, group=self.group, heading=self.heading,
            kind=self.kind, on_obstacle=self.on_obstacle.astype(int),
            toe_out=self.toe_out, spin=self.spin,
        )
