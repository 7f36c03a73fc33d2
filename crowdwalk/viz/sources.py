"""Where the viewer gets poses from: a run's ``poses.sqlite``, its trajectories (when no
poses were stored), or arrays in memory. All expose the same small interface:

``names`` (J,), ``parents`` (J,) int, ``times`` (F,) [s], ``agent_ids`` (sorted ids of
every agent that appears), ``n_agents`` and ``at(i) -> (ids (k,), positions (k, J, 3)
[m])`` for output frame ``i``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from crowdwalk.errors import invalid

__all__ = [
    "PoseSource",
    "ArrayPoses",
    "RunPoses",
    "TrajectoryPoses",
    "PoseTimeline",
    "blend_frames",
    "frame_index",
]


class PoseSource(Protocol):
    """Joint world positions of the agents present in each output frame."""

    names: list[str]
    parents: np.ndarray
    times: np.ndarray
    agent_ids: np.ndarray
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
        self.agent_ids = np.unique(np.concatenate(self._ids)) if self._ids else np.zeros(0, int)
        self.n_agents = len(self.agent_ids)
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
        known = np.array(sorted(poses.body_heights), dtype=int)
        if not len(known) and len(self.times):
            known = np.unique(self.at(0)[0])
        self.agent_ids = known
        self.n_agents = len(known)

    def at(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Ids (k,) and joint positions (k, J, 3) [m] of stored frame ``index``."""
        record = self._poses.frame(int(self._frames[index]))
        return record.ids, record.positions


class TrajectoryPoses:
    """Upright poles with a shoulder bar from trajectories, for runs stored without poses.

    Each agent is a four-joint figure: a pole from the ground under it to ``height``
    above it and, ``0.2`` m below its top, a bar ``shoulders`` wide across the torso's
    facing (the trajectories' ``ori_x, ori_y``), so that drawn with capsules of
    :attr:`pole_radius` the figure is as broad as the body's outline and shows which way
    its shoulders face (:mod:`crowdwalk.crowd.shape`).

    Parameters
    ----------
    trajectories : crowdwalk.record.Trajectories
        Rows sorted by frame.
    height : float
        Pole height [m].
    shoulders : float
        Distance between the bar's end joints [m].
    """

    #: Capsule radius [m] the viewer draws the figure with.
    pole_radius = 0.12

    def __init__(self, trajectories, height: float = 1.5, shoulders: float = 0.2) -> None:
        frames = np.asarray(trajectories.frame, dtype=int)
        self.names = ["ground", "top", "left", "right"]
        self.parents = np.array([-1, 0, 1, 1])
        self._frames = np.unique(frames)
        self.times = self._frames / float(trajectories.fps)
        self._start = np.searchsorted(frames, self._frames, side="left")
        self._stop = np.searchsorted(frames, self._frames, side="right")
        ground = np.column_stack([trajectories.x, trajectories.y, trajectories.z])
        left = np.column_stack([-np.asarray(trajectories.ori_y), trajectories.ori_x,
                                np.zeros(len(ground))]) * (0.5 * shoulders)
        bar = ground + [0.0, 0.0, height - 0.2]
        self._positions = np.stack([ground, ground + [0.0, 0.0, height], bar + left,
                                    bar - left], axis=1)
        self._ids = np.asarray(trajectories.id, dtype=int)
        self.agent_ids = np.unique(self._ids)
        self.n_agents = len(self.agent_ids)

    def at(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Ids (k,) and figure joints (k, 4, 3) [m] of frame ``index``."""
        rows = slice(self._start[index], self._stop[index])
        return self._ids[rows], self._positions[rows]


def blend_frames(
    ids0: np.ndarray, positions0: np.ndarray, ids1: np.ndarray, positions1: np.ndarray,
    alpha: float,
) -> np.ndarray:
    """Joint positions between two output frames, for the agents of the first.

    Agents present in both frames move linearly by ``alpha`` ∈ [0, 1] towards the second
    frame; agents missing from it keep their first-frame pose.

    Parameters
    ----------
    ids0, ids1 : (k0,), (k1,) int
        Agent ids of the two frames (unique).
    positions0, positions1 : (k0, J, 3), (k1, J, 3) float
        Joint world positions [m].
    alpha : float
        Fraction of the frame interval [-].

    Returns
    -------
    (k0, J, 3) float
        Positions [m] in the order of ``ids0``.
    """
    out = np.array(positions0, dtype=float, copy=True)
    _, i0, i1 = np.intersect1d(ids0, ids1, assume_unique=True, return_indices=True)
    out[i0] += alpha * (np.asarray(positions1, dtype=float)[i1] - out[i0])
    return out


class PoseTimeline:
    """Poses at any time: the output frame at or before ``t``, blended linearly with the
    next frame (display only: smooth slow motion and movies at more frames per second
    than the run stored). Keeps the last frames read, so playback reads each once.

    Parameters
    ----------
    source : PoseSource
    interpolate : bool
        Blend between frames; when False, hold the frame at or before ``t``.
    """

    def __init__(self, source: PoseSource, interpolate: bool = True) -> None:
        self.source = source
        self.interpolate = interpolate
        self._cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _frame(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        if index not in self._cache:
            if len(self._cache) >= 4:
                self._cache.pop(next(iter(self._cache)))
            self._cache[index] = self.source.at(index)
        return self._cache[index]

    def at_time(self, t: float) -> tuple[int, np.ndarray, np.ndarray]:
        """Frame index at or before ``t`` [s], agent ids (k,) and positions (k, J, 3) [m]."""
        times = self.source.times
        index = frame_index(times, t)
        ids, positions = self._frame(index)
        if self.interpolate and index + 1 < len(times) and t > times[index] + 1e-9:
            alpha = min((t - times[index]) / (times[index + 1] - times[index]), 1.0)
            ids1, positions1 = self._frame(index + 1)
            positions = blend_frames(ids, positions, ids1, positions1, alpha)
        return index, ids, positions
