"""The crowd loop's speed in one process, its kernels loaded, and where the simulation
thread's time goes (the A/B runs of docs/architecture.md "Crowd speed", session 22).

One warm-up run (it loads every kernel from numba's cache), then ``--rounds`` runs of
each variant, alternated in both orders, of the room of ``bench_vs_jupedsim.py`` or the
stadium of ``bench_crowd.py`` (trajectories and footsteps written). Printed per variant:
simulated s per wall s of the loop and per CPU s of the process, and the simulation
thread's wall, run, runqueue and sleep time per simulated s (Linux
``/proc/self/task/<tid>/schedstat``: time on a core, time waiting for one — other
processes' load —, and the rest: asleep on the GIL or on the row threads).

Variants: ``default``; ``t1``, ``t2``: that many row threads
(:class:`crowdwalk.workers.RowThreads`); ``c<k>``: ``workers.CHUNKS_PER_THREAD = k``.

Usage: ``python benchmarks/bench_loop.py room|stadium AGENTS SECONDS [--rounds 2]
[--variants default ...]``
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

import bench_crowd  # noqa: E402
import bench_vs_jupedsim  # noqa: E402

import crowdwalk.workers as W  # noqa: E402
from crowdwalk.crowd.run import RunOverrides, run_scenario  # noqa: E402


def _sched() -> tuple[float, float]:
    """This thread's time on a core and waiting for one so far [s] (0, 0 off Linux)."""
    try:
        with open(f"/proc/self/task/{threading.get_native_id()}/schedstat") as f:
            run, wait = f.read().split()[:2]
        return int(run) / 1e9, int(wait) / 1e9
    except OSError:
        return 0.0, 0.0


def one(path: Path, out: Path, overrides: RunOverrides, variant: str) -> dict:
    """One run of ``variant``: the loop's rates and the simulation thread's times."""
    W._ROW_THREADS = W.RowThreads(int(variant[1:]) if variant.startswith("t") else
                                  W.available_cores())
    chunks = getattr(W, "CHUNKS_PER_THREAD", None)  # (absent before session 22)
    if variant.startswith("c"):
        W.CHUNKS_PER_THREAD = int(variant[1:])
    started: list = []

    def first(*_):  # the loop's start (after the set-up)
        if not started:
            started.append((time.perf_counter(), time.process_time(), *_sched()))

    try:
        summary = run_scenario(path, out, overrides=overrides, progress=first)
    finally:
        if chunks is not None:
            W.CHUNKS_PER_THREAD = chunks
        W._ROW_THREADS.close()
    wall, cpu, (run, queue) = time.perf_counter(), time.process_time(), _sched()
    shutil.rmtree(out)
    sim = summary["simulated_time_s"]
    wall -= started[0][0]
    run, queue = run - started[0][2], queue - started[0][3]
    return {"sim/wall": sim / wall, "sim/CPU": sim / (cpu - started[0][1]),
            "wall": wall / sim, "run": run / sim, "runqueue": queue / sim,
            "sleep": (wall - run - queue) / sim}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", choices=["room", "stadium"])
    ap.add_argument("agents", type=int)
    ap.add_argument("seconds", type=float)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--variants", nargs="+", default=["default"])
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_loop_"))
    try:
        if args.scenario == "room":
            path = bench_vs_jupedsim.room_scenario(args.agents, tmp)
            overrides = RunOverrides(duration=args.seconds, poses=False)
        else:
            path = bench_crowd.stadium(args.agents, tmp)
            overrides = RunOverrides(planner="best_first_multistart", duration=args.seconds,
                                     poses=False, fps=10.0)
        one(path, tmp / "warm", overrides, args.variants[0])
        runs: dict = {v: [] for v in args.variants}
        for r in range(args.rounds):
            for v in args.variants if r % 2 == 0 else args.variants[::-1]:
                runs[v].append(one(path, tmp / "run", overrides, v))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    for v, rs in runs.items():
        col = {k: [r[k] for r in rs] for k in rs[0]}
        print(f"{v:>8}: sim s per wall s {', '.join(f'{x:.2f}' for x in col['sim/wall'])}; "
              f"per CPU s {', '.join(f'{x:.2f}' for x in col['sim/CPU'])}; simulation "
              f"thread per sim s (median): wall {np.median(col['wall']):.3f}, run "
              f"{np.median(col['run']):.3f}, runqueue {np.median(col['runqueue']):.3f}, "
              f"sleep {np.median(col['sleep']):.3f} s")


if __name__ == "__main__":
    main()
