"""Planner benchmark: a Table-2-style timing table with the work done, batch throughput,
the speed targets and the quality of each search against ``optimal``.

Run ``python benchmarks/bench_planners.py [--repeat N] [--profiles N] [--agents N]
[--targets-only ROUNDS] [--stages]``. Prints:

1. per terrain and grid resolution (13/11/7 intervals, n = 4), for each planner: median,
   p95 and min wall time per plan and the counted work (``Plan.stats``): nodes expanded,
   legality checks, lattice steps evaluated, key-frame solves, swing curves built (and
   reused from the flat-ground cache), and the energy gap (to the horizon's end) over
   ``optimal``;
2. ``plan_batch`` throughput for a crowd of walkers on random terrain (per plan, amortised);
3. the speed targets of issue 15 against what was measured;
4. on random terrain profiles, how often each search is within 1 % of ``optimal``
   (``best_first_multistart`` for several numbers of starts).

``--stages`` prints instead where the time of a plan goes, per planner: the table build
(per-leg grids, the lattice's arrays, the table kernel), the search and the plan
assembly (:mod:`planners.stages`), for single plans on flat ground and stairs (median of
``--repeat``) and for the batch of ``--agents`` walkers on random terrain (amortised).

``--targets-only ROUNDS`` measures the target cells alone (single plans on flat ground and
stairs, the batch of ``--agents`` walkers, 1,000 by default, as issue 15 names it), ROUNDS
times in turn, and prints each cell's median over the rounds and the spread (lowest and
highest round), then the counted work per plan of each cell (lattice steps evaluated,
key-frame solves, swing curves built, nodes expanded): run it alternately against another checkout
(``PYTHONPATH=OTHER python benchmarks/bench_planners.py --targets-only 5``) for a
comparison in the same minutes on a shared machine.
"""

from __future__ import annotations

import os

# Small arrays: BLAS worker threads only add contention on a shared machine.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from planners import GroundProfile, Leg, PlannerConfig, plan, plan_batch  # noqa: E402
from planners.stages import STAGES, recording  # noqa: E402


def terrains() -> dict[str, GroundProfile]:
    """The terrains of Table 2 (flat, stairs, slopes) and two uneven profiles [m]."""
    uneven_a = GroundProfile(  # Fig. 10(a)-like: a step, a block, a dip
        np.array([-2, 0.5, 0.5, 1.4, 1.4, 1.75, 1.75, 2.6, 2.6, 3.1, 3.1, 9]),
        np.array([0, 0, 0.12, 0.12, 0.22, 0.22, 0.12, 0.12, 0.04, 0.04, 0.12, 0.12]))
    uneven_b = GroundProfile(  # Fig. 10(b)-like: stairs up, a landing, a ramp down
        np.array([-2, 0.4, 0.4, 0.7, 0.7, 1.0, 1.0, 1.8, 3.0, 9]),
        np.array([0, 0, 0.16, 0.16, 0.32, 0.32, 0.48, 0.48, 0.2, 0.2]))
    return {
        "flat ground": GroundProfile.flat(),
        "upstairs": GroundProfile.stairs(0.17, 0.30, 8, first_edge=0.4),
        "uphill 10 %": GroundProfile(np.array([-2, 0.3, 8.0]), np.array([0, 0, 0.77])),
        "downstairs": GroundProfile.stairs(-0.17, 0.30, 8, first_edge=0.4),
        "downhill 10 %": GroundProfile(np.array([-2, 0.3, 8.0]), np.array([0, 0, -0.77])),
        "uneven (a)": uneven_a,
        "uneven (b)": uneven_b,
    }


def random_terrain(rng: np.random.Generator) -> GroundProfile:
    """Flat runs, stair flights (rise 12-19 cm, going 28-35 cm), blocks, ramps [m]."""
    s, z = [-2.0], [0.0]
    x = rng.uniform(0.25, 0.8)
    while x < 5.0:
        kind = rng.integers(4)
        h = z[-1]
        s.append(x)
        z.append(h)
        if kind == 0:
            x += rng.uniform(0.5, 1.5)
        elif kind == 1:
            rise = rng.choice([-1, 1]) * rng.uniform(0.12, 0.19)
            tread = rng.uniform(0.28, 0.35)
            for _ in range(rng.integers(2, 5)):
                s += [x]
                z += [z[-1] + rise]
                x += tread
                s += [x]
                z += [z[-1]]
        elif kind == 2:
            height, depth = rng.uniform(0.05, 0.2), rng.uniform(0.1, 0.4)
            s += [x, x + depth, x + depth]
            z += [h + height, h + height, h]
            x += depth + rng.uniform(0.3, 1.0)
        else:
            length, grade = rng.uniform(0.5, 2.0), rng.uniform(-0.15, 0.15)
            x += length
            s.append(x)
            z.append(h + grade * length)
    s.append(12.0)
    z.append(z[-1])
    return GroundProfile(np.array(s), np.array(z))


def timed(profile, leg, planner, config, repeat):
    """Wall and CPU times per plan (repeat,) [ms] and the plan."""
    plan(profile, leg, 1.34, planner, config)  # warm caches (flat swings, structures)
    wall, cpu, result = [], [], None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        result = plan(profile, leg, 1.34, planner, config)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return 1e3 * np.array(wall), 1e3 * np.array(cpu), result


def _to_reach(p) -> float:
    """What the searches minimise [J/kg]: the plan's energy plus the terminal estimate to
    the horizon's common end (PlannerConfig.terminal_cost)."""
    return p.energy_total + p.stats["terminal_energy"]


SEARCHES = ("best_first", "best_first_multistart", "optimal", "fixed")


def table_2(repeat: int) -> dict:
    """Prints the Table 2 analogue; returns the median ms per plan {(terrain, planner)}."""
    leg = Leg.from_body_height(1.75)
    print("Table 2 (n = 4 steps, 1.75 m body, 1.34 m/s): wall time per plan [ms] and the "
          "counted work of each plan")
    print(f"{'terrain':<15}{'int':>4} {'planner':<22}{'med':>7}{'p95':>7}{'min':>7}"
          f"{'nodes':>7}{'checks':>8}{'steps':>6}{'IK':>6}{'swings':>7}{'reused':>7}"
          f"{'gap %':>7}")
    medians = {}
    for name, profile in terrains().items():
        for intervals in (13, 11, 7):
            config = PlannerConfig(intervals=intervals)
            _, _, best = timed(profile, leg, "optimal", config, 1)
            for planner in SEARCHES:
                wall, _, p = timed(profile, leg, planner, config, repeat)
                st = p.stats
                gap = 100 * (_to_reach(p) / _to_reach(best) - 1) if best.ok and p.ok else np.nan
                if intervals == 13:
                    medians[name, planner] = float(np.median(wall))
                print(f"{name:<15}{intervals:>4} {planner:<22}{np.median(wall):>7.2f}"
                      f"{np.percentile(wall, 95):>7.2f}{wall.min():>7.2f}"
                      f"{st['nodes_expanded']:>7}{st['legality_checks']:>8}"
                      f"{st['lattice_steps']:>6}{st['key_frame_solves']:>6}"
                      f"{st['swing_curves']:>7}{st['swing_curves_reused']:>7}{gap:>7.2f}"
                      + ("" if p.ok else "  " + p.status))
    return medians


#: The counted work the target table shows (Plan.stats), with its column headers.
WORK = (("lattice_steps", "steps"), ("key_frame_solves", "IK"), ("swing_curves", "swings"),
        ("nodes_expanded", "nodes"))


def work(plans) -> dict:
    """Mean counted work per plan of ``plans`` (:data:`WORK`)."""
    return {k: float(np.mean([p.stats[k] for p in plans])) for k, _ in WORK}


def batch_runs(profiles, legs, speeds, planner: str, agents: int, counted: dict | None = None):
    """Time ``plan_batch`` of the walkers twice (ms per plan, amortised): first with every
    walker's leg new to the planners' per-leg caches, then again (as a crowd re-plans).
    ``counted`` gets the mean counted work per plan of each run."""
    warm = [Leg.from_body_height(1.6 + 0.01 * i) for i in range(16)]  # compiles, not legs
    plan_batch(profiles[:16], warm, speeds[:16], planner)
    runs = []
    for label in (f"batch of {agents}, random terrain, new legs",
                  f"batch of {agents}, random terrain, again"):
        t0, c0 = time.perf_counter(), time.process_time()
        plans = plan_batch(profiles, legs, speeds, planner)
        runs.append((label, 1e3 * (time.perf_counter() - t0) / agents,
                     1e3 * (time.process_time() - c0) / agents))
        if counted is not None:
            counted[label, planner] = work(plans)
    return runs


def batch(agents: int) -> dict:
    """Prints the batch table; returns ms per plan (amortised) per planner and run."""
    profiles, legs, speeds = random_batch(agents)
    print(f"\nplan_batch: {agents} walkers on random terrain (per plan, amortised; first "
          "with every leg new to the per-leg caches, then the same walkers again)")
    print(f"{'planner':<22}{'new legs [ms]':>15}{'again [ms]':>12}")
    per_plan = {}
    for planner in SEARCHES:
        runs = batch_runs(profiles, legs, speeds, planner, agents)
        per_plan.update({(label, planner): wall for label, wall, _ in runs})
        print(f"{planner:<22}{runs[0][1]:>15.3f}{runs[1][1]:>12.3f}")
    return per_plan


def targets(medians: dict, per_plan: dict, agents: int) -> None:
    print("\nSpeed targets (issue 15) against this run [ms per plan]")
    print(f"{'target':<44}{'limit':>7}" + "".join(f"{p:>23}" for p in SEARCHES))
    rows = [("single plan, flat ground (median)", 0.5, [medians["flat ground", p]
                                                        for p in SEARCHES]),
            ("single plan, upstairs (median)", 1.5, [medians["upstairs", p] for p in SEARCHES]),
            ("single plan, downstairs (median)", 1.5, [medians["downstairs", p]
                                                       for p in SEARCHES]),
            *((label, 0.1, [per_plan[label, p] for p in SEARCHES])
              for label in dict.fromkeys(key[0] for key in per_plan))]
    for label, limit, values in rows:
        print(f"{label:<44}{limit:>7.2f}" + "".join(
            f"{v:>17.3f} {'met' if v <= limit else 'NOT':>5}" for v in values))


def quality(count: int) -> None:
    rng = np.random.default_rng(2026)
    profiles = [random_terrain(rng) for _ in range(count)]
    leg = Leg.from_body_height(1.75)
    optimal = plan_batch(profiles, leg, 1.34, "optimal")
    fixed = plan_batch(profiles, leg, 1.34, "fixed")
    print(f"\nthe searches against optimal on {count} random terrain profiles "
          "(energy to the horizon's end, the searches' criterion; ok plans only)")
    print(f"{'search':<32}{'within 1 %':>11}{'median gap %':>14}{'p90 gap %':>11}"
          f"{'max gap %':>11}{'time [ms]':>11}")
    cases = [("best_first (Chen & Li)", "best_first", PlannerConfig())] + [
        (f"multistart, {s} start" + ("s" if s > 1 else "") + (" (default)" if s == 8 else ""),
         "best_first_multistart", PlannerConfig(search_starts=s)) for s in (1, 2, 3, 5, 8, 14)]
    for label, planner, config in cases:
        t0 = time.perf_counter()
        bf = plan_batch(profiles, leg, 1.34, planner, config)
        per_plan = 1e3 * (time.perf_counter() - t0) / count
        gaps = np.array([_to_reach(b) / _to_reach(o) - 1
                         for b, o in zip(bf, optimal, strict=True) if o.ok and b.ok])
        print(f"{label:<32}{100 * np.mean(gaps < 0.01):>10.1f}%"
              f"{100 * np.median(gaps):>14.2f}{100 * np.percentile(gaps, 90):>11.2f}"
              f"{100 * gaps.max():>11.2f}{per_plan:>11.2f}")
    gaps = np.array([_to_reach(f) / _to_reach(o) - 1
                     for f, o in zip(fixed, optimal, strict=True) if o.ok and f.ok])
    print(f"{'fixed (unplanned)':<32}{100 * np.mean(gaps < 0.01):>10.1f}%"
          f"{100 * np.median(gaps):>14.2f}{100 * np.percentile(gaps, 90):>11.2f}"
          f"{100 * gaps.max():>11.2f}")
    print(f"optimal found a legal plan on {sum(o.ok for o in optimal)} of {count}")


def random_batch(agents: int) -> tuple[list, list, np.ndarray]:
    """The random-terrain batch of the batch target: profiles, legs and speeds [m/s] of
    ``agents`` walkers (seed 7, the same in every table)."""
    rng = np.random.default_rng(7)
    profiles = [random_terrain(rng) for _ in range(agents)]
    legs = [Leg.from_body_height(h) for h in rng.normal(1.72, 0.08, agents).clip(1.5, 1.95)]
    return profiles, legs, rng.normal(1.34, 0.2, agents).clip(0.6, 2.0)


def targets_only(rounds: int, repeat: int, agents: int) -> None:
    """The target cells, ``rounds`` times in turn; median and spread over the rounds, and
    each cell's counted work per plan."""
    leg, grounds = Leg.from_body_height(1.75), terrains()
    profiles, legs, speeds = random_batch(agents)
    cells: dict = {}
    counted: dict = {}
    for _ in range(rounds):
        for name in ("flat ground", "upstairs", "downstairs"):
            for planner in SEARCHES:
                wall, cpu, p = timed(grounds[name], leg, planner, PlannerConfig(), repeat)
                label = f"single plan, {name} (median)"
                cells.setdefault((label, planner), []).append(
                    (float(np.median(wall)), float(np.median(cpu))))
                counted[label, planner] = work([p])
        for planner in SEARCHES:
            for label, wall, cpu in batch_runs(profiles, legs, speeds, planner, agents,
                                               counted):
                cells.setdefault((label, planner), []).append((wall, cpu))
    limits = {"flat ground": 0.5, "upstairs": 1.5, "downstairs": 1.5, "batch": 0.1}
    print(f"Speed targets (issue 15) [ms per plan]: wall time, median of {rounds} rounds "
          f"[lowest, highest round], and CPU time (all threads; median); {repeat} plans "
          f"per single-plan round; batches amortised over {agents} plans")
    print(f"{'target':<42}{'limit':>6}" + "".join(f"{p:>32}" for p in SEARCHES))
    for label in dict.fromkeys(key[0] for key in cells):
        limit = next(v for k, v in limits.items() if k in label)
        row = ""
        for planner in SEARCHES:
            v = np.array(cells[label, planner])
            row += (f"{np.median(v[:, 0]):>8.3f} [{v[:, 0].min():.3f}, {v[:, 0].max():.3f}]"
                    f" cpu {np.median(v[:, 1]):.3f}")
        print(f"{label:<42}{limit:>6.2f}{row}")
    print("\nCounted work per plan (Plan.stats, the batches' means): "
          + ", ".join(f"{h} = {k}" for k, h in WORK))
    print(f"{'target':<42}" + "".join(f"{p:>32}" for p in SEARCHES))
    for label in dict.fromkeys(key[0] for key in cells):
        row = ""
        for planner in SEARCHES:
            c = counted[label, planner]
            row += f"{' / '.join(f'{c[k]:.0f}' for k, _ in WORK):>32}"
        print(f"{label:<42}{row}")
    print(f"(machine load average {os.getloadavg()[0]:.1f})")


def _staged(run, *args) -> list[float]:
    """Wall time of ``run(*args)`` and of each of its :data:`~planners.stages.STAGES`
    [s]."""
    with recording() as times:
        t0 = time.perf_counter()
        run(*args)
        total = time.perf_counter() - t0
    return [total] + [times[s] for s in STAGES]


def stage_table(repeat: int, agents: int) -> None:
    """Prints the time per plan of each stage, per planner: single plans (median of
    ``repeat`` of each column) and the batch of ``agents`` walkers on random terrain
    (amortised; first with every leg new to the per-leg caches, then again)."""
    leg, grounds = Leg.from_body_height(1.75), terrains()
    profiles, legs, speeds = random_batch(agents)
    print("Stages of a plan [ms per plan, wall]: tables = grids (structure, per-leg grids "
          "and flat caches) + arrays (shifted profiles, lattice arrays) + kernel (the "
          "up-front table kernel; for the lazy planners the nodes only, their steps and "
          "swings are evaluated in the search); other = input checks and the rest; single "
          f"plans: median of {repeat} per column; batches: amortised over {agents}, "
          "their stages summed over the threads that plan chunks at once "
          "(planners.lattice.run_tasks), so they may add up to more than the total")
    head = ("total", "tables", "grids", "arrays", "kernel", "search", "assemble", "other")
    print(f"{'case':<32}{'planner':<23}" + "".join(f"{h:>9}" for h in head)
          + f"{'tables %':>10}{'search %':>10}")
    for planner in SEARCHES:
        rows = []
        for name in ("flat ground", "upstairs", "downstairs"):
            single = (grounds[name], leg, 1.34, planner)
            plan(*single)  # warm caches (flat swings, structures)
            rows.append((f"single plan, {name}",
                         np.median([_staged(plan, *single) for _ in range(repeat)], axis=0)))
        warm = [Leg.from_body_height(1.6 + 0.01 * i) for i in range(16)]
        plan_batch(profiles[:16], warm, speeds[:16], planner)
        for label in ("new legs", "again"):
            rows.append((f"batch of {agents}, {label}", np.array(_staged(
                plan_batch, profiles, legs, speeds, planner)) / agents))
        for label, v in rows:
            total, grids, arrays, kernel, search, assemble = 1e3 * v
            tables = grids + arrays + kernel
            other = total - tables - search - assemble
            cells = (total, tables, grids, arrays, kernel, search, assemble, other)
            print(f"{label:<32}{planner:<23}" + "".join(f"{c:>9.3f}" for c in cells)
                  + f"{100 * tables / total:>9.0f}%{100 * search / total:>9.0f}%")
    print(f"(machine load average {os.getloadavg()[0]:.1f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30, help="timed plans per cell")
    parser.add_argument("--profiles", type=int, default=200, help="random profiles")
    parser.add_argument("--agents", type=int, default=1000, help="walkers in the batch")
    parser.add_argument("--targets-only", type=int, default=0, metavar="ROUNDS",
                        help="only the target cells, ROUNDS times in turn")
    parser.add_argument("--stages", action="store_true",
                        help="only the time of each stage of a plan, per planner")
    args = parser.parse_args()
    if args.stages:
        stage_table(args.repeat, args.agents)
        return
    if args.targets_only:
        targets_only(args.targets_only, args.repeat, args.agents)
        return
    start = time.perf_counter()
    medians = table_2(args.repeat)
    per_plan = batch(args.agents)
    targets(medians, per_plan, args.agents)
    quality(args.profiles)
    print(f"\n(total {time.perf_counter() - start:.0f} s; machine load average "
          f"{statistics.mean(os.getloadavg()):.1f})")


if __name__ == "__main__":
    main()
