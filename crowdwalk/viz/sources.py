"""Where the viewer gets poses from: a run's ``poses.sqlite``, its trajectories (when no
poses were stored), or arrays in memory. All expose the same small interface:

``names`` (J,), ``parents`` (J,) int, ``times`` (F,) [s], ``n_agents`` (how many
distinct agents appear) and ``at(i) -> (ids (k,), positions (k, J, 3) [m])`` for output
frame ``i``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from crowdwalk.errors import invalid

__all__ = ["PoseSource", "ArrayPoses", "RunPoses", "TrajectoryPoses", "frame_index"]


class PoseSource(Protocol):
    """Joint world positions of the agents present in each output frame."""

    names: list[str]
    parents: np.ndarray
    times: np.ndarray
    n_agents: int

    def at(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Ids (k,) and joint world positions (k, J, 3) [m] of output frame ``index``."""


def frame_index(times: np.ndarray, t: float) -> int:
    """Index of the last output frame at or before ``t`` [s] (0 before the first)."""
    i = int(np.searchsorted(times, t + 1e-9, side="right")) - 1
    return min(max(i, 0), len(times) - 1)


class ArrayPoses:
    """Poses held in memory.

    Parameters
    ----------
    times : (F,) float
        Frame times [s], increasing.
    ids : sequence of (k_f,) int
        Agent ids of each frame.
    positions : sequence of (k_f, J, 3) float
        Joint world positions of each frame [m].
    parents : (J,) int
        Parent joint (-1 for the root).
    names : sequence of str, optional
        Joint names.
    """

    def __init__(
        self,
        times: np.ndarray,
        ids: Sequence[np.ndarray],
        positions: Sequence[np.ndarray],
        parents: np.ndarray,
        names: Sequence[str] | None = None,
    ) -> None:
        self.times = np.asarray(times, dtype=float)
        if len(ids) != len(self.times) or len(positions) != len(self.times):
            raise invalid("ArrayPoses", "ids", f"one entry per frame ({len(self.times)})",
                          (len(ids), len(positions)))
        if np.any(np.diff(self.times) <= 0):
            raise invalid("ArrayPoses", "times", "strictly increasing [s]", self.times)
        self.parents = np.asarray(parents, dtype=int)
        self.names = list(names) if names is not None else [f"j{j}" for j in range(len(parents))]
        self._ids = [np.asarray(i, dtype=int) for i in ids]
        self.n_agents = len(np.unique(np.concatenate(self._ids))) if self._ids else 0
        self._positions = [np.asarray(p, dtype=float) for p in positions]

    def at(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Ids (k,) and joint positions (k, J, 3) [m] of frame ``index``."""
        return self._ids[index], self._positions[index]


class RunPoses:
    """Poses from a run folder's ``poses.sqlite`` (:class:`crowdwalk.record.Poses`)."""

    def __init__(self, poses) -> None:
        self._poses = poses
        self.names = list(poses.names)
        self.parents = np.asarray(poses.parents, dtype=int)
        self.times = np.asarray(poses.times, dtype=float)
        self._frames = np.asarray(poses.frames, dtype=int)
        self.n_agents = len(poses.body_heights) or (len(self.at(0)[0]) if len(self.times) else 0)

    def at(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Ids (k,) and joint positions (k, J, 3) [m] of stored frame ``index``."""
        record = self._poses.frame(int(self._frames[index]))
        return record.ids, record.positions


class TrajectoryPoses:
    """Upright poles from trajectories, for runs stored without poses.

    Each agent is a two-joint figure from the ground under it to ``height`` above it.

    Parameters
    ----------
    trajectories : crowdwalk.record.Trajectories
        Rows sorted by frame.
    height : float
        Pole height [m].
    """

    def __init__(self, trajectories, height: float = 1.5) -> None:
        frames = np.asarray(trajectories.frame, dtype=int)
        self.names = ["ground", "top"]
        self.parents = np.array([-1, 0])
        self._frames = np.unique(frames)
        self.times = self._frames / float(trajectories.fps)
        self._start = np.searchsorted(frames, self._frames, side="left")
        self._stop = np.searchsorted(frames, self._frames, side="right")
        ground = np.column_stack([trajectories.x, trajectories.y, trajectories.z])
        self._positions = np.stack([ground, ground + [0.0, 0.0, height]], axis=1)
        self._ids = np.asarray(trajectories.id, dtype=int)
        self.n_agents = len(np.unique(self._ids))

    def at(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Ids (k,) and pole end points (k, 2, 3) [m] of frame ``index``."""
        rows = slice(self._start[index], self._stop[index])
        return self._ids[rows], self._positions[rows]
