"""Peak memory of a run against its agent count (what crowdwalk.checks budgets per agent).

Runs ``stadium_egress`` with its stands sized for the largest count (as ``bench_crowd.py``
sizes them; the same world for every count) and the first n of its walkers, for a few
simulated seconds, each in a fresh process, and prints the peak RSS
of the run's process, of its largest worker process (:mod:`crowdwalk.workers`; from 500
walkers one per further core) and the growth per agent between sizes (of the two summed:
an upper bound, the peaks need not coincide).

    python benchmarks/bench_memory.py [--agents 100 400 1000] [--no-poses] [--seconds 4]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path
from tempfile import TemporaryDirectory

ROOT = Path(__file__).resolve().parents[1]
CHILD = """
import resource, sys
sys.path.insert(0, sys.argv[5])
from pathlib import Path
from bench_crowd import stadium
from crowdwalk.crowd.run import RunOverrides, run_scenario
out = Path(sys.argv[1])
run_scenario(stadium(int(sys.argv[6]), out.parent), out, overrides=RunOverrides(
    duration=float(sys.argv[3]), poses=sys.argv[4] == "1", max_agents=int(sys.argv[2])))
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
      resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
"""


def peak_rss_kib(agents: int, duration: float, poses: bool, world: int) -> tuple[int, int]:
    """Peak RSS [KiB] of the run's process and of its largest child process (``agents``
    of the stadium sized for ``world`` walkers)."""
    with TemporaryDirectory() as tmp:
        proc = subprocess.run([sys.executable, "-c", CHILD, str(Path(tmp) / "run"), str(agents),
                               str(duration), "1" if poses else "0", str(ROOT / "benchmarks"),
                               str(world)],
                              capture_output=True, text=True, check=True, cwd=ROOT)
    main, child = proc.stdout.split()[-2:]
    return int(main), int(child)


def main() -> None:
    from crowdwalk.checks import BYTES_PER_AGENT

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--agents", type=int, nargs="+", default=[100, 400, 1000])
    ap.add_argument("--no-poses", action="store_true")
    ap.add_argument("--seconds", type=float, default=4.0)
    args = ap.parse_args()
    world = max(args.agents)
    rows = [(n, *peak_rss_kib(n, args.seconds, not args.no_poses, world)) for n in args.agents]
    print(f"stadium for {world:,} walkers, poses {'off' if args.no_poses else 'on'}, "
          f"{args.seconds:g} s simulated; "
          f"budget in crowdwalk.checks: {BYTES_PER_AGENT // 1000} kB per agent")
    print("| agents | run process peak RSS [MiB] | largest worker [MiB] | growth per agent [kB] |")
    print("|---|---|---|---|")
    for i, (n, kib, child) in enumerate(rows):
        total, first = kib + child, rows[0][1] + rows[0][2]
        per = "" if i == 0 else f"{(total - first) * 1.024 / (n - rows[0][0]):.0f}"
        print(f"| {n:,} | {kib / 1024:.0f} | {child / 1024:.0f} | {per} |")


if __name__ == "__main__":
    main()
