"""What holds the walkers at a narrow door's mouth during its long gaps (jams).

Runs ``crowdwalk verify``'s bottleneck scenario (``crowdwalk.verify._bottleneck``: a
room, a 2 m long opening from x = 8 to 10 m on the axis y = 5 m; verify's ``_run``) and
records every stand of a walker at the mouth (7.4 < x < 8.05, |y − 5| < 0.75) that has
stood for more than ``--stuck`` seconds. Each is asked again (counterfactual
``choose_steps`` calls on the same row; the run is not changed): without the reserved
steps of ``mouth_priority``; with a fan of step directions every 5° instead of the
default's 11 (is the block a gap between candidate directions?); without any neighbour
(walls only); and without each set of one, two or three neighbours within 0.8 m, their
bodies and reservations (the smallest sets that let it step; ``blockers``).

For each gap of more than 1.5 s between consecutive walkers entering the opening (x = 8;
steady part, entrants 6 to n − 5) it prints one JSON line: the walkers recorded at the
mouth, their median place, seconds stood, and their single blockers; the mutual pairs
(each one of the other's single blockers at some stand in the gap: an arch of bodies
wedged against each other); the stands freed by no neighbour set (walls), by the finer
fan, by dropping the reservations. Then one line of totals over the seeds.

Usage: ``python scripts/bottleneck_jams.py WIDTH SEED [SEED ...] [--stuck 0.5] [--gap 1.5]
[--set FIELD=VALUE ...]`` (``--gap``: the entry gaps reported are longer than this [s]).
"""

from __future__ import annotations

import itertools
import json
from collections import Counter, defaultdict
from dataclasses import replace

import numpy as np
from bottleneck_binds import (
    Recorder,
    _row,
    bottleneck_arguments,
    entries,
    recorded_runs,
    without_columns,
)

#: the finer fan of step directions [deg] (every 5° to ±90°)
FINE = (0.0, *(s * a for a in range(5, 95, 5) for s in (-1.0, 1.0)))


class JamRecorder(Recorder):
    """Records the stands of stuck walkers at the mouth (:attr:`decisions`) with the
    counterfactual calls of the module docstring."""

    def __init__(self, stuck: float) -> None:
        super().__init__()
        self.stuck = stuck

    def _record(self, choose, idx, position, stance, kw, res) -> dict:
        x, y = position[:, 0], position[:, 1] - 5.0
        stuck = np.asarray(kw["stuck"])
        rows = np.flatnonzero((x > 7.4) & (x < 8.05) & (np.abs(y) < 0.75) & ~res.move
                              & (stuck > self.stuck))
        nb, lim, m = kw["neighbours"], kw.get("limits"), len(position)
        big = nb.valid.shape[1]
        for r in rows:
            one = _row(kw, r, m)
            p1, s1 = position[r:r + 1], stance[r:r + 1]
            no_lim = {k: v for k, v in one.items() if k != "limits"}
            d = {"t": self._now["t"], "agent": int(idx[r]), "x": float(x[r]),
                 "y": float(y[r]), "stuck": float(stuck[r]),
                 "fine": bool(choose(p1, s1, **{**one, "params": replace(
                     one["params"], offsets_deg=FINE)}).move[0]),
                 "nolim": bool(choose(p1, s1, **no_lim).move[0]),
                 "alone": bool(choose(p1, s1, **{**no_lim, "neighbours": replace(
                     one["neighbours"], valid=np.zeros_like(one["neighbours"].valid))}
                     ).move[0])}
            near = [k for k in np.flatnonzero(nb.valid[r])
                    if np.linalg.norm(nb.now[r, k] - position[r]) < 0.8]
            sets: list[tuple] = []
            for size in (1, 2, 3):
                for combo in itertools.combinations(near, size):
                    if any(set(s) <= set(combo) for s in sets):
                        continue
                    v = one["neighbours"].valid.copy()
                    v[:, list(combo)] = False
                    o = {**one, "neighbours": replace(one["neighbours"], valid=v)}
                    if lim is not None:
                        o["limits"] = without_columns(one["limits"], big, combo)
                    if choose(p1, s1, **o).move[0]:
                        sets.append(combo)
                if sets:
                    break
            d["blockers"] = [[int(nb.agent[r, k]) for k in s] for s in sets]
            self.decisions.append(d)
        return {}


def jams(decisions: list[dict], traj, seed: int, gap: float = 1.5) -> list[dict]:
    """One summary per entry gap over ``gap`` [s] of one run."""
    ent = entries(traj)
    ent = ent[5:len(ent) - 5]
    out = []
    for (tl, _, _), (tf, _, _) in zip(ent[:-1], ent[1:], strict=True):
        if tf - tl <= gap:
            continue
        ds = [d for d in decisions if tl <= d["t"] < tf]
        by = defaultdict(list)
        for d in ds:
            by[d["agent"]].append(d)
        single = {a: {s[0] for d in v for s in d["blockers"] if len(s) == 1}
                  for a, v in by.items()}
        mutual = sorted({tuple(sorted((a, b))) for a, bs in single.items() for b in bs
                         if a in single.get(b, ())})
        out.append({
            "seed": seed, "t": [round(tl, 2), round(tf, 2)], "gap_s": round(tf - tl, 2),
            "stands": len(ds), "mutual_pairs": [list(p) for p in mutual],
            "walls_only": sum(not d["alone"] for d in ds),
            "no_set_of_3": sum(d["alone"] and not d["blockers"] for d in ds),
            "by_one": sum(any(len(s) == 1 for s in d["blockers"]) for d in ds),
            "by_two_or_three": sum(bool(d["blockers"]) and all(len(s) > 1 for s in
                                                               d["blockers"]) for d in ds),
            "fine_fan_frees": sum(d["fine"] for d in ds),
            "reservation_binds": sum(d["nolim"] for d in ds),
            "walkers": {a: {"x": round(float(np.median([d["x"] for d in v])), 2),
                            "y": round(float(np.median([d["y"] for d in v])), 2),
                            "stands": len(v), "single_blockers": sorted(single[a])}
                        for a, v in sorted(by.items(), key=lambda kv: -len(kv[1]))[:6]}})
    return out


def main() -> None:
    ap = bottleneck_arguments(__doc__)
    ap.add_argument("--stuck", type=float, default=0.5)
    ap.add_argument("--gap", type=float, default=1.5)
    args = ap.parse_args()
    total: Counter = Counter()
    for seed, rec, run in recorded_runs(args, lambda: JamRecorder(args.stuck)):
        for j in jams(rec.decisions, run.traj, seed, args.gap):
            print(json.dumps(j), flush=True)
            total["gaps"] += 1
            total["gap_s"] += j["gap_s"]
            total["with_mutual_pair"] += bool(j["mutual_pairs"])
            for k in ("stands", "walls_only", "no_set_of_3", "by_one", "by_two_or_three",
                      "fine_fan_frees", "reservation_binds"):
                total[k] += j[k]
    print(json.dumps({"width": args.width, "seeds": args.seeds, "total": {
        k: round(v, 1) for k, v in total.items()}}))


if __name__ == "__main__":
    main()
