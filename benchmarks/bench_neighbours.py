"""Cost of finding the deciders' neighbours: ``scipy.spatial.cKDTree`` (build + query)
against the grid of ``crowd.neighbours`` (``_Grid`` + ``_nearest``), the same k nearest.

``--agents`` walkers at about 2 /m², ``--deciders`` of them asking for ``--count`` + 1
nearest within ``--reach`` m, as one tick of a run does. Prints the CPU time of this
thread [ms] per tick, median of ``--repeats``; both in the same minutes, alternated.

Usage: ``python benchmarks/bench_neighbours.py [--agents 1000 10000 20000]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd.neighbours import _Grid, _nearest


def _tree(now, me, k, reach):
    t = time.thread_time()
    tree = cKDTree(now)
    b = time.thread_time()
    _, found = tree.query(me, k=k, distance_upper_bound=reach)
    return b - t, time.thread_time() - b, np.atleast_2d(found).reshape(len(me), k)


def _grid(now, me, k, reach):
    t = time.thread_time()
    grid = _Grid(now, reach)
    b = time.thread_time()
    found = np.full((len(me), k), len(now), np.int64)
    _nearest(me, now, grid.origin, grid.cell, grid.shape, grid.start, grid.order,
             reach**2, found)
    return b - t, time.thread_time() - b, found


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--agents", type=int, nargs="+", default=[1000, 10000, 20000])
    ap.add_argument("--deciders", type=float, default=0.08, help="share deciding per tick")
    ap.add_argument("--count", type=int, default=32)
    ap.add_argument("--reach", type=float, default=3.0)
    ap.add_argument("--repeats", type=int, default=40)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print(f"{'walkers':>8} {'deciders':>8} | {'tree build':>10} {'query':>7} | "
          f"{'grid build':>10} {'query':>7} | same")
    for n in args.agents:
        now = rng.uniform(0, np.sqrt(n / 2.0), (n, 2))
        me = now[rng.choice(n, max(1, int(n * args.deciders)), replace=False)]
        k = args.count + 1
        _grid(now, me, k, args.reach)  # compile / load the kernels
        times = {"tree": [], "grid": []}
        for _ in range(args.repeats):
            for name, f in (("tree", _tree), ("grid", _grid)):
                build, query, found = f(now, me, k, args.reach)
                times[name].append((build, query))
                if name == "tree":
                    want = found
        same = bool(np.array_equal(found, want))
        t, g = (np.median(np.array(times[x]), axis=0) * 1e3 for x in ("tree", "grid"))
        print(f"{n:>8} {len(me):>8} | {t[0]:>10.2f} {t[1]:>7.2f} | {g[0]:>10.2f} "
              f"{g[1]:>7.2f} | {same}")
    print("CPU ms per tick of this thread, median; 'same': the grid's k nearest are the "
          "tree's, in order (random positions have no exact ties)")


if __name__ == "__main__":
    main()
