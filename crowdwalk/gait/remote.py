"""A gait engine in a worker process, so that posing runs beside the simulation.

The engine lives in one worker (:class:`crowdwalk.workers.Workers`) and gets the same
calls in the same order as it would here, so its poses are the same. Step commands are
queued there without waiting; :meth:`RemoteEngine.pose_async` asks for a frame and
returns at once, and the simulation goes on with its next ticks while the worker poses
(the run delivers a frame when the next one has been asked for,
:func:`crowdwalk.crowd.run.run_scenario`).

Why not split the walkers between several engines: an engine is not independent per
walker — ElevInterp inserts the datasets it builds into the space later requests
interpolate in (§5.1), so each walker's poses depend on the steps all walkers asked for
before; one engine keeps them exactly as one process computes them.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from crowdwalk.gait.engine import GaitEngine, PoseFrame
from crowdwalk.steps import StepBatch
from crowdwalk.workers import Workers, available_cores, set_row_threads

__all__ = ["RemoteEngine"]

_KEY = "gait-engine"


class RemoteEngine:
    """The :class:`~crowdwalk.gait.engine.GaitEngine` that ``factory()`` builds, run in
    worker ``worker`` of ``workers``.

    Parameters
    ----------
    factory : callable
        Picklable ``factory() -> GaitEngine`` (built in the worker).
    workers : Workers
    worker : int
        Which worker [-].
    """

    def __init__(self, factory: Callable[[], GaitEngine], workers: Workers,
                 worker: int = 0) -> None:
        self.workers, self.worker = workers, worker
        # the worker is a daemon process (one row thread by default): its engine's
        # compiled solves run on parts of a frame's walkers in a thread per core
        workers.send(worker, None, set_row_threads, available_cores())
        workers.keep(_KEY, factory, build=True, worker=worker)
        self._skeleton = None

    @property
    def skeleton(self) -> tuple[tuple[str, ...], np.ndarray]:
        if self._skeleton is None:
            self._skeleton = self.workers.call(self.worker, _KEY, "skeleton")()
        return self._skeleton

    def command(self, steps: StepBatch) -> None:
        self.workers.send(self.worker, _KEY, "command", steps)

    def pose_async(self, t: float, agents: np.ndarray) -> Callable[[], PoseFrame]:
        """Ask for the poses at ``t`` [s] of ``agents`` (k,); returns a function that waits
        for them (:meth:`pose`'s frame)."""
        return self.workers.call(self.worker, _KEY, "pose", t, np.asarray(agents))

    def pose(self, t: float, agents: np.ndarray) -> PoseFrame:
        return self.pose_async(t, agents)()
