"""Gait benchmark: agent-poses per second of one vectorised Animator.pose call.

Drives n agents (bodies 1.50–1.95 m, speeds 1.0–1.6 m/s) along straight paths with
MetaGait on flat ground, then times ``Animator.pose`` for all of them at once, and the
per-step ``Animator.command`` (ElevInterp + end-of-step walker evaluations). Prints a table.
A second table walks the agents for a few seconds at 25 fps (``animate_paths``, steps
desynchronised by the speeds) and gives the Animator's CPU time per output frame, split
into the step commands and the pose call, after the first second. The compiled kernels
are loaded before anything is timed.

Usage: ``python benchmarks/bench_gait.py [n ...]`` (default 100 1000).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from crowdwalk.body import Body
from crowdwalk.gait.animator import Animator
from crowdwalk.gait.metagait import MetaGait, animate_paths, level_step_length


def _flat(xy: np.ndarray) -> np.ndarray:
    return np.zeros(len(xy))


def _walkers(n: int, seed: int):
    """n bodies (1.50-1.95 m), speeds (1.0-1.6 m/s), start points (n, 2) and straight
    60 m paths (n, 2, 2) [m] in random directions."""
    rng = np.random.default_rng(seed)
    body = Body.from_heights(rng.uniform(1.50, 1.95, n))
    speed = rng.uniform(1.0, 1.6, n)
    start = np.column_stack([rng.uniform(0, 50, n), rng.uniform(0, 50, n)])
    heading = rng.uniform(-np.pi, np.pi, n)
    ahead = start + 60.0 * np.column_stack([np.cos(heading), np.sin(heading)])
    paths = np.stack([start, ahead], axis=1)
    return body, speed, start, paths


def bench(n: int, frames: int = 20, fps: float = 25.0) -> dict[str, float]:
    """Time n agents: command (first steps) and pose (``frames`` calls)."""
    body, speed, start, paths = _walkers(n, seed=0)
    animator = Animator(body, ground=_flat)
    metagait = MetaGait(n, base_toe_out=animator.style.toe_out)
    level = level_step_length(body.leg_length, speed)
    stance = np.column_stack([start, np.zeros(n)])
    t0 = time.perf_counter()
    cmd = metagait.next_step(np.arange(n), np.zeros(n), stance, np.ones(n, int), paths, level,
                             speed, body.height, _flat)
    animator.command(cmd)
    t_first = time.perf_counter() - t0
    second = metagait.next_step(np.arange(n), cmd.time + cmd.duration, cmd.target,
                                np.zeros(n, int), paths, level, speed, body.height, _flat)
    t0 = time.perf_counter()
    animator.command(second)
    t_command = time.perf_counter() - t0
    times = []
    for f in range(frames):
        t = float(second.time.min()) + f / fps
        t0 = time.perf_counter()
        frame = animator.pose(t)
        times.append(time.perf_counter() - t0)
        assert np.isfinite(frame.positions).all()
    per_call = float(np.median(times))
    return {
        "n": n,
        "pose_ms": 1e3 * per_call,
        "poses_per_s": n / per_call,
        "command_ms": 1e3 * t_command,
        "first_command_ms": 1e3 * t_first,
        "fallbacks": animator.stats["fallbacks"],
    }


class _TimedAnimator(Animator):
    """An Animator that adds up the CPU time of its commands and pose calls after t0."""

    def __init__(self, *args, t0: float, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.t0, self.cpu, self.frames, self.steps = t0, {"command": 0.0, "pose": 0.0}, 0, 0

    def command(self, cmd) -> None:
        c0 = time.process_time()
        super().command(cmd)
        if cmd.time.size and cmd.time.min() >= self.t0:
            self.cpu["command"] += time.process_time() - c0
            self.steps += cmd.agent.size

    def pose(self, t, agents=None):
        c0 = time.process_time()
        frame = super().pose(t, agents)
        if t >= self.t0:
            self.cpu["pose"] += time.process_time() - c0
            self.frames += 1
        return frame


def walking(n: int, seconds: float = 3.0, fps: float = 25.0) -> dict[str, float]:
    """CPU time per frame [ms] of the Animator for n agents walking straight paths."""
    body, speed, _, paths = _walkers(n, seed=1)
    animator = _TimedAnimator(body, ground=_flat, t0=1.0)
    animate_paths(body, paths, _flat, speed, seconds, fps, animator=animator)
    f = max(animator.frames, 1)
    return {"n": n, "command_ms": 1e3 * animator.cpu["command"] / f,
            "pose_ms": 1e3 * animator.cpu["pose"] / f, "steps": animator.steps / f}  # fmt: skip


def main(argv: list[str]) -> None:
    sizes = [int(a) for a in argv] or [100, 1000]
    walking(20, seconds=1.2)  # load the compiled kernels
    print(f"{'agents':>7} {'pose call [ms]':>15} {'agent-poses/s':>14} "
          f"{'step command [ms]':>18} {'first command [ms]':>19} {'fallbacks':>9}")  # fmt: skip
    for n in sizes:
        r = bench(n)
        print(f"{r['n']:>7d} {r['pose_ms']:>15.1f} {r['poses_per_s']:>14,.0f} "
              f"{r['command_ms']:>18.1f} {r['first_command_ms']:>19.1f} {r['fallbacks']:>9d}")
    print("target: >= 20,000 agent-poses/s for 1,000 agents in one call (issue 4, item 9)")
    print()
    print(f"{'agents':>7} {'steps/frame':>12} {'command [ms/frame]':>19} "
          f"{'pose [ms/frame]':>16} {'Animator [ms/frame]':>20}")  # fmt: skip
    for n in sizes:
        r = walking(n)
        print(f"{r['n']:>7d} {r['steps']:>12.1f} {r['command_ms']:>19.1f} {r['pose_ms']:>16.1f} "
              f"{r['command_ms'] + r['pose_ms']:>20.1f}")  # fmt: skip
    print("walking 3 s at 25 fps (CPU time after the first second); a crowd frame is one "
          "command batch and one pose call")


if __name__ == "__main__":
    main(sys.argv[1:])
