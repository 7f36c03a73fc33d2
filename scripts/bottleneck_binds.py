"""What holds walkers entering a narrow door: the binding constraint of each decision.

Runs ``crowdwalk verify``'s bottleneck scenario (``crowdwalk.verify._bottleneck``: a
room, a 2 m long opening from x = 8 to 10 m on the axis y = 5 m; verify's ``_run``) and
records every decision of walkers in front of the mouth (6 < x < 8.6, |y − 5| < 1.2).
Each is asked again without parts of the model (counterfactual ``choose_steps`` calls on
the same rows; the run itself is not changed): without the reserved steps of
``mouth_priority`` (``limits``), without the soft neighbour and wall terms, without any
neighbour, and without each neighbour within 1 m (its body and its reservation). The
headway model's cap along the chosen direction, the in-time clash check, the same-tick
yield and the wake time are read from the run.

Consecutive walkers entering the opening (x = 8) are paired, leader L and follower F,
and binned by their lateral distance there (under 0.1 m, 0.1–0.3 m, 0.3 m and more, as
``bottleneck_diagnose.py``'s ``entry_gap_by_dy``). Each of F's decisions between L's
entry and its own gets one label (:func:`label`), and its time (until F decides again) is
summed per label. Prints one JSON line per bin: pairs, entry gap median and mean [s],
F's distance to the mouth and lateral distance from L's entry point at L's entry [m],
how often and for how long F stands (and how often the stand ends early by the wake),
and the seconds per pair by label.

Usage: ``python scripts/bottleneck_binds.py WIDTH SEED [SEED ...] [--count 60]
[--by dy|gap] [--set FIELD=VALUE ...]`` (``--by gap``: bins of entry gap up to 1.0,
1.1–1.5 and over 1.5 s; a step more than 45° off the door's direction is labelled
``…:side``) (``--set``: CrowdParams fields, ``steering.``-prefixed
SteeringParams fields, Python literals). The seeds' pairs are pooled.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from collections import Counter, defaultdict
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np

import crowdwalk.crowd.simulation as simulation
from crowdwalk.crowd import CrowdParams
from crowdwalk.crowd.params import parse_overrides
from crowdwalk.verify import _bottleneck, _run
from crowdwalk.workers import _cut, _splits

BINS = {"<0.1": (0.0, 0.1), "0.1-0.3": (0.1, 0.3), ">=0.3": (0.3, np.inf)}
#: ``--by gap``: the pairs binned by their entry gap [s] instead; the edges sit half a
#: frame of the 10 fps trajectories above 1.0 and 1.5 s (gaps of exactly 1.0 s go into the
#: first bin, of 1.5 s into the second, as ``bottleneck_jams.py --gap``'s "over 1.0 s")
GAP_BINS = {"<=1.0": (0.0, 1.05), "1.1-1.5": (1.05, 1.55), ">1.5": (1.55, np.inf)}
#: a step more than this [deg] off the +x direction (into the door) is a side step
SIDE_DEG = 45.0


def _region(pos: np.ndarray) -> np.ndarray:
    return (pos[:, 0] > 6.0) & (pos[:, 0] < 8.6) & (np.abs(pos[:, 1] - 5.0) < 1.2)


def _row(kw: dict, r: int, m: int) -> dict:
    """``choose_steps``' keyword arguments cut to row ``r`` of m (as the row threads
    cut them; the clearance field and the parameters whole)."""
    return {k: (_cut(v, slice(r, r + 1), m) if k not in ("clearance", "params")
                and _splits(v, m) else v) for k, v in kw.items()}


class Recorder:
    """Wraps the crowd's steering, clash check and commit to record the decisions
    (:attr:`decisions`, dicts) of walkers in front of the mouth; a context manager (the
    wrappers are removed on leaving it)."""

    def __init__(self) -> None:
        self.decisions: list[dict] = []
        self._now: dict = {}
        self._saved: tuple = ()

    def __enter__(self) -> Recorder:
        sim, rec = simulation.CrowdSimulation, self
        decide, gap_steps, commit = sim._decide, sim._gap_steps, sim._commit
        choose, clashes = simulation.choose_steps, simulation.clashes_with_neighbours
        self._saved = (decide, gap_steps, commit, choose, clashes)

        def _decide(s, idx, t):
            rec._now = {"t": t}
            return decide(s, idx, t)

        def _gap_steps(s, idx, pos, nbs, walled=None):
            rec._now["idx"] = idx.copy()
            return gap_steps(s, idx, pos, nbs, walled)

        def _choose(position, stance, **kw):
            res = choose(position, stance, **kw)
            idx = rec._now.get("idx")
            if idx is not None and len(idx) == len(position):
                rec._now["rows"] = rec._record(choose, idx, position, stance, kw, res)
            return res

        def _clashes(nbs, rows, **kw):
            c = clashes(nbs, rows, **kw)
            for q, r in enumerate(rows):
                if (d := rec._now.get("rows", {}).get(int(r))) is not None:
                    d["clash"] = bool(c[q])
            return c

        def _commit(s, idx, te, t, direction, yaw, plan, wake=None):
            rows = rec._now.get("rows", {})
            for r, d in rows.items():
                d.update(plan_move=bool(plan.move[r]), plan_len=float(plan.length[r]),
                         wake=float(wake[r]) if wake is not None else np.inf)
            commit(s, idx, te, t, direction, yaw, plan, wake)
            for r, d in rows.items():
                a = int(idx[r])
                step = s.state.pos1[a] - s.state.pos0[a]
                d.update(stepped=bool(s.state.t1[a] > t + 1e-9 and np.any(step != 0)),
                         t1=float(s.state.t1[a]),
                         heading=float(np.degrees(np.arctan2(step[1], step[0]))))

        sim._decide, sim._gap_steps, sim._commit = _decide, _gap_steps, _commit
        simulation.choose_steps, simulation.clashes_with_neighbours = _choose, _clashes
        return self

    def __exit__(self, *exc) -> None:
        sim = simulation.CrowdSimulation
        sim._decide, sim._gap_steps, sim._commit, simulation.choose_steps, \
            simulation.clashes_with_neighbours = self._saved

    def _record(self, choose, idx, position, stance, kw, res) -> dict:
        rows = np.flatnonzero(_region(position))
        out: dict = {}
        if not rows.size:
            return out
        nb, lim, gap = kw["neighbours"], kw.get("limits"), kw.get("gap")
        reach = (gap.along(res.direction)[1] if gap is not None
                 else np.full(len(position), np.inf))
        no_lim = {k: v for k, v in kw.items() if k != "limits"}
        alts = {"nolim": choose(position, stance, **no_lim),
                "nosoft": choose(position, stance, **{**kw, "params": replace(
                    kw["params"], personal_weight=0.0, wall_weight=0.0)}),
                "alone": choose(position, stance, **{**no_lim, "neighbours": replace(
                    nb, valid=np.zeros_like(nb.valid))})}
        m = len(position)
        for r in rows:
            d = {"t": self._now["t"], "agent": int(idx[r]), "x": float(position[r, 0]),
                 "y": float(position[r, 1] - 5.0), "move": bool(res.move[r]),
                 "free": float(res.free_length[r]), "reach": float(reach[r]),
                 "nominal": float(kw["nominal_step"][r])}
            for name, alt in alts.items():
                d[name] = (bool(alt.move[r]), float(alt.free_length[r]))
            single = {}
            near = np.flatnonzero(nb.valid[r] & (np.linalg.norm(nb.now[r] - position[r],
                                                                axis=1) < 1.0))
            for k in near:
                a = int(nb.agent[r, k])
                one = {**kw, "neighbours": replace(nb, valid=nb.valid & (
                    np.arange(nb.valid.shape[1]) != k)[None, :])}
                if lim is not None:
                    one["limits"] = without_columns(lim, nb.valid.shape[1], [k])
                alt = choose(position[r:r + 1], stance[r:r + 1], **_row(one, r, m))
                single[a] = (bool(alt.move[0]), float(alt.free_length[0]))
            d["single"] = single
            out[int(r)] = d
            self.decisions.append(d)
        return out


def without_columns(limits, k_nbs: int, cols) -> object:
    """The hard-test neighbours ``limits`` without neighbours ``cols`` (columns of the
    K = ``k_nbs`` gathered ones): their bodies and, when ``limits`` holds reservations
    (``mouth_priority.with_reservations``: K + K columns, the reservations in the
    neighbours' order, no ``agent``), their reservations too."""
    valid = limits.valid.copy()
    cols = list(cols)
    valid[:, cols] = False
    if valid.shape[1] == 2 * k_nbs:
        valid[:, [k_nbs + c for c in cols]] = False
    return replace(limits, valid=valid)


def label(d: dict, leader: int) -> str:
    """What a decision of a follower of ``leader`` was held by: ``stand:`` soft terms
    (it would step without them), priority (without the reserved steps), hard_leader /
    hard_other (without that one neighbour), hard_several (only without all), walls
    (not even alone), clash (the in-time check), yield (same tick); ``step:`` headway
    (the speed model's cap shortened it), full (at least 0.9 of the nominal step), or
    short_ by the same causes (a step 0.1 m longer without them)."""
    def freed(mv_fl, step):
        return mv_fl[0] if not step else mv_fl[1] > d["free"] + 0.1
    for step in (False, True):
        if step != d["move"]:
            continue
        kind = "step:short_" if step else "stand:"
        if step:
            if d.get("clash"):
                return "stand:clash"
            if not d.get("plan_move", False):
                return "stand:no_plan"
            if not d.get("stepped", True):
                return "stand:yield"
            if d["reach"] < d["free"] - 1e-9:
                return "step:headway"
            if d["plan_len"] >= 0.9 * d["nominal"]:
                return "step:full"
        if not step and freed(d["nosoft"], False):
            return "stand:soft"
        if freed(d["nolim"], step):
            return kind + "priority"
        who = [a for a, v in d["single"].items() if freed(v, step)]
        if who:
            return kind + ("hard_leader" if leader in who else "hard_other")
        if freed(d["alone"], step):
            return kind + "hard_several"
        return kind + ("walls" if not step else "walls_or_plan")
    raise AssertionError("unreachable")


def entries(traj) -> list[tuple[float, int, float]]:
    """(time [s], walker, y − 5 [m]) of each walker's first crossing of x = 8, in time
    order."""
    out = []
    for i in np.unique(traj.id):
        k = np.flatnonzero(traj.id == i)
        c = np.flatnonzero((traj.x[k][:-1] < 8.0) & (traj.x[k][1:] >= 8.0))
        if c.size:
            j = k[c[0] + 1]
            out.append((traj.frame[j] / traj.fps, int(i), float(traj.y[j] - 5.0)))
    return sorted(out)


def attribute(decisions: list[dict], traj, acc: dict, by: str = "dy") -> None:
    """Add one run's pairs (steady part: entrants 6 to n − 5) to ``acc`` (per bin of
    lateral distance, ``by="dy"``, or of entry gap, ``by="gap"``). A step more than
    :data:`SIDE_DEG` off +x gets its label with ``:side`` appended."""
    mine = defaultdict(list)
    for d in decisions:
        mine[d["agent"]].append(d)
    ent = entries(traj)
    ent = ent[5:len(ent) - 5]
    for (tl, il, yl), (tf, jf, yf) in zip(ent[:-1], ent[1:], strict=True):
        key, bins = (tf - tl, GAP_BINS) if by == "gap" else (abs(yf - yl), BINS)
        b = next(k for k, (lo, hi) in bins.items() if lo <= key < hi)
        a = acc.setdefault(b, {"gaps": [], "dist": [], "lat": [], "stands": 0, "woke": 0,
                               "stand_s": 0.0, "s": Counter()})
        a["gaps"].append(tf - tl)
        before = [d for d in mine[jf] if d["t"] <= tl]
        if before:
            a["dist"].append(8.0 - before[-1]["x"])
            a["lat"].append(abs(before[-1]["y"] - yl))
        for d in mine[jf]:
            if not tl <= d["t"] < tf or "t1" not in d:
                continue
            side = d["stepped"] and abs(d.get("heading", 0.0)) > SIDE_DEG
            a["s"][label(d, il) + (":side" if side else "")] += d["t1"] - d["t"]
            if not d["stepped"]:
                a["stands"] += 1
                a["stand_s"] += d["t1"] - d["t"]
                a["woke"] += int(d["wake"] < d["t1"] + 1e-9 and d["t1"] - d["t"] < 0.25 - 1e-6)


def report(acc: dict) -> list[dict]:
    """One summary per bin."""
    out = []
    for b in (*BINS, *GAP_BINS):
        if b not in acc:
            continue
        a, n = acc[b], len(acc[b]["gaps"])
        out.append({"dy": b, "pairs": n,
                    "entry_gap_median_s": round(float(np.median(a["gaps"])), 2),
                    "entry_gap_mean_s": round(float(np.mean(a["gaps"])), 2),
                    "gap_s_sum": round(float(np.sum(a["gaps"])), 1),
                    "follower_to_mouth_m": round(float(np.median(a["dist"])), 2),
                    "follower_lateral_m": round(float(np.median(a["lat"])), 2),
                    "stands_per_pair": round(a["stands"] / n, 2),
                    "stand_s_per_pair": round(a["stand_s"] / n, 3),
                    "stands_woken_share": round(a["woke"] / max(a["stands"], 1), 2),
                    "s_per_pair": {k: round(v / n, 3) for k, v in a["s"].most_common()}})
    return out


def bottleneck_arguments(doc: str) -> argparse.ArgumentParser:
    """The diagnosis scripts' common arguments: door width [m], seeds, ``--count``
    walkers and ``--set FIELD=VALUE`` crowd parameter overrides."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("width", type=float)
    ap.add_argument("seeds", type=int, nargs="+")
    ap.add_argument("--count", type=int, default=60)
    ap.add_argument("--set", nargs="*", default=[], metavar="FIELD=VALUE")
    return ap


def recorded_runs(args: argparse.Namespace, recorder) -> Iterator[tuple[int, Recorder, object]]:
    """(seed, its recorder, its run) for each of ``args.seeds``: verify's bottleneck run
    with ``recorder()`` (a :class:`Recorder`) recording its decisions."""
    params = CrowdParams().with_overrides(parse_overrides(args.set))
    for seed in args.seeds:
        with recorder() as rec, tempfile.TemporaryDirectory() as tmp:
            run = _run(_bottleneck(args.width, seed, args.count), Path(tmp) / "run", params)
        yield seed, rec, run


def main() -> None:
    ap = bottleneck_arguments(__doc__)
    ap.add_argument("--by", choices=("dy", "gap"), default="dy",
                    help="bin the pairs by lateral distance or by entry gap")
    args = ap.parse_args()
    acc: dict = {}
    for _, rec, run in recorded_runs(args, Recorder):
        attribute(rec.decisions, run.traj, acc, args.by)
    for row in report(acc):
        print(json.dumps({"width": args.width, "seeds": args.seeds, **row}))


if __name__ == "__main__":
    main()
