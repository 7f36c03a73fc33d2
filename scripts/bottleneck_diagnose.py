"""Why a narrow door is slow: time gaps, lanes, shoulder turning and stalls in one run.

Runs ``crowdwalk verify``'s bottleneck scenario (``crowdwalk.verify._bottleneck``: a
room, a 2 m long opening from x = 8 to 10 m on the axis y = 5 m) once and prints one
JSON line: the flow as verify measures it; the time gaps between walkers leaving
(x = 10) and entering (x = 8) in the steady part (crossings 6 to n − 5); at mid-opening
(x = 9) the median |y| off the axis, the median lateral distance between consecutive
walkers (``dy``; about the body width apart = two lanes, near 0 = one file), the share
of consecutive pairs more than 0.2 m apart laterally, their time gaps apart and in one
file, and the median torso twist (facing against the walking direction; the disc body
always faces its step); the mean number of walkers inside the opening and in front of
it (7 < x < 8, |y − 5| < 1), and the share of those standing (< 0.1 m/s over a frame);
the gaps longer than 1.5 s with what they add up to; where they enter (x = 8), the
median lateral distance between consecutive walkers and their entry time gaps by it
(under 0.1 m, 0.1–0.3 m, 0.3 m and more); and the mean speed of walkers 0–1,
1–2 and 2–4 m past the opening's end (``speed_after``: a slow band there holds the door back).

Also, with ``--why``: of the decisions of walkers in front of the opening and inside it,
how many stand, and how many of those would have stepped without the soft neighbour
and wall terms (``SteeringParams.personal_weight``, ``wall_weight`` set to 0 in a
second, counterfactual call of ``choose_steps`` on the same rows): a stand by choice,
not a hard block; and how many would have stepped with no neighbours at all (a third
call with every neighbour invalid: the walls and the walker's own target allow a step,
so it stands for its neighbours).

With ``--blockers SECONDS``: for walkers standing longer than that against the wall
beside the opening, the single neighbours whose removal would let them step (an arch
at the mouth shows as one walker blocking two).

Usage: ``python scripts/bottleneck_diagnose.py WIDTH SEED [--count 60] [--why] [--blockers 4]
[--set body="three_discs" steering.twists_deg="(60.0,)" ...]`` (``--set``: CrowdParams
fields, ``steering.``-prefixed SteeringParams fields, Python literals).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

import crowdwalk.crowd.simulation as simulation
from crowdwalk.crowd import CrowdParams
from crowdwalk.crowd.params import parse_overrides
from crowdwalk.verify import _bottleneck, _run


def _crossing(x: np.ndarray, at: float) -> int | None:
    c = np.flatnonzero((x[:-1] < at) & (x[1:] >= at))
    return int(c[0]) + 1 if c.size else None


def _mean_or_none(values: np.ndarray) -> float | None:
    """The mean of the finite ``values``, 2 decimals; None when there are none."""
    v = values[np.isfinite(values)]
    return round(float(v.mean()), 2) if v.size else None


def diagnose(traj) -> dict:
    """The measures of one finished bottleneck run's trajectories."""
    fps, out, mid, enter, speed = traj.fps, [], [], [], np.full(traj.x.size, np.nan)
    enter_y = []
    for i in np.unique(traj.id):
        k = np.flatnonzero(traj.id == i)
        x, y = traj.x[k], traj.y[k] - 5.0
        speed[k[1:]] = np.hypot(np.diff(x), np.diff(traj.y[k])) * fps
        if (j := _crossing(x, 10.0)) is not None:
            out.append(traj.frame[k[j]] / fps)
        if (j := _crossing(x, 8.0)) is not None:
            enter.append(traj.frame[k[j]] / fps)
            enter_y.append((traj.frame[k[j]] / fps, y[j]))
        if (j := _crossing(x, 9.0)) is not None and j > 0:
            walk = np.arctan2(y[j] - y[j - 1], x[j] - x[j - 1])
            face = np.arctan2(traj.ori_y[k[j]], traj.ori_x[k[j]])
            twist = abs((face - walk + np.pi) % (2 * np.pi) - np.pi)
            mid.append((traj.frame[k[j]] / fps, y[j], np.degrees(twist)))
    out, enter = np.sort(out), np.sort(enter)
    n = out.size
    enter_y.sort()
    ey = np.array(enter_y[5:len(enter_y) - 5]).reshape(-1, 2)
    e_dt, e_dy = np.diff(ey[:, 0]), np.abs(np.diff(ey[:, 1]))
    gaps = np.diff(out[5:n - 5])
    mid.sort()
    tm, ys, tw = (np.array(c) for c in zip(*mid, strict=True))
    dy, dt = np.abs(np.diff(ys)), np.diff(tm)
    t0, t1 = out[5], out[n - 6]
    t = traj.frame / fps
    steady = (t >= t0) & (t <= t1)
    frames = np.arange(int(t0 * fps), int(t1 * fps) + 1)
    inside = steady & (traj.x > 8.0) & (traj.x < 10.0)
    front = steady & (traj.x > 7.0) & (traj.x <= 8.0) & (np.abs(traj.y - 5.0) < 1.0)
    long = gaps[gaps > 1.5]
    return {
        "flow": round(float((n - 11) / (out[n - 6] - out[5])), 3),
        "exit_gap_median": round(float(np.median(gaps)), 2),
        "exit_gap_mean": round(float(gaps.mean()), 2),
        "entry_gap_median": round(float(np.median(np.diff(enter[5:n - 5]))), 2),
        "gaps_over_1_5s": int(long.size), "their_sum_s": round(float(long.sum()), 1),
        "steady_s": round(float(gaps.sum()), 1),
        "mid_abs_y_median": round(float(np.median(np.abs(ys))), 3),
        "dy_median": round(float(np.median(dy)), 3),
        "staggered_share": round(float(np.mean(dy > 0.2)), 2),
        "gap_staggered_s": round(float(np.median(dt[dy > 0.2])), 2) if (dy > 0.2).any()
        else None,
        "gap_one_file_s": round(float(np.median(dt[dy < 0.1]))
                                if (dy < 0.1).any() else float("nan"), 2),
        # where they enter (x = 8): consecutive walkers' lateral distance, and their time
        # gaps [count, median s] by it (one file, partly offset, in two layers)
        "entry_dy_median": round(float(np.median(e_dy)), 3) if e_dy.size else None,
        "entry_gap_by_dy": {name: [int(m.sum()), round(float(np.median(e_dt[m])), 2)
                                   if m.any() else None]
                            for name, m in (("<0.1", e_dy < 0.1),
                                            ("0.1-0.3", (e_dy >= 0.1) & (e_dy < 0.3)),
                                            (">=0.3", e_dy >= 0.3))},
        "twist_median_deg": round(float(np.median(tw)), 1),
        "in_opening_mean": round(float(np.isin(traj.frame[inside], frames).sum()
                                       / frames.size), 2),
        "in_front_mean": round(float(front.sum() / frames.size), 2),
        "in_front_standing_share": round(float(np.mean(speed[front] < 0.1)), 2),
        "in_opening_standing_share": round(float(np.mean(speed[inside] < 0.1)), 2),
        # behind the opening: the mean speed [m/s] of walkers 0-1, 1-2 and 2-4 m past its
        # end (a slow band there holds the door back)
        "speed_after": [_mean_or_none(speed[steady & (traj.x > 10.0 + a)
                                            & (traj.x <= 10.0 + b)])
                        for a, b in ((0.0, 1.0), (1.0, 2.0), (2.0, 4.0))],
    }


def _count_soft_stands(counts: dict):
    """Wrap ``choose_steps`` to count stands in front of / inside the opening and the
    stands a call without the soft neighbour and wall terms would have stepped."""
    base = simulation.choose_steps

    def wrapped(position, stance, **kw):
        res = base(position, stance, **kw)
        x, y = position[:, 0], position[:, 1] - 5.0
        zones = {"front": (x > 7.2) & (x <= 8.0) & (np.abs(y) < 0.8),
                 "opening": (x > 8.0) & (x < 10.0)}
        if any(z.any() for z in zones.values()):
            bare = base(position, stance, **{**kw, "params": replace(
                kw["params"], personal_weight=0.0, wall_weight=0.0)})
            nb = kw["neighbours"]
            alone = base(position, stance, **{**kw, "neighbours": replace(
                nb, valid=np.zeros_like(nb.valid))})
            for name, z in zones.items():
                c = counts.setdefault(name, {"decisions": 0, "stand": 0, "stand_by_choice": 0,
                                             "stand_free_of_walls": 0})
                c["decisions"] += int(z.sum())
                c["stand"] += int((z & ~res.move).sum())
                c["stand_by_choice"] += int((z & ~res.move & bare.move).sum())
                c["stand_free_of_walls"] += int((z & ~res.move & alone.move).sum())
        return res

    simulation.choose_steps = wrapped


def _print_blockers(stuck_after: float, every: int = 25) -> None:
    """Wrap ``choose_steps`` to print, for walkers standing in front of the opening's
    walls (7.7 < x ≤ 8, 0.15 < |y − 5| < 0.6) for more than ``stuck_after`` seconds,
    every ``every``-th such decision, the single neighbours whose removal (a
    counterfactual call without it) lets the walker step, with that step."""
    base, seen = simulation.choose_steps, [0]

    def wrapped(position, stance, **kw):
        res = base(position, stance, **kw)
        x, y = position[:, 0], position[:, 1] - 5.0
        z = np.flatnonzero((x > 7.7) & (x <= 8.0) & (np.abs(y) > 0.15) & (np.abs(y) < 0.6)
                           & ~res.move & (np.asarray(kw["stuck"]) > stuck_after))
        if z.size:
            seen[0] += 1
            if seen[0] % every == 0:
                r, nb, found = z[0], kw["neighbours"], []
                for k in np.flatnonzero(nb.valid[r]):
                    v = nb.valid.copy()
                    v[:, k] = False
                    alt = base(position, stance, **{**kw, "neighbours": replace(nb, valid=v)})
                    if alt.move[r]:
                        d = alt.direction[r]
                        found.append({"blocker": np.round(nb.now[r, k] - (0, 5), 2).tolist(),
                                      "step_deg": round(float(np.degrees(np.arctan2(d[1], d[0])))),
                                      "step_m": round(float(alt.free_length[r]), 2)})
                print(json.dumps({"walker": np.round(position[r] - (0, 5), 3).tolist(),
                                  "stuck_s": round(float(kw["stuck"][r]), 2),
                                  "single_blockers": found}), flush=True)
        return res

    simulation.choose_steps = wrapped


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("width", type=float)
    ap.add_argument("seed", type=int)
    ap.add_argument("--count", type=int, default=60)
    ap.add_argument("--why", action="store_true")
    ap.add_argument("--blockers", type=float, default=None, metavar="SECONDS")
    ap.add_argument("--set", nargs="*", default=[], metavar="FIELD=VALUE")
    args = ap.parse_args()
    fields = parse_overrides(args.set)
    params = CrowdParams().with_overrides(fields)
    counts: dict = {}
    if args.why:
        _count_soft_stands(counts)
    if args.blockers is not None:
        _print_blockers(args.blockers)
    with tempfile.TemporaryDirectory() as tmp:
        run = _run(_bottleneck(args.width, args.seed, args.count), Path(tmp) / "run", params)
        print(json.dumps({"width": args.width, "seed": args.seed, **fields,
                          **diagnose(run.traj),
                          "max_overlap_m": run.summary.get("max_overlap_m"),
                          **({"stands": counts} if counts else {})}))


if __name__ == "__main__":
    main()
