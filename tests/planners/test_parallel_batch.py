"""A batch planned on several threads (planners.lattice.run_parts: each thread takes every
``parts``-th agent) gives byte-identical plans, counters included, to the same batch on
one thread, whatever the number of threads: an agent's plan does not depend on which
thread planned it or on the other agents."""

import sys
import time
from pathlib import Path

import numpy as np
import pytest

import planners.lattice as lattice
from planners import PLANNERS, Leg, plan_batch

_FIELDS = ("footholds_s", "footholds_z", "swing_controls", "phase_durations", "En", "Ev",
           "Ej", "E")


def _batch():
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    from bench_planners import random_terrain

    rng = np.random.default_rng(5)
    count = 3 * lattice.PARALLEL_AGENTS + 1  # parallel, and not a multiple of the threads
    profiles = [random_terrain(rng) for _ in range(count)]
    legs = [Leg.from_body_height(h) for h in rng.uniform(1.5, 1.95, count)]
    return profiles, legs, rng.uniform(0.8, 1.8, count), -rng.uniform(0.3, 0.8, count)


@pytest.mark.parametrize("planner", sorted(PLANNERS))
def test_threads_give_the_plans_of_one_thread(planner, monkeypatch):
    profiles, legs, speeds, trailing = _batch()
    runs = {}
    for threads in (1, 2, 3):
        monkeypatch.setattr(lattice, "THREADS", threads)
        runs[threads] = plan_batch(profiles, legs, speeds, planner, trailing=trailing)
    stats = [k for k in runs[1][0].stats if k != "time_s"]
    assert any(p.ok for p in runs[1]) and not all(p.ok for p in runs[1]), "a mixed batch"
    for threads in (2, 3):
        for p, q in zip(runs[1], runs[threads], strict=True):
            assert (p.status, p.message) == (q.status, q.message)
            for field in _FIELDS:
                assert getattr(p, field).tobytes() == getattr(q, field).tobytes(), field
            assert [p.stats[k] for k in stats] == [q.stats[k] for k in stats]


@pytest.mark.parametrize("planner", sorted(PLANNERS))
def test_chunks_on_threads_give_the_plans_of_one_thread(planner, monkeypatch):
    """The chunks of a batch shared out on the threads (lattice.run_tasks, each chunk's
    kernels on one thread) give the plans and counters of the chunks in turn."""
    plan_module = sys.modules["planners.plan"]  # (planners.plan is the function)
    profiles, legs, speeds, trailing = _batch()
    monkeypatch.setattr(plan_module, "BATCH_CHUNK", 5)  # 5 chunks, the last one short
    runs = {}
    for threads, shared in ((1, False), (2, True), (3, True)):
        monkeypatch.setattr(lattice, "THREADS", threads)
        monkeypatch.setattr(plan_module, "CHUNK_THREADS", shared)
        runs[threads] = plan_batch(profiles, legs, speeds, planner, trailing=trailing)
    stats = [k for k in runs[1][0].stats if k != "time_s"]
    for threads in (2, 3):
        assert len(runs[threads]) == len(profiles)
        for p, q in zip(runs[1], runs[threads], strict=True):
            assert (p.status, p.message) == (q.status, q.message)
            for field in _FIELDS:
                assert getattr(p, field).tobytes() == getattr(q, field).tobytes(), field
            assert [p.stats[k] for k in stats] == [q.stats[k] for k in stats]


def test_run_tasks_keeps_order_and_raises():
    """run_tasks returns the tasks' results in task order and passes a task's error on."""
    assert lattice.run_tasks(lambda i: i * i, 7) == [i * i for i in range(7)]

    def bad(i):
        if i == 3:
            raise ValueError("task 3")
        return i

    with pytest.raises(ValueError, match="task 3"):
        lattice.run_tasks(bad, 6)


def test_run_tasks_stops_taking_tasks_after_an_error(monkeypatch):
    """After a task raised, the threads take no further task."""
    monkeypatch.setattr(lattice, "THREADS", 2)
    done = []

    def task(i):
        done.append(i)
        if i == 0:
            raise ValueError("first")
        time.sleep(0.002)  # (the other thread takes few tasks before the error)
        return i

    with pytest.raises(ValueError, match="first"):
        lattice.run_tasks(task, 200)
    assert len(done) < 100
