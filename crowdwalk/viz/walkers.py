"""Who each walker is (group, planner, style) and what the followed one is doing.

:class:`Walkers` is read from a run folder (``summary.json``'s per-agent rows, else the
footstep table); :func:`walker_status` measures a walker's speed, step length and energy
so far from its foot placements up to a time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crowdwalk.viz.footprints import Footsteps

__all__ = ["CATEGORIES", "Walkers", "WalkerStatus", "walker_status"]

CATEGORIES = ("group", "planner", "style")
UNKNOWN = "unknown"


@dataclass(frozen=True)
class Walkers:
    """Per-walker labels, struct of arrays sorted by id: ``id`` (m,) int; ``group``,
    ``planner``, ``style`` (m,) str (``"unknown"`` when the run does not say)."""

    id: np.ndarray
    group: np.ndarray
    planner: np.ndarray
    style: np.ndarray

    @classmethod
    def empty(cls) -> Walkers:
        """No walkers."""
        none = np.zeros(0, dtype=str)
        return cls(np.zeros(0, int), none, none, none)

    @classmethod
    def from_rows(cls, rows: list[dict]) -> Walkers:
        """From per-agent dicts with ``id`` and optionally ``group``, ``planner``,
        ``style`` (a name, or a dict with a ``name``/``preset``)."""
        rows = sorted(rows, key=lambda r: int(r["id"]))

        def label(row, key):
            value = row.get(key)
            if isinstance(value, dict):
                value = value.get("name", value.get("preset"))
            return UNKNOWN if value in (None, "") else str(value)

        return cls(
            np.array([int(r["id"]) for r in rows], dtype=int),
            *(np.array([label(r, k) for r in rows], dtype=object).astype(str)
              for k in CATEGORIES),
        )

    @classmethod
    def from_footsteps(cls, steps: Footsteps) -> Walkers:
        """Group and planner of each walker from its first foot placement."""
        ids, first = np.unique(steps.agent, return_index=True)
        group = steps.group[first] if steps.group is not None else np.full(len(ids), UNKNOWN)
        return cls(ids, group.astype(str), steps.planner[first].astype(str),
                   np.full(len(ids), UNKNOWN))

    @classmethod
    def from_run(cls, run, steps: Footsteps) -> Walkers:
        """From a :class:`crowdwalk.record.Run`: its summary's agent rows when present (a
        walker without a recorded style gets its group's style preset from the scenario as
        run)."""
        rows = run.summary.get("agents") if run.summary_path.exists() else None
        if not rows:
            return cls.from_footsteps(steps)
        styles = _group_styles(run.scenario_path)
        rows = [r if r.get("style") else {**r, "style": styles.get(r.get("group"))}
                for r in rows]
        return cls.from_rows(rows)

    def __len__(self) -> int:
        return len(self.id)

    def index(self, ids: np.ndarray) -> np.ndarray:
        """Row (k,) of each id in this table, -1 for unknown ids."""
        ids = np.asarray(ids, dtype=int)
        if not len(self.id):
            return np.full(len(ids), -1)
        i = np.clip(np.searchsorted(self.id, ids), 0, len(self.id) - 1)
        return np.where(self.id[i] == ids, i, -1)

    def labels(self, field: str) -> list[str]:
        """The distinct values of ``field`` ("group", "planner" or "style"), sorted."""
        return sorted(set(getattr(self, field).tolist()))

    def codes(self, field: str, ids: np.ndarray) -> np.ndarray:
        """Category code (k,) of each id for ``field``, index into :meth:`labels`; -1 for
        unknown walkers."""
        names = self.labels(field)
        lookup = {n: i for i, n in enumerate(names)}
        codes = np.array([lookup[v] for v in getattr(self, field)], dtype=int)
        row = self.index(ids)
        return np.where(row >= 0, codes[np.maximum(row, 0)] if len(codes) else -1, -1)


def _group_styles(scenario_path) -> dict[str, str]:
    """Group name -> its KLAW style preset in a scenario file ("normal" without a style,
    "custom" for attributes without a preset); empty when the file cannot be read."""
    from crowdwalk.scenario import load_scenario

    try:
        groups = load_scenario(scenario_path).groups
    except (OSError, ValueError):
        return {}
    out = {}
    for g in groups:
        spec = getattr(g, "style", None)
        out[g.name] = "normal" if spec is None else (spec.preset or "custom")
    return out


@dataclass(frozen=True)
class WalkerStatus:
    """What one walker is doing at a time: speed [m/s] over its last stride, length [m]
    of its last step, energy [J/kg] of its steps so far, steps so far."""

    speed: float
    step_length: float
    energy: float
    steps: int


def walker_status(steps: Footsteps, agent: int, t: float) -> WalkerStatus:
    """Status of walker ``agent`` at time ``t`` [s] from its placements up to ``t``.

    Speed is the distance between the last two placements of the same foot over their time
    apart (one stride; one step after the first two placements), zero when the last
    placement is more than two such intervals ago (the walker stopped).
    """
    mine = np.flatnonzero((steps.agent == agent) & (steps.time <= t + 1e-9))
    if not mine.size:
        return WalkerStatus(0.0, 0.0, 0.0, 0)
    mine = mine[np.argsort(steps.time[mine], kind="stable")]
    energy = float(np.nansum(steps.energy[mine]))
    length = float(steps.step_length[mine[-1]]) if steps.step_length is not None else np.nan
    speed = 0.0
    if mine.size >= 2:
        a, b = mine[-min(3, mine.size)], mine[-1]
        stride = steps.time[b] - steps.time[a]
        if stride > 0 and t - steps.time[b] <= 2 * stride:
            speed = float(np.hypot(*(steps.position[b, :2] - steps.position[a, :2])) / stride)
    return WalkerStatus(speed, length, energy, int(mine.size))
