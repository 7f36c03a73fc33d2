"""Swing-foot clearance report: how far animated feet go below the ground in crowd runs.

Runs crowd scenarios with poses (default: quickstart — curb, stairs, ramp, slope —,
stairs_up_down and obstacle_stride), reads ``poses.sqlite`` back through
``crowdwalk.record.open_run`` and the terrain through ``build_world(...).terrain.height``,
and measures, for every stored agent-frame, the penetration [m] of the swing foot's sole
below the ground: points along the heel→ball and ball→toe-tip segments (the sole is a
segment: at a riser edge its middle can be inside the step while heel, ball and toe are
not), 1 cm apart, with every ground edge between two samples located by bisection and
measured exactly. The sole points are rebuilt from the stored root and local joint quaternions by
forward kinematics (the stored positions have no foot orientation).

The step each agent-frame belongs to comes from the steps the crowd decides (logged by a
run sink, :class:`StepLog`): its rise (step-up > 2 cm, step-down,
level), whether the planner supplied a Bezier swing curve (planned) or not (a shortened or
positioning step, ``_shorten``), and the swing phase. Prints one table per scenario and a
list of the worst agent-frames.

Usage: ``PYTHONPATH=. python scripts/foot_clearance_report.py [scenario.yaml ...]
[--duration S] [--fps F] [--out DIR]``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from crowdwalk.body import LEG_JOINTS, Body, forward_kinematics
from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.record import open_run
from crowdwalk.scenario import load_scenario
from crowdwalk.world import build_world

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ["scenarios/quickstart.yaml", "scenarios/stairs_up_down.yaml",
           "scenarios/obstacle_stride.yaml"]  # fmt: skip
HEEL_BALL = np.linspace(0.0, 1.0, 17)  # samples heel → ball
BALL_TOE = np.linspace(0.0, 1.0, 5)[1:]  # ball → toe tip


def _quat_to_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)  # fmt: skip


def sole_points(body: Body, positions: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """Points along both soles, (k, 2, q, 3) [m]: heel → ball → toe tip."""
    k = len(body)
    z = np.zeros(k)
    heel_local = np.stack([-body.heel_offset, z, -body.ankle_height], axis=1)
    tip_local = np.stack([body.toe_offset - body.ball_offset, z, z], axis=1)
    out = []
    for s in range(2):
        tc, sub, mtp = LEG_JOINTS[s, 2], LEG_JOINTS[s, 3], LEG_JOINTS[s, 4]
        heel = positions[:, tc] + np.einsum("kij,kj->ki", rotations[:, sub], heel_local)
        ball = positions[:, mtp]
        tip = ball + np.einsum("kij,kj->ki", rotations[:, mtp], tip_local)
        a = heel[:, None] + HEEL_BALL[None, :, None] * (ball - heel)[:, None]
        b = ball[:, None] + BALL_TOE[None, :, None] * (tip - ball)[:, None]
        out.append(np.concatenate([a, b], axis=1))
    return np.stack(out, axis=1)


def penetration(height, sole: np.ndarray, bisections: int = 10) -> np.ndarray:
    """Depth [m] of sole points (k, q, 3) below the ground ``height(xy)``, (k, q); where
    the ground jumps between two neighbouring samples (an edge), the edge is located by
    bisection and the depth there (on its high side) is credited to the nearer sample."""
    k, q = sole.shape[:2]
    g = height(sole[:, :, :2].reshape(-1, 2)).reshape(k, q)
    pen = g - sole[:, :, 2]
    r, i = np.nonzero(np.abs(np.diff(g, axis=1)) > 1e-3)
    if r.size:
        p0, p1, g0, g1 = sole[r, i], sole[r, i + 1], g[r, i], g[r, i + 1]
        lo, hi = np.zeros(r.size), np.ones(r.size)
        for _ in range(bisections):
            mid = 0.5 * (lo + hi)
            gm = height((p0 + mid[:, None] * (p1 - p0))[:, :2])
            near0 = np.abs(gm - g0) <= np.abs(gm - g1)
            lo, hi = np.where(near0, mid, lo), np.where(near0, hi, mid)
        t = np.where(g1 > g0, hi, lo)
        pt = p0 + t[:, None] * (p1 - p0)
        d = height(pt[:, :2]) - pt[:, 2]
        j = np.where(t > 0.5, i + 1, i)
        np.maximum.at(pen, (r, j), d)
    return pen


class StepLog:
    """A run sink (``crowdwalk.sinks.RunSink``) that keeps every decided step's timing,
    swing foot, rise, length and whether the planner gave it a swing curve."""

    def __init__(self) -> None:
        self.rows: list[dict] = []

    def begin(self, info) -> None:
        pass

    def steps(self, batch) -> None:
        planned = np.all(np.isfinite(batch.swing_bezier), axis=(1, 2))
        self.rows.append(dict(agent=batch.agent, t0=batch.start_time, duration=batch.duration,
                              foot=batch.foot.astype(int),
                              rise=batch.target[:, 2] - batch.start[:, 2], planned=planned,
                              length=batch.length))  # fmt: skip

    def frame(self, time, snapshot, poses) -> None:
        pass

    def end(self, summary) -> None:
        pass

    def table(self) -> dict[str, np.ndarray]:
        return {k: np.concatenate([r[k] for r in self.rows]) for k in self.rows[0]}


def case_of(rise: np.ndarray, planned: np.ndarray) -> np.ndarray:
    kind = np.where(rise > 0.02, "step-up", np.where(rise < -0.02, "step-down", "level"))
    return np.char.add(kind.astype(str), np.where(planned, " planned", " unplanned"))


def measure(scenario: str, out: Path, duration=None, fps=None) -> dict:
    """Run ``scenario`` into ``out`` and measure the swing soles; returns arrays over the
    agent-frames (depth [m], agent, time, case, phase, fallback, x, y)."""
    log = StepLog()
    run_scenario(ROOT / scenario if not Path(scenario).is_absolute() else scenario, out,
                 overrides=RunOverrides(poses=True, duration=duration, fps=fps), sinks=[log])
    cmds = log.table()
    terrain = build_world(load_scenario(out / "scenario.yaml")).terrain
    run = open_run(out)
    poses = run.poses()
    order = np.lexsort((cmds["t0"], cmds["agent"]))
    cmds = {k: v[order] for k, v in cmds.items()}
    rec = {k: [] for k in ("depth", "agent", "time", "case", "phase", "fallback", "x", "y",
                           "point")}  # fmt: skip
    for f in poses.frames:
        p = poses.frame(f)
        ids = p.ids
        body = Body.from_heights(np.array([poses.body_heights[i] for i in ids]))
        local = _quat_to_matrix(p.joints)
        root_rot = _quat_to_matrix(p.root_quaternion)
        pos, rot = forward_kinematics(body, p.root_position, root_rot, local)
        # the step in progress: the agent's latest command at or before this time
        key = ids + p.time / 1e6
        ck = cmds["agent"] + cmds["t0"] / 1e6
        j = np.searchsorted(ck, key + 1e-12, side="right") - 1
        ok = (j >= 0) & (cmds["agent"][np.maximum(j, 0)] == ids)
        j = np.maximum(j, 0)
        foot = cmds["foot"][j]
        phase = np.clip((p.time - cmds["t0"][j]) / cmds["duration"][j], 0.0, 1.0)
        sole = sole_points(body, pos, rot)[np.arange(ids.size), foot]  # (k, q, 3)
        pen = penetration(terrain.height, sole)
        worst = pen.argmax(axis=1)
        depth = pen.max(axis=1)
        rows = np.arange(ids.size)
        rec["depth"].append(np.where(ok, depth, 0.0))
        rec["agent"].append(ids)
        rec["time"].append(np.full(ids.size, p.time))
        rec["case"].append(case_of(cmds["rise"][j], cmds["planned"][j]))
        rec["phase"].append(phase)
        rec["fallback"].append(p.fallback.astype(bool))
        rec["x"].append(sole[rows, worst, 0])
        rec["y"].append(sole[rows, worst, 1])
        rec["point"].append(worst)
    return {k: np.concatenate(v) for k, v in rec.items()}


def report(name: str, r: dict, top: int = 8) -> str:
    d = r["depth"]
    lines = [f"\n## {name}: {d.size} agent-frames",
             f"{'case':<22}{'frames':>8}{'>5 mm':>8}{'>1 cm':>8}{'% >5mm':>9}{'worst mm':>10}"]
    cases = sorted(set(r["case"].tolist()))
    for c in ["all", *cases, "fallback"]:
        sel = (np.ones(d.size, bool) if c == "all" else r["fallback"] if c == "fallback"
               else r["case"] == c)  # fmt: skip
        n = int(sel.sum())
        if n == 0:
            continue
        x = d[sel]
        lines.append(f"{c:<22}{n:>8}{int((x > 0.005).sum()):>8}{int((x > 0.01).sum()):>8}"
                     f"{100 * (x > 0.005).mean():>9.3f}{1000 * x.max():>10.1f}")
    idx = np.argsort(-d)[:top]
    lines.append("worst: depth [mm], agent, time [s], case, swing phase, sole point "
                 "(0 heel .. 16 ball .. 20 toe tip), x, y")
    for i in idx:
        if d[i] <= 0.005:
            break
        lines.append(f"  {1000 * d[i]:6.1f}  a{r['agent'][i]:<4d} t={r['time'][i]:6.2f}  "
                     f"{r['case'][i]:<20} phase {r['phase'][i]:.2f}  pt {r['point'][i]:2d}  "
                     f"({r['x'][i]:.2f}, {r['y'][i]:.2f})"
                     f"{'  FALLBACK' if r['fallback'][i] else ''}")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenarios", nargs="*", default=DEFAULT)
    ap.add_argument("--duration", type=float, default=None, help="[s]")
    ap.add_argument("--fps", type=float, default=None, help="output frames per second")
    ap.add_argument("--out", type=Path, default=None, help="keep the run folders here")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        base = args.out or Path(tmp)
        for sc in args.scenarios:
            r = measure(sc, base / Path(sc).stem, args.duration, args.fps)
            print(report(Path(sc).stem, r), flush=True)


if __name__ == "__main__":
    main()
