"""Peak memory of a run against its agent count (what crowdwalk.checks budgets per agent).

Runs ``stadium_egress`` with 100 / 400 / 1,000 agents for a few simulated seconds, poses on,
each in a fresh process, and prints peak RSS and the growth per agent between sizes.

    python benchmarks/bench_memory.py
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from tempfile import TemporaryDirectory

ROOT = Path(__file__).resolve().parents[1]
CHILD = """
import resource, sys
from crowdwalk.crowd.run import RunOverrides, run_scenario
run_scenario(sys.argv[1], sys.argv[2], overrides=RunOverrides(max_agents=int(sys.argv[3]),
             duration=float(sys.argv[4]), poses=True))
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def peak_rss_kib(agents: int, duration: float) -> int:
    with TemporaryDirectory() as out:
        proc = subprocess.run([sys.executable, "-c", CHILD,
                               str(ROOT / "scenarios" / "stadium_egress.yaml"), out, str(agents),
                               str(duration)], capture_output=True, text=True, check=True,
                              cwd=ROOT)
    return int(proc.stdout.split()[-1])


def main() -> None:
    from crowdwalk.checks import BYTES_PER_AGENT

    sizes, duration = (100, 400, 1000), 4.0
    rows = [(n, peak_rss_kib(n, duration)) for n in sizes]
    print(f"| agents | peak RSS [MiB] | growth per agent [kB] |  (budget: "
          f"{BYTES_PER_AGENT // 1000} kB)")
    print("|---|---|---|")
    for i, (n, kib) in enumerate(rows):
        per = "" if i == 0 else f"{(kib - rows[0][1]) * 1.024 / (n - rows[0][0]):.0f}"
        print(f"| {n:,} | {kib / 1024:.0f} | {per} |")


if __name__ == "__main__":
    main()
