"""Sweeps on Dask distributed: a real scheduler and two worker processes on 127.0.0.1, a
worker killed in the middle, resuming; seeds; the report's intervals across seeds."""

import csv
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from crowdwalk.sweep import load_sweep, mean_interval, parse_seeds, run_sweep, trials_of

ROOT = Path(__file__).resolve().parents[1]
SWEEP = """
scenario: {scenario}
seeds: "1..2"
planners: [best_first, fixed]
axes:
  groups.0.free_speed.mean: [1.2, 1.4]
duration: 2.0
"""


def _sweep_file(tmp_path) -> Path:
    path = tmp_path / "sweep.yaml"
    path.write_text(SWEEP.format(scenario=ROOT / "scenarios" / "lone_walker.yaml"))
    return path


def _start(args, env, log):
    return subprocess.Popen([sys.executable, "-m", *args], cwd=ROOT, env=env,
                            stdout=log, stderr=subprocess.STDOUT)


def test_a_sweep_on_a_real_scheduler_survives_a_killed_worker(tmp_path):
    spec = load_sweep(_sweep_file(tmp_path))
    trials = trials_of(spec)
    assert len(trials) == 8 and len({t.name for t in trials}) == 8
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    sched_file = tmp_path / "scheduler.json"
    log = open(tmp_path / "dask.log", "w")  # noqa: SIM115
    procs = [_start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                     "--no-dashboard", "--scheduler-file", str(sched_file)], env, log)]
    try:
        for _ in range(300):
            if sched_file.exists() and sched_file.stat().st_size:
                break
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        for _ in range(2):
            procs.append(_start(["distributed.cli.dask_worker", address, "--nthreads", "1",
                                 "--no-nanny", "--no-dashboard"], env, log))
        out = tmp_path / "out"
        finished: list[str] = []
        killed = threading.Event()

        def progress(done, total, trial):
            finished.append(trial)
            if done == 2 and not killed.is_set():
                procs[1].kill()  # one worker dies in the middle of the sweep
                killed.set()

        try:
            run_sweep(spec, out, scheduler=address, progress=progress)
        except Exception:  # noqa: BLE001 - tasks lost with the worker: run the sweep again
            pass
        assert killed.is_set()
        done_before = {p.name: (p / "summary.json").stat().st_mtime_ns
                       for p in (out / "trials").iterdir() if (p / "summary.json").exists()}
        assert set(finished) <= set(done_before)  # no finished trial was lost
        rerun: list[str] = []
        report = run_sweep(spec, out, scheduler=address,
                           progress=lambda d, t, name: rerun.append(name))
        for name, mtime in done_before.items():  # finished trials are not run again
            assert (out / "trials" / name / "summary.json").stat().st_mtime_ns == mtime
        assert set(rerun).isdisjoint(done_before)
        assert sorted(p.name for p in (out / "trials").iterdir()
                      if not p.name.startswith(".")) == sorted(t.name for t in trials)
    finally:
        for p in procs:
            p.kill()
            p.wait()
        log.close()
    with open(out / "manifest.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 8
    assert {r["planner"] for r in rows} == {"best_first", "fixed"}
    for r in rows:  # every trial ran with its own seed and axis value
        summary = json.loads((out / "trials" / r["trial"] / "summary.json").read_text())
        assert summary["seed"] == int(r["seed"])
        assert summary["agents"][0]["free_speed_m_s"] == pytest.approx(
            float(r["groups.0.free_speed.mean"]), abs=0.06)
    text = report.read_text()
    assert "Headline: planned (best_first) against unplanned (fixed)" in text


def test_seeds_and_intervals():
    assert parse_seeds("3..5") == [3, 4, 5] and parse_seeds("1,4") == [1, 4]
    with pytest.raises(ValueError, match="seeds"):
        parse_seeds("5..x")
    rng = np.random.default_rng(0)
    x = rng.normal(2.0, 1.0, 400)
    m, lo, hi, n = mean_interval(x)
    assert n == 400 and lo < 2.0 < hi and hi - lo < 0.25
    m, lo, hi, n = mean_interval(x[:5])
    assert lo < m < hi and hi - lo > 0.25  # five seeds: a wider t interval
    assert np.isnan(mean_interval([1.0])[1])  # one seed: no interval


def test_a_run_takes_its_seed_from_the_command_line(tmp_path):
    from crowdwalk.crowd.run import RunOverrides, prepare

    path = ROOT / "scenarios" / "bottleneck.yaml"
    (sc4, _, sim4, _, _), (sc5, _, sim5, _, _) = (prepare(path, RunOverrides(seed=s))
                                                  for s in (4, 5))
    assert (sc4.simulation.seed, sc5.simulation.seed) == (4, 5)
    assert not np.array_equal(sim4.pop.body_height, sim5.pop.body_height)
