"""Worker processes for one run: the machine's other cores.

A run's heavy stages are independent per walker: the steering of the walkers deciding in
a tick, their footstep plans, their poses. :class:`Workers` starts worker processes once
per run; :func:`split_rows` runs a function of per-walker arrays on contiguous parts of
its rows at once (the last part here, the others in the workers) and joins the results,
so the result is the one a single call would give. Objects many calls need (the
clearance field) are sent once (:meth:`Workers.share`); a call refers to them by key.
A worker also holds objects with state of their own (the run's gait engine,
:mod:`crowdwalk.gait.remote`), driven by messages in order.

Workers are spawned (not forked), ignore Ctrl-C (the run stops them) and end with the run.

Within this process, :class:`RowThreads` runs the parts of a row-independent call in
threads at once (:meth:`RowThreads.map`): numpy's array operations, scipy's queries and
the numba kernels (``nogil``) release the GIL, so the parts use the cores without copying
anything. The crowd steers with these threads; worker processes pose.
"""

from __future__ import annotations

import dataclasses
import gc
import multiprocessing as mp
import os
import queue
import signal
import sys
import threading
import traceback
import types
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from itertools import count as _count

import numpy as np

__all__ = ["Workers", "WorkerError", "RowThreads", "available_cores", "row_threads",
           "set_row_threads", "split_rows", "worker_count", "CHUNKS_PER_THREAD",
           "MIN_PARALLEL_AGENTS", "MIN_SPLIT_ROWS", "MIN_THREAD_ROWS"]

#: A run that writes poses and has fewer walkers stays in one process (workers cost ~2 s
#: to start) [-]: ``bench_crowd.py --agents 1000 --workers 0 auto --repeats 2 --seconds 6``
#: on the idle machine gave 0.69 vs 0.91 sim s per wall s with poses. Without poses a run
#: has no worker: its steering runs in this process's threads (:class:`RowThreads`).
MIN_PARALLEL_AGENTS = 500
#: A call with fewer rows is not split among worker processes [-]: the 1,000-walker
#: stadium (~100 walkers deciding per tick) ran at 1.21 sim s per wall s with its steering
#: split and 1.45 without (``bench_crowd.py --agents 1000 --workers 0 auto --repeats 2``,
#: load 1-4).
MIN_SPLIT_ROWS = 400
#: A call with fewer rows per thread is not split among threads [-] (a part's fixed cost,
#: ~0.3 ms of Python between numpy calls, against ~60 µs per walker steered).
MIN_THREAD_ROWS = 32
#: A split call's rows are cut into up to this many parts per thread [-], taken by the
#: threads as they come free, the caller first (:meth:`RowThreads.map`): the
#: 10,000-walker stadium (5 s, load 4) waited 0.3 s per simulated s for the second thread
#: after its own half of each call (the steering targets' half took 0.38 s, the wait
#: 0.64 s); a part that thread has not begun when the caller is done is the caller's now.
#: Four parts per thread measured the same as one under load 3-5 (0.41 against 0.42 sim s
#: per wall s at 10,000 walkers, 2.25 against 2.31 for the 1,000-walker room;
#: ``benchmarks/bench_loop.py ... --variants default c4``), so one.
CHUNKS_PER_THREAD = 1
#: The same for a light call, a compiled kernel of a few µs per walker (the crowd's
#: steering targets, neighbour grid queries, clash tests, footing) [-]: at ~100 deciders
#: per tick, split in two threads, such calls took 2-10 times their one-thread time
#: (room of 1,000 walkers, ``bench_vs_jupedsim``'s scenario, load 4.5).
MIN_LIGHT_ROWS = 256
#: A worker's first-generation garbage-collection threshold (Python's default 700) [-]:
#: posing allocates millions of small objects per simulated second, and with the default
#: every 100th first-generation collection may be a full one over the whole heap (numba,
#: scipy, the engine). The engine replay of the 1,000-walker stadium (4 s, 100 frames, 8,419 step
#: commands) took 6.80 / 8.56 CPU s with 700 and 5.85 / 7.00 with 20,000 (alternating,
#: load 2-3), identical poses (the collector frees nothing a pose reads).
WORKER_GC_THRESHOLD = 20_000


class WorkerError(RuntimeError):
    """A worker process failed (its traceback is the message)."""


def available_cores() -> int:
    """CPU cores this process may run on [-]."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def worker_count(agents: int, requested: int | None, *, poses: bool = True) -> int:
    """Worker processes for a run of ``agents`` walkers: ``requested`` if given, else one
    per core beyond this one when the run writes ``poses`` and has at least
    :data:`MIN_PARALLEL_AGENTS` walkers (without poses, none: the steering runs in
    threads, :class:`RowThreads`); none in a daemon process, such as a Dask worker, which
    may not start processes."""
    if requested is not None:
        return int(requested)
    if mp.current_process().daemon:  # e.g. a Dask worker: a process per core already
        return 0
    return available_cores() - 1 if poses and agents >= MIN_PARALLEL_AGENTS else 0


class RowThreads:
    """``count`` threads of this process, the caller's among them, for row-independent
    calls (:meth:`map`)."""

    def __init__(self, count: int) -> None:
        self.count = max(1, int(count))
        self._pool = (ThreadPoolExecutor(self.count - 1, thread_name_prefix="crowdwalk-rows")
                      if self.count > 1 else None)

    def map(self, fn: Callable, m: int, /, *args, min_rows: int | None = None,
            light: bool = False, **kwargs):
        """``fn(*args, **kwargs)`` computed on contiguous parts of its m rows at once in
        the threads, joined in order: the rules of :func:`split_rows` (row-independent
        ``fn``; arguments with m rows are split). Fewer than ``min_rows`` (default
        :data:`MIN_THREAD_ROWS`; a ``light`` call's :data:`MIN_LIGHT_ROWS`) rows per part:
        fewer parts.

        The rows are cut into up to :data:`CHUNKS_PER_THREAD` parts per thread, which
        the threads take one after another as they come free, the calling thread first
        (:meth:`_share`): a thread that gets no core for a while (the run's writer, other
        processes) leaves its parts to the others instead of making the call wait."""
        least = (min_rows if min_rows is not None
                 else MIN_LIGHT_ROWS if light else MIN_THREAD_ROWS)
        parts = min(self.count, m // max(least, 1))
        if parts <= 1 or self._pool is None:
            return fn(*args, **kwargs)
        parts = min(parts * CHUNKS_PER_THREAD, m // max(least, 1))
        # np.linspace(0, m, parts + 1).round()'s bounds (i · (m / parts), half to even)
        step = m / parts
        bounds = [round(i * step) for i in range(parts)] + [m]
        cuts = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
        # which arguments are split is found once for all parts (_part's rules)
        split = [_splits(a, m) for a in args]
        named = {k: _splits(v, m) for k, v in kwargs.items()}

        def part(rows):
            return fn(*[_cut(a, rows, m) if s else a for a, s in zip(args, split, strict=True)],
                      **{k: _cut(v, rows, m) if named[k] else v for k, v in kwargs.items()})

        return _join(self._share(part, cuts))

    def _share(self, part: Callable, cuts: list) -> list:
        """``[part(c) for c in cuts]``, the parts taken in order by whichever thread is
        free: the calling thread and those of the pool that start before every part is
        taken (one that starts later takes none, and is not waited for)."""
        results: list = [None] * len(cuts)
        lock = threading.Lock()
        state = {"next": 0, "done": 0, "error": None}
        finished = threading.Event()

        def work() -> None:
            while True:
                with lock:
                    i = state["next"]
                    if i >= len(cuts):
                        return
                    state["next"] = i + 1
                try:
                    results[i] = part(cuts[i])
                except BaseException as exc:  # noqa: BLE001 - raised in the calling thread
                    state["error"] = state["error"] or exc
                with lock:
                    state["done"] += 1
                    if state["done"] == len(cuts):
                        finished.set()

        for _ in range(self.count - 1):
            self._pool.submit(work)
        work()
        finished.wait()
        if state["error"] is not None:
            raise state["error"]
        return results

    def close(self) -> None:
        """End the threads."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None


_ROW_THREADS: RowThreads | None = None
_ROW_LOCK = threading.Lock()


def row_threads() -> RowThreads:
    """This process's :class:`RowThreads`: one per core (one in a daemon process, such as
    a Dask worker, where every core has a process of its own), made on first use."""
    global _ROW_THREADS
    with _ROW_LOCK:
        if _ROW_THREADS is None:
            _ROW_THREADS = RowThreads(1 if mp.current_process().daemon else available_cores())
        return _ROW_THREADS


def set_row_threads(count: int) -> None:
    """Make this process's :class:`RowThreads` (:func:`row_threads`) ``count`` threads: a
    worker process that poses (:mod:`crowdwalk.gait.remote`) is a daemon, which would
    get one, and runs the gait engine's compiled solves on parts of a frame's walkers at
    once."""
    global _ROW_THREADS
    with _ROW_LOCK:
        if _ROW_THREADS is not None and _ROW_THREADS.count == max(1, int(count)):
            return
        old, _ROW_THREADS = _ROW_THREADS, RowThreads(count)
    if old is not None:
        old.close()


class _Handle:
    """Stands for an object shared with the workers; unpickles as that object there."""

    def __init__(self, key: int) -> None:
        self.key = key

    def __reduce__(self):
        return _shared_object, (self.key,)


_SHARED: dict[int, object] = {}  # in a worker: key -> object sent by Workers.share


def _shared_object(key: int):
    return _SHARED[key]


def _serve(inbox, outbox) -> None:
    """A worker's loop: ``(seq, target, method, args, kwargs)`` messages in order. A failed
    call answers its traceback; a failed message without reply (seq None) breaks the
    worker's state, so every later reply is that traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    gc.set_threshold(WORKER_GC_THRESHOLD, *gc.get_threshold()[1:])
    broken = None
    while True:
        msg = inbox.get()
        if msg is None:
            return
        seq, target, method, args, kwargs = msg
        failed = broken
        if broken is None:
            try:
                result = _handle(target, method, args, kwargs)
            except BaseException:  # noqa: BLE001 - the main process raises it
                failed = traceback.format_exc()
                if seq is None:
                    broken = failed
        if seq is not None:
            outbox.put((seq, failed, None if failed else result))


def _handle(target, method, args: tuple, kwargs: dict):
    if target is None:  # a function call
        return method(*args, **kwargs)
    if method is None:  # keep an object: args = (key, object or factory)
        obj = args[1]
        _SHARED[target] = obj() if kwargs.get("build") else obj
        return None
    attr = getattr(_SHARED[target], method)  # a method (or an attribute) of a kept object
    return attr(*args, **kwargs) if callable(attr) else attr


class Workers:
    """``count`` worker processes (spawned now) that call functions and keep objects.

    Messages to one worker are handled in the order sent. Use as a context manager, or
    call :meth:`close`.
    """

    def __init__(self, count: int) -> None:
        ctx = mp.get_context("spawn")
        self._inbox = [ctx.Queue() for _ in range(count)]
        self._outbox = [ctx.Queue() for _ in range(count)]
        self._procs = [ctx.Process(target=_serve, args=(i, o), daemon=True,
                                   name=f"crowdwalk-worker-{k}")
                       for k, (i, o) in enumerate(zip(self._inbox, self._outbox, strict=True))]
        # a worker needs nothing of the caller's script: without this, spawning imports
        # it again (and re-runs a script that lacks an ``if __name__ == "__main__"`` guard)
        main = sys.modules["__main__"]
        sys.modules["__main__"] = types.ModuleType("__main__")
        try:
            for p in self._procs:
                p.start()
        finally:
            sys.modules["__main__"] = main
        self._seq = _count()
        self._replies: list[dict[int, tuple]] = [{} for _ in range(count)]
        self._shared: dict[int, object] = {}  # id(object) -> object (kept alive)

    def __len__(self) -> int:
        return len(self._procs)

    def __enter__(self) -> Workers:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def send(self, worker: int, target, method, /, *args, **kwargs) -> None:
        """Queue ``method(*args, **kwargs)`` on ``worker`` without waiting for it: ``target``
        None calls the function ``method``, else the method of the object kept as
        ``target``. Shared objects among the arguments travel as their keys."""
        self._inbox[worker].put((None, target, method, *self._pack(args, kwargs)))

    def call(self, worker: int, target, method, /, *args, **kwargs) -> Callable[[], object]:
        """Like :meth:`send`; returns a function that waits for the result and returns it."""
        seq = next(self._seq)
        self._inbox[worker].put((seq, target, method, *self._pack(args, kwargs)))
        return lambda: self._result(worker, seq)

    def keep(self, key, obj, *, build: bool = False, worker: int | None = None) -> None:
        """Keep ``obj`` (or what the picklable factory ``obj()`` builds, ``build``) as
        ``key`` in ``worker`` (default every worker), for :meth:`send` / :meth:`call` with
        ``target=key``."""
        for w in range(len(self)) if worker is None else (worker,):
            self._inbox[w].put((None, key, None, (key, obj), {"build": build}))

    def share(self, obj) -> None:
        """Send ``obj`` to every worker once; later arguments that are ``obj`` travel as its
        key."""
        if id(obj) not in self._shared:
            self._shared[id(obj)] = obj
            self.keep(("shared", id(obj)), obj)

    def is_shared(self, obj) -> bool:
        """True when ``obj`` was sent by :meth:`share`."""
        return id(obj) in self._shared

    def close(self) -> None:
        """Stop the workers (waits briefly, then terminates)."""
        for box in self._inbox:
            box.put(None)
        for p in self._procs:
            p.join(timeout=5.0)
            if p.is_alive():
                p.terminate()
                p.join()
        for box in (*self._inbox, *self._outbox):
            box.cancel_join_thread()  # the workers are gone: what they did not read is moot
            box.close()
        self._procs = []

    def _pack(self, args: tuple, kwargs: dict) -> tuple[tuple, dict]:
        def swap(v):
            return _Handle(("shared", id(v))) if id(v) in self._shared else v

        return tuple(swap(a) for a in args), {k: swap(v) for k, v in kwargs.items()}

    def _result(self, worker: int, seq: int):
        got = self._replies[worker]
        while seq not in got:
            try:
                s, failed, value = self._outbox[worker].get(timeout=1.0)
            except queue.Empty:
                if not self._procs[worker].is_alive():
                    raise WorkerError(f"worker {worker} ended (exit code "
                                      f"{self._procs[worker].exitcode})") from None
                continue
            got[s] = (failed, value)
        failed, value = got.pop(seq)
        if failed:
            raise WorkerError(failed)
        return value


def _splits(value, m: int) -> bool:
    """Whether :func:`_part` may restrict ``value`` (an array or list of m rows, or a
    dataclass instance, whose fields it looks into)."""
    if isinstance(value, np.ndarray):
        return bool(value.ndim) and value.shape[0] == m
    if isinstance(value, list):
        return len(value) == m
    return dataclasses.is_dataclass(value) and not isinstance(value, type)


def _cut(value, rows: slice, m: int):
    """:func:`_part` of a value :func:`_splits` accepts: an array's rows directly."""
    return value[rows] if isinstance(value, np.ndarray) else _part(value, rows, m)


def _part(value, rows: slice, m: int):
    """``value`` restricted to ``rows`` when it has m rows (arrays, lists, dataclasses of
    them); anything else unchanged."""
    if isinstance(value, np.ndarray):
        return value[rows] if value.ndim and value.shape[0] == m else value
    if isinstance(value, list) and len(value) == m:
        return value[rows]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        parts = {f.name: _part(getattr(value, f.name), rows, m)
                 for f in dataclasses.fields(value) if f.init}
        if any(parts[k] is not getattr(value, k) for k in parts):
            return type(value)(**parts)
    return value


def _join(parts: list):
    """The results of the parts joined as one call's: arrays and lists concatenated,
    tuples and dataclasses item by item."""
    first = parts[0]
    if isinstance(first, np.ndarray):
        return np.concatenate(parts)
    if isinstance(first, tuple):
        return tuple(_join(list(values)) for values in zip(*parts, strict=True))
    if isinstance(first, list):
        return [x for p in parts for x in p]
    if dataclasses.is_dataclass(first):
        return type(first)(**{f.name: _join([getattr(p, f.name) for p in parts])
                              for f in dataclasses.fields(first) if f.init})
    raise TypeError(f"cannot join results of type {type(first).__name__}")


def split_rows(workers: Workers | None, fn: Callable, m: int, /, *args,
               on: Sequence[int] | None = None, **kwargs):
    """``fn(*args, **kwargs)`` computed on contiguous parts of its m rows at once, one part
    per worker (those listed in ``on``, default all) and the last here, joined in order.

    Every argument with m rows (an array's first axis, a list, a dataclass's fields) is
    split; everything else goes whole (shared objects by key, :meth:`Workers.share`).
    ``fn`` must be row-independent (row i of the result depends only on row i of the
    arguments) and importable by name; the result an array, a list or a dataclass of
    them (or a tuple of those). Without workers, or with fewer than :data:`MIN_SPLIT_ROWS`
    rows, one call here.
    """
    on = list(range(len(workers))) if workers is not None and on is None else on
    if workers is None or not on or m < MIN_SPLIT_ROWS:
        return fn(*args, **kwargs)
    bounds = np.linspace(0, m, len(on) + 2).round().astype(int)
    cuts = [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]

    def part(rows):
        def cut(v):
            return v if workers.is_shared(v) else _part(v, rows, m)

        return tuple(cut(a) for a in args), {k: cut(v) for k, v in kwargs.items()}

    waits = []
    for w, rows in zip(on, cuts[:-1], strict=True):
        a, k = part(rows)
        waits.append(workers.call(w, None, fn, *a, **k))
    a, k = part(cuts[-1])
    here = fn(*a, **k)
    return _join([wait() for wait in waits] + [here])
