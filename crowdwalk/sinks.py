"""Run sinks: everything that observes a run implements :class:`RunSink`
(docs/architecture.md, "Steps, gait engines and sinks").

``run_scenario`` calls, for every sink in its list and in this order:

1. ``begin(info)`` once, before the first frame (:class:`RunInfo`: the agents);
2. ``frame(time, snapshot, poses)`` for frame 0 (the start, ``poses`` None), then at
   every output frame ``steps(batch)`` with the steps decided since the last one (when
   there are any) and ``frame(time, snapshot, poses)``; after the last frame, the steps
   decided after it;
3. ``end(summary)`` once, also after an interruption (the summary says so).

The simulation knows no output format: :class:`crowdwalk.record.RunWriter` (the run
folder), :class:`OverlapMonitor` and ``scripts/foot_clearance_report.py``'s step log
are sinks. :class:`BackgroundSink` runs a sink's calls in a thread of their own.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.steps import StepBatch

if TYPE_CHECKING:
    from crowdwalk.crowd.shape import BodyShape
    from crowdwalk.gait.engine import PoseFrame

__all__ = ["RunInfo", "Snapshot", "RunSink", "OverlapMonitor", "BackgroundSink"]


@dataclass(frozen=True, eq=False)
class RunInfo:
    """The agents of a run (n of them), given to :meth:`RunSink.begin`.

    Attributes
    ----------
    fps : float
        Output frame rate [1/s].
    body_height : (n,) float [m]
    shape : crowdwalk.crowd.shape.BodyShape
        Body outlines (three discs on the shoulder line; ``shape.radius`` the centre
        disc's radius [m]).
    group : (n,) str
        Group name per agent.
    planner : (n,) str
        Planner name per agent.
    """

    fps: float
    body_height: np.ndarray
    shape: BodyShape
    group: np.ndarray
    planner: np.ndarray

    def __len__(self) -> int:
        return int(self.body_height.shape[0])


@dataclass(frozen=True, eq=False)
class Snapshot:
    """The walking agents at an output frame (k of them).

    Attributes
    ----------
    frame : int
        Output frame index (time = frame / fps).
    agents : (k,) int
        Agent indices, ascending.
    xy : (k, 2) float
        Body positions [m].
    z : (k,) float
        Body heights (mean of the two footholds' heights) [m].
    orientation : (k, 2) float
        Unit facing directions of the torsos (the walking direction turned by the
        shoulder twist; the shoulder line is perpendicular to it).
    """

    frame: int
    agents: np.ndarray
    xy: np.ndarray
    z: np.ndarray
    orientation: np.ndarray


@runtime_checkable
class RunSink(Protocol):
    """An observer of a run (see the module docstring for the order of calls)."""

    def begin(self, info: RunInfo) -> None: ...

    def steps(self, batch: StepBatch) -> None: ...

    def frame(self, time: float, snapshot: Snapshot, poses: PoseFrame | None) -> None: ...

    def end(self, summary: dict) -> None: ...


class OverlapMonitor:
    """The largest overlap of two body outlines over the run's frames [m] (the deepest
    interpenetration of any two of their discs; ``max_overlap`` in the summary; 0 when
    bodies never overlap)."""

    def __init__(self) -> None:
        self.max_overlap = 0.0
        self._shape = np.zeros((0, 3))

    def begin(self, info: RunInfo) -> None:
        self._shape = info.shape.packed()

    def steps(self, batch: StepBatch) -> None:
        pass

    def frame(self, time: float, snapshot: Snapshot, poses) -> None:
        ids, xy = snapshot.agents, snapshot.xy
        if ids.size <= 1:
            return
        reach = 2 * float(np.maximum(self._shape[:, 0], self._shape[:, 1:].sum(axis=1)).max())
        pairs = cKDTree(xy).query_pairs(reach, output_type="ndarray")
        if len(pairs):
            from crowdwalk.crowd.shape import shape_overlap  # crowd imports this module

            i, j = pairs[:, 0], pairs[:, 1]
            yaw = np.arctan2(snapshot.orientation[:, 1], snapshot.orientation[:, 0])
            over = shape_overlap(xy[i], yaw[i], self._shape[ids[i]], xy[j], yaw[j],
                                 self._shape[ids[j]])
            self.max_overlap = max(self.max_overlap, float(over.max()))

    def end(self, summary: dict) -> None:
        pass


class BackgroundSink:
    """The sink ``factory()`` builds, called in order in a thread of its own, so that its
    work overlaps the simulation (SQLite and file writes release the GIL).

    The sink is built in that thread (an SQLite connection belongs to the thread that
    opens it). A failure there is raised here by the next call; :meth:`wait` and
    :meth:`end` return when every call before them is done (``end`` raising a failure).
    At most ``backlog`` calls wait at a time [-]; ``name`` names the thread.
    """

    def __init__(self, factory: Callable[[], RunSink], *, backlog: int = 32,
                 name: str = "crowdwalk-sink") -> None:
        self._calls: queue.Queue = queue.Queue(maxsize=backlog)
        self._error: BaseException | None = None
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._serve, args=(factory,), daemon=True,
                                        name=name)
        self._thread.start()
        self._ready.wait()
        self._raise()  # the sink could not be built

    def begin(self, info: RunInfo) -> None:
        self._put("begin", info)

    def steps(self, batch: StepBatch) -> None:
        self._put("steps", batch)

    def frame(self, time: float, snapshot: Snapshot, poses) -> None:
        self._put("frame", time, snapshot, poses)

    def call(self, name: str, *args) -> None:
        """Call the sink's method ``name`` with ``args``, in order with the others."""
        self._put(name, *args)

    def wait(self) -> None:
        """Return when every call made so far is done. A failure of one is raised by the
        next call or :meth:`end` (so that a run still writes its summary first)."""
        self._calls.join()

    def end(self, summary: dict) -> None:
        self._put("end", summary)
        self._calls.put(None)
        self._thread.join()
        self._raise()

    def _serve(self, factory) -> None:
        try:
            sink = factory()
        except BaseException as exc:  # noqa: BLE001 - raised in the calling thread
            self._error = exc
        self._ready.set()
        while (call := self._calls.get()) is not None:
            if self._error is None:
                try:
                    getattr(sink, call[0])(*call[1])
                except BaseException as exc:  # noqa: BLE001 - raised in the calling thread
                    self._error = exc
            self._calls.task_done()
        self._calls.task_done()

    def _put(self, name: str, *args) -> None:
        self._raise()
        self._calls.put((name, args))

    def _raise(self) -> None:
        if self._error is not None:
            raise self._error
