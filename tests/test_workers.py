"""Worker processes and row threads: split calls give one call's result, failures surface,
and a run with workers (or with its steering split among threads) writes the same run
folder as one in a single thread."""

from __future__ import annotations

import sqlite3
import threading
import time
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import crowdwalk.workers as W
from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.workers import RowThreads, WorkerError, Workers, split_rows, worker_count

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Pair:
    total: np.ndarray
    rows: list


def weighted(x: np.ndarray, labels: list, *, table: np.ndarray, scale: float) -> Pair:
    """Row-independent: row i of the result from row i of x and labels."""
    return Pair(total=scale * (x @ table[: x.shape[1]]), rows=[f"{s}:{len(s)}" for s in labels])


def fail_on_ones(x: np.ndarray) -> np.ndarray:
    if x[0, 0] == 1.0:
        raise ValueError(f"bad rows: {len(x)}")
    return x


@pytest.fixture(scope="module")
def workers():
    with Workers(2) as w:
        yield w


def test_split_rows_equals_one_call_and_sends_shared_objects_once(workers, monkeypatch):
    monkeypatch.setattr(W, "MIN_SPLIT_ROWS", 2)
    rng = np.random.default_rng(3)
    x = rng.normal(size=(200, 3))
    labels = [f"a{i}" for i in range(200)]
    table = rng.normal(size=(200, 2))  # 200 rows too: a shared object is never split
    workers.share(table)
    whole = weighted(x, labels, table=table, scale=2.0)
    split = split_rows(workers, weighted, 200, x, labels, table=table, scale=2.0)
    assert np.array_equal(split.total, whole.total)
    assert split.rows == whole.rows
    only_one = split_rows(workers, weighted, 200, x, labels, table=table, scale=2.0, on=[1])
    assert np.array_equal(only_one.total, whole.total)


def where(x: np.ndarray, labels: list) -> Pair:
    """Row-independent, and says which thread computed each row (each part lasts long
    enough for the others to be taken by other threads)."""
    time.sleep(0.05)
    return Pair(total=2.0 * x, rows=[threading.get_ident()] * len(labels))


def test_row_threads_equal_one_call_and_use_every_thread(monkeypatch):
    x = np.random.default_rng(4).normal(size=(200, 3))
    labels = [f"a{i}" for i in range(200)]
    threads = RowThreads(3)
    try:
        whole = weighted(x, labels, table=np.eye(3), scale=2.0)
        split = threads.map(weighted, 200, x, labels, table=np.eye(3), scale=2.0)
        assert np.array_equal(split.total, whole.total) and split.rows == whole.rows
        monkeypatch.setattr(W, "CHUNKS_PER_THREAD", 4)  # 12 parts of 50 ms
        parts = threads.map(where, 200, x, labels, min_rows=10)
        assert np.array_equal(parts.total, 2.0 * x)
        # parts of 50 ms, taken as threads come free: every thread takes some
        assert set(parts.rows) >= {threading.get_ident()} and len(set(parts.rows)) == 3
        few = threads.map(where, 200, x, labels, min_rows=150)  # too few rows to split
        assert set(few.rows) == {threading.get_ident()}
    finally:
        threads.close()


def test_row_threads_do_not_wait_for_a_thread_that_does_not_start():
    """A pool thread kept busy elsewhere takes no part: the calling thread computes them
    all and returns without waiting for it."""
    x = np.random.default_rng(5).normal(size=(400, 3))
    labels = [f"a{i}" for i in range(400)]
    threads = RowThreads(2)
    release = threading.Event()
    try:
        threads._pool.submit(release.wait, 30.0)  # the one pool thread, busy
        t0 = time.perf_counter()
        parts = threads.map(weighted, 400, x, labels, table=np.eye(3), scale=2.0, min_rows=10)
        assert time.perf_counter() - t0 < 10.0
        assert np.array_equal(parts.total, weighted(x, labels, table=np.eye(3),
                                                    scale=2.0).total)
        assert parts.rows == weighted(x, labels, table=np.eye(3), scale=2.0).rows
    finally:
        release.set()
        threads.close()


def test_a_failure_in_a_worker_is_raised_here_with_its_traceback(workers, monkeypatch):
    monkeypatch.setattr(W, "MIN_SPLIT_ROWS", 2)
    x = np.zeros((200, 1))
    x[:67] = 1.0  # the first worker's part
    with pytest.raises(WorkerError, match="bad rows: 67"):
        split_rows(workers, fail_on_ones, 200, x)
    # the worker goes on serving after a failed call
    assert workers.call(0, None, len, [1, 2, 3])() == 3


def test_a_dead_worker_is_reported_not_waited_for():
    with Workers(1) as w:
        w._procs[0].kill()
        w._procs[0].join()
        w.keep("big", np.zeros(1_000_000))  # more than a pipe holds: nobody reads it
        with pytest.raises(WorkerError, match="ended"):
            w.call(0, None, len, [1])()
    # and closing did not wait for the dead worker to read it


def test_worker_count_follows_cores_and_run_size():
    assert worker_count(10, None) == 0
    assert worker_count(10, 3) == 3
    assert worker_count(10_000, None) == W.available_cores() - 1
    assert worker_count(1_000, None) == W.available_cores() - 1  # posing: a worker pays
    assert worker_count(1_000, None, poses=False) == 0  # steering alone: one process faster


def _rows(path: Path, table: str) -> list:
    with closing(sqlite3.connect(path)) as con:
        return con.execute(f"SELECT * FROM {table} ORDER BY rowid").fetchall()


def test_a_run_with_workers_writes_the_same_run_folder(tmp_path, monkeypatch):
    """Steering split over worker 1 (every tick, however few decide) and posing in
    worker 0 give the run folder of a run in one process."""
    monkeypatch.setattr(W, "MIN_SPLIT_ROWS", 2)
    scenario = ROOT / "scenarios" / "bottleneck.yaml"
    runs = {}
    for workers in (0, 2):
        out = tmp_path / f"w{workers}"
        summary = run_scenario(scenario, out, overrides=RunOverrides(
            duration=4.0, poses=True, fps=10.0, workers=workers))
        runs[workers] = out
        assert summary["poses"] == "written"
    a, b = runs[0], runs[2]
    assert (a / "footsteps.csv").read_bytes() == (b / "footsteps.csv").read_bytes()
    assert len((a / "footsteps.csv").read_bytes().splitlines()) > 50
    assert _rows(a / "trajectories.sqlite", "trajectory_data") == \
        _rows(b / "trajectories.sqlite", "trajectory_data")
    assert _rows(a / "poses.sqlite", "pose_frame") == _rows(b / "poses.sqlite", "pose_frame")


def test_a_run_steered_in_threads_writes_the_same_run_folder(tmp_path, monkeypatch):
    """Neighbours, steering, clash tests and footing split among three threads (every
    tick, however few decide) give the run folder of a run in one thread."""
    import crowdwalk.crowd.simulation as S

    monkeypatch.setattr(W, "MIN_THREAD_ROWS", 1)
    monkeypatch.setattr(W, "MIN_LIGHT_ROWS", 1)  # the light kernels too
    scenario = ROOT / "scenarios" / "bottleneck.yaml"
    runs = {}
    for count in (1, 3):
        threads = RowThreads(count)
        monkeypatch.setattr(S, "row_threads", lambda threads=threads: threads)
        try:
            run_scenario(scenario, tmp_path / f"t{count}", overrides=RunOverrides(
                duration=4.0, poses=False, fps=10.0, workers=0))
        finally:
            threads.close()
        runs[count] = tmp_path / f"t{count}"
    a, b = runs[1], runs[3]
    assert len((a / "footsteps.csv").read_bytes().splitlines()) > 50
    assert (a / "footsteps.csv").read_bytes() == (b / "footsteps.csv").read_bytes()
    assert _rows(a / "trajectories.sqlite", "trajectory_data") == \
        _rows(b / "trajectories.sqlite", "trajectory_data")


def test_a_negative_worker_count_is_bad_input():
    from crowdwalk.crowd.run import check_overrides
    from crowdwalk.errors import InputError

    with pytest.raises(InputError, match="workers must be an integer >= 0"):
        check_overrides(RunOverrides(workers=-1))


def test_workers_collect_garbage_less_often_than_python_by_default():
    """A worker (where the gait engine poses) raises the first-generation threshold of
    the garbage collector to WORKER_GC_THRESHOLD; this process keeps its own."""
    import gc

    with W.Workers(1) as workers:
        inside = workers.call(0, None, gc.get_threshold)()
    assert inside[0] == W.WORKER_GC_THRESHOLD > gc.get_threshold()[0]
    assert inside[1:] == gc.get_threshold()[1:]
