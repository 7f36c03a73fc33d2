"""Cost of writing trajectory frames to the run folder (``RunWriter.write_frame``).

Writes ``--frames`` frames of ``--agents`` walkers (random positions, a commit every
``--fps`` frames as in a run) and prints, per frame, the CPU time [ms] of
``write_frame``, of the commits (``flush``) and of ``close`` (which builds the index
``frame_id_idx`` since issue 16; before, every insert updated it). CPU time of this
thread, which the machine's other load changes less than wall time.

Usage: ``python benchmarks/bench_writer.py [--agents 10000] [--frames 50] [--repeats 3]``
(run it once per checkout and alternate them to compare).
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from crowdwalk.record import RunWriter

SQUARE = "POLYGON ((0 0, 80 0, 80 80, 0 80, 0 0))"


def measure(out: Path, agents: int, frames: int, fps: int) -> dict:
    rng = np.random.default_rng(0)
    ids = np.arange(agents)
    w = RunWriter(out, scenario_text="", walkable_wkt=SQUARE, fps=float(fps))
    write = flush = 0.0
    for f in range(frames):
        xy = rng.uniform(0, 80, (agents, 2))
        ang = rng.uniform(-np.pi, np.pi, agents)
        ori = np.column_stack([np.cos(ang), np.sin(ang)])
        z = rng.uniform(0, 3, agents)
        c0 = time.thread_time()
        w.write_frame(f, ids, xy, z, ori)
        c1 = time.thread_time()
        if f % fps == fps - 1:
            w.flush()
        write += c1 - c0
        flush += time.thread_time() - c1
    c0 = time.thread_time()
    w.close()
    close = time.thread_time() - c0
    return {"write": 1e3 * write / frames, "flush": 1e3 * flush / frames,
            "close": 1e3 * close / frames}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agents", type=int, default=10000)
    parser.add_argument("--frames", type=int, default=50)
    parser.add_argument("--fps", type=int, default=10)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_writer_"))
    try:
        rows = [measure(tmp / f"run{k}", args.agents, args.frames, args.fps)
                for k in range(args.repeats)]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f"{args.agents} walkers, {args.frames} frames, CPU ms per frame "
          f"(median of {args.repeats}; range)")
    for key in ("write", "flush", "close"):
        v = np.array([r[key] for r in rows])
        print(f"  {key:<6} {np.median(v):7.1f}  ({v.min():.1f}-{v.max():.1f})")
    total = np.array([sum(r.values()) for r in rows])
    print(f"  total  {np.median(total):7.1f}  ({total.min():.1f}-{total.max():.1f})")


if __name__ == "__main__":
    main()
