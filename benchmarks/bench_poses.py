"""Record the gait-engine calls of a run, replay them: time the engine alone and check that
its poses are bitwise the same.

``record`` runs a scenario (or bench_crowd's stadium with ``--stadium N`` walkers) in one
process with poses, and stores the engine's factory arguments (population, terrain), every
``command``/``pose`` call in order and a SHA-1 of every returned frame's arrays. ``replay``
rebuilds the engine with the code on ``PYTHONPATH``, makes the same calls, prints the CPU
seconds of the step commands and of the pose calls, and whether every frame is bitwise
equal to the recorded one (exit 1 if not).

Usage::

    python benchmarks/bench_poses.py record (SCENARIO | --stadium N) --seconds S [--fps F] \
        --out FILE
    python benchmarks/bench_poses.py replay FILE [--repeats R]
"""

from __future__ import annotations

import argparse
import hashlib
import pickle
import sys
import tempfile
import time
from dataclasses import fields
from pathlib import Path

import numpy as np

import crowdwalk.crowd.run as run_mod
from crowdwalk.crowd.run import RunOverrides, run_scenario


def frame_digest(frame) -> str:
    """SHA-1 over a PoseFrame's fields (array bytes, dtype and shape; scalars by repr)."""
    h = hashlib.sha1()
    for f in fields(frame):
        v = getattr(frame, f.name)
        if isinstance(v, np.ndarray):
            h.update(f"{f.name}{v.dtype}{v.shape}".encode())
            h.update(np.ascontiguousarray(v).tobytes())
        else:
            h.update(f"{f.name}{v!r}".encode())
    return h.hexdigest()


class _Recorder:
    def __init__(self, engine, calls: list) -> None:
        self.engine, self.calls = engine, calls

    @property
    def skeleton(self):
        return self.engine.skeleton

    def command(self, steps) -> None:
        self.calls.append(("command", pickle.dumps(steps), None))
        self.engine.command(steps)

    def pose(self, t, agents):
        frame = self.engine.pose(t, agents)
        self.calls.append(("pose", pickle.dumps((t, np.asarray(agents))), frame_digest(frame)))
        return frame


def record(scenario: Path, seconds: float | None, fps: float | None, out: Path) -> None:
    made: dict = {}
    original = run_mod._make_gait

    def make(pop, terrain):
        made["args"] = pickle.dumps((pop, terrain))
        made["calls"] = []
        return _Recorder(original(pop, terrain), made["calls"])

    run_mod._make_gait = make
    try:
        with tempfile.TemporaryDirectory() as tmp:
            run_scenario(scenario, Path(tmp) / "run", overrides=RunOverrides(
                duration=seconds, poses=True, fps=fps, workers=0))
    finally:
        run_mod._make_gait = original
    out.write_bytes(pickle.dumps(made))
    n = sum(c[0] == "pose" for c in made["calls"])
    print(f"recorded {len(made['calls']) - n} commands, {n} pose calls -> {out}")


def replay(path: Path, repeats: int) -> bool:
    made = pickle.loads(path.read_bytes())
    calls = [(kind, pickle.loads(arg), digest) for kind, arg, digest in made["calls"]]
    ok = True
    for r in range(repeats):
        engine = run_mod._make_gait(*pickle.loads(made["args"]))
        cpu = {"command": 0.0, "pose": 0.0}
        bad = 0
        for kind, arg, digest in calls:
            t0 = time.process_time()
            if kind == "command":
                engine.command(arg)
            else:
                frame = engine.pose(*arg)
            cpu[kind] += time.process_time() - t0
            if kind == "pose" and frame_digest(frame) != digest:
                bad += 1
        ok &= bad == 0
        print(f"replay {r}: commands {cpu['command']:.2f} s, poses {cpu['pose']:.2f} s, "
              f"total {cpu['command'] + cpu['pose']:.2f} s CPU; "
              f"{'IDENTICAL' if bad == 0 else f'{bad} frames DIFFER'}", flush=True)
    return ok


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    r.add_argument("scenario", type=Path, nargs="?")
    r.add_argument("--stadium", type=int, default=None, help="bench_crowd's stadium, N walkers")
    r.add_argument("--seconds", type=float, default=None)
    r.add_argument("--fps", type=float, default=None)
    r.add_argument("--out", type=Path, required=True)
    p = sub.add_parser("replay")
    p.add_argument("file", type=Path)
    p.add_argument("--repeats", type=int, default=1)
    args = ap.parse_args()
    if args.cmd == "record":
        if (args.scenario is None) == (args.stadium is None):
            sys.exit("bench_poses: give a SCENARIO or --stadium N")
        if args.stadium is not None:
            sys.path.insert(0, str(Path(__file__).parent))
            from bench_crowd import stadium

            tmp = Path(tempfile.mkdtemp(prefix="bench_poses_"))
            args.scenario = stadium(args.stadium, tmp)
        record(args.scenario, args.seconds, args.fps, args.out)
    else:
        sys.exit(0 if replay(args.file, args.repeats) else 1)


if __name__ == "__main__":
    main()
