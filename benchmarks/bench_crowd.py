"""Crowd simulation speed on the stadium egress (the performance reference).

Prints a table for 100, 1,000 and 5,000 agents: simulated seconds per wall second (and
per CPU second of this process, which is what the machine's other load does not change)
with the ``best_first_multistart`` planner,

- ``traj+steps``: trajectories (10 fps) and footsteps written, no poses;
- ``full poses``: trajectories, footsteps and full-body poses at 25 fps;

the share of planning, steering, poses and writing, and how the cost grows with n.

``--workers 0 auto`` runs each case in one process and with the run's worker processes
(:mod:`crowdwalk.workers`; ``auto``: one per further core from 500 walkers), alternately,
``--repeats`` times each; the table gives the median and, in brackets, the range.
``--threads N`` steers (and gathers neighbours) in N threads of this process instead of
one per core (:class:`crowdwalk.workers.RowThreads`; 1: one thread), to measure what the
split gains.

Usage: ``python benchmarks/bench_crowd.py [--agents 100 1000 5000] [--seconds S]
[--workers auto] [--repeats 1] [--threads N]``
"""

from __future__ import annotations

import argparse
import resource
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

import crowdwalk.workers as W
from crowdwalk.crowd.run import RunOverrides, run_scenario

ROOT = Path(__file__).parents[1]
STADIUM = ROOT / "scenarios" / "stadium_egress.yaml"


def stadium(n: int, out: Path) -> Path:
    """The stadium scenario with n agents (n/4 per section), stands deep enough to seat
    them at about 1.3 /m²."""
    sc = yaml.safe_load(STADIUM.read_text())
    per = n // 4
    depth = max(20.0, per / 1.3 / 18.0)  # stand section 18 m wide
    top = 28.0 + depth
    sc["terrain"]["extent"][3] = top + 2.0
    sc["terrain"]["features"][0]["footprint"] = [[0, 25], [80, 25], [80, top + 2], [0, top + 2]]
    for node in sc["routes"]["nodes"]:
        if node["name"].startswith("stand_"):
            x = node["xy"][0]
            node["xy"] = [x, 28.0 + depth / 2]
            node["area"] = [[x - 9, 28], [x + 9, 28], [x + 9, top], [x - 9, top]]
    for g in sc["groups"]:
        g["count"] = per
    path = out / f"stadium_{n}.yaml"
    path.write_text(yaml.safe_dump(sc, sort_keys=False))
    return path


def measure(path: Path, out: Path, seconds: float, poses: bool, workers: int | None) -> dict:
    started: list[float] = []

    def first_frame(*_):  # CPU time when the loop starts (after the setup)
        if not started:
            started.append(time.process_time())

    def children() -> float:  # CPU time of ended child processes (the run's workers)
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        return r.ru_utime + r.ru_stime

    kids = children()
    summary = run_scenario(path, out, progress=first_frame, overrides=RunOverrides(
        planner="best_first_multistart", duration=seconds, poses=poses,
        fps=25.0 if poses else 10.0, workers=workers))
    cpu = time.process_time() - started[0]
    worker_cpu = children() - kids
    tm = summary["timing"]
    steps = sum(a["steps"] for a in summary["agents"])
    return {
        "sim": summary["simulated_time_s"], "wall": tm["wall_s"], "cpu": cpu,
        "worker_cpu": worker_cpu,
        "setup": tm["setup_s"], "planning": tm["planning_s"], "steering": tm["steering_s"],
        "poses": tm["poses_s"], "writing": tm["writing_s"],
        "steps": steps,
        "runs": summary["planning"]["planner_runs"], "requests": summary["planning"]["requests"],
        "size": sum(f.stat().st_size for f in out.iterdir()) / 1e6,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agents", type=int, nargs="+", default=[100, 1000, 5000])
    parser.add_argument("--seconds", type=float, default=None,
                        help="simulated seconds per run (default: 20, 20, 10 without poses; "
                             "10, 6, 2 with poses)")
    parser.add_argument("--workers", nargs="+", default=["auto"],
                        help="worker processes per run: a number or 'auto' (alternated)")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--outputs", nargs="+", default=["traj+steps", "poses"],
                        choices=["traj+steps", "poses"])
    parser.add_argument("--threads", type=int, default=None,
                        help="row threads of this process (default: one per core)")
    args = parser.parse_args()
    if args.threads is not None:  # the process's RowThreads, which every run uses
        W._ROW_THREADS = W.RowThreads(args.threads)
    variants = [None if w == "auto" else int(w) for w in args.workers]
    plain = {100: 20.0, 1000: 20.0, 5000: 10.0}
    posed = {100: 10.0, 1000: 6.0, 5000: 2.0}
    tmp = Path(tempfile.mkdtemp(prefix="bench_crowd_"))
    rows = []
    try:
        for n in args.agents:
            path = stadium(n, tmp)
            for poses in (False, True):
                if ("poses" if poses else "traj+steps") not in args.outputs:
                    continue
                seconds = args.seconds or (posed if poses else plain).get(n, 5.0)
                runs: dict = {w: [] for w in range(len(variants))}
                for k in range(args.repeats):  # variants alternately, in both orders
                    order = range(len(variants)) if k % 2 == 0 else reversed(range(len(variants)))
                    for w in order:
                        out = tmp / f"run_{n}_{int(poses)}_{w}"
                        runs[w].append(measure(path, out, seconds, poses, variants[w]))
                        shutil.rmtree(out)
                for w, rs in runs.items():
                    rates = [r["sim"] / (r["wall"] - r["setup"]) for r in rs]
                    r = dict(rs[int(np.argsort(rates)[len(rates) // 2])])
                    r.update(n=n, output="full poses 25 fps" if poses else "traj+steps",
                             workers=args.workers[w], low=min(rates), high=max(rates))
                    rows.append(r)
                print(f"  done: {n} agents, {'poses' if poses else 'traj+steps'}", flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    head = (f"{'agents':>6} {'output':<18} {'workers':>7} {'sim s':>6} {'wall s':>7} "
            f"{'sim/wall (range)':>18} "
            f"{'sim/CPU':>8} {'wkr CPU':>7} {'plan':>5} {'steer':>5} {'poses':>5} {'write':>5} "
            f"{'plans run/asked':>16} {'µs/agent-step':>13} {'MB':>7}")
    print()
    print(head)
    print("-" * len(head))
    for r in rows:
        run = r["wall"] - r["setup"]
        share = {k: 100 * r[k] / run for k in ("planning", "steering", "poses", "writing")}
        rng = f"{r['sim'] / run:.2f} ({r['low']:.2f}-{r['high']:.2f})"
        print(f"{r['n']:>6} {r['output']:<18} {r['workers']:>7} {r['sim']:>6.1f} "
              f"{r['wall']:>7.1f} {rng:>18} {r['sim'] / max(r['cpu'], 1e-9):>8.2f} "
              f"{r['worker_cpu']:>7.1f} {share['planning']:>4.0f}% "
              f"{share['steering']:>4.0f}% {share['poses']:>4.0f}% "
              f"{share['writing']:>4.0f}% {r['runs']:>7}/{r['requests']:<8} "
              f"{1e6 * run / max(r['steps'], 1):>13.0f} {r['size']:>7.1f}")
    print("\nsim/wall and sim/CPU exclude setup (world, population, distance field); sim/CPU"
          " counts this process only; 'wkr CPU' is its workers' CPU seconds (set-up included);"
          " 'poses' includes the Animator's step commands, or with workers the wait for the"
          " worker that poses.")
    for output, w in ((o, w) for o in ("traj+steps", "full poses 25 fps") for w in args.workers):
        sel = [r for r in rows if r["output"] == output and r["workers"] == w]
        if len(sel) >= 2:
            n = np.array([r["n"] for r in sel], float)
            cost = np.array([(r["wall"] - r["setup"]) / r["sim"] for r in sel])
            slope = np.polyfit(np.log(n), np.log(cost), 1)[0]
            print(f"{output}, workers {w}: wall seconds per simulated second grow as n^{slope:.2f} "
                  f"({', '.join(f'{c:.2f} s at {int(k)}' for k, c in zip(n, cost, strict=True))})")


if __name__ == "__main__":
    main()
