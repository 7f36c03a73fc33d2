"""Studies: many independent trials of a scenario (seeds × planners × scenario fields) on
Dask distributed, one run folder per trial, a manifest table and a report with intervals
across seeds (docs/architecture.md, "Sweeps").

A sweep file::

    scenario: ../scenarios/stairs_up_down.yaml   # relative to the sweep file
    seeds: [1, 2, 3, 4, 5]                         # or "1..5"
    planners: [best_first, fixed]                  # default: the scenario's own
    axes:                                          # dotted paths into the scenario
      groups.0.count: [5, 10]
    duration: 30                                   # optional overrides of the run
    poses: false

Every trial (one combination) is run by a Dask worker into ``OUT/trials/<name>/``: into a
temporary folder first, renamed when the run is complete, so a folder under that name is
a finished trial (a worker killed mid-trial leaves only a temporary folder, and the trial
runs again). Running a sweep again skips the finished trials (resumable). ``OUT/
manifest.csv`` has one row of summary metrics per trial; ``OUT/report.md`` the means over
seeds with 95 % t intervals per combination of planner and axes, and the headline: the
energy per metre of planned (``best_first``) against unplanned (``fixed``) walkers,
paired by seed.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import os
import shutil
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crowdwalk.errors import invalid

__all__ = ["SweepSpec", "Trial", "load_sweep", "trials_of", "run_trial", "run_sweep",
           "parse_seeds", "METRICS"]

#: Manifest columns taken from each trial's summary.json (units in the names).
METRICS = ("agents_total", "agents_arrived", "simulated_time_s", "energy_per_metre_J_per_kg_m",
           "energy_J_per_kg", "travel_time_s", "waiting_s", "steps", "planner_runs",
           "max_overlap_m", "wall_s")


def parse_seeds(text) -> list[int]:
    """Seeds from ``"A..B"`` (inclusive), ``"A,B,C"``, an int or a list of ints."""
    if isinstance(text, int):
        return [text]
    if isinstance(text, list | tuple):
        seeds = [int(s) for s in text]
    else:
        s = str(text).strip()
        try:
            if ".." in s:
                a, b = (int(x) for x in s.split(".."))
                seeds = list(range(a, b + 1))
            else:
                seeds = [int(x) for x in s.split(",") if x.strip()]
        except ValueError:
            raise invalid("Sweep", "seeds", "'A..B', 'A,B,C' or a list of integers", s) from None
    if not seeds or len(set(seeds)) != len(seeds) or min(seeds) < 0:
        raise invalid("Sweep", "seeds", "distinct integers >= 0, at least one", text)
    return seeds


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: scenario file, seeds, planners (None: the scenario's own),
    axes (dotted path -> values), run overrides (duration [s], poses, max_agents)."""

    scenario: Path
    seeds: tuple[int, ...]
    planners: tuple[str | None, ...] = (None,)
    axes: dict = field(default_factory=dict)
    duration: float | None = None
    poses: bool = False
    max_agents: int | None = None


@dataclass(frozen=True)
class Trial:
    """One run of a sweep: its folder name, seed, planner and axis values."""

    name: str
    seed: int
    planner: str | None
    values: tuple[tuple[str, object], ...]


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and validate a sweep YAML file (errors name the file and the field)."""
    import yaml

    from planners import PLANNERS

    path = Path(path)
    data = yaml.safe_load(path.read_text())
    where = f"{path}"
    if not isinstance(data, dict):
        raise invalid(where, "sweep", "a mapping", type(data).__name__)
    known = {"scenario", "seeds", "planners", "axes", "duration", "poses", "max_agents"}
    extra = sorted(set(data) - known)
    if extra:
        raise invalid(where, extra[0], f"one of {sorted(known)}", extra[0])
    if "scenario" not in data:
        raise invalid(where, "scenario", "a scenario file path", None)
    scenario = (path.parent / str(data["scenario"])).resolve()
    if not scenario.exists():
        raise FileNotFoundError(str(scenario))
    seeds = parse_seeds(data.get("seeds", [0]))
    planners = data.get("planners") or [None]
    for p in planners:
        if p is not None and p not in PLANNERS:
            raise invalid(where, "planners", f"names in {sorted(PLANNERS)}", p)
    axes = data.get("axes") or {}
    if not isinstance(axes, dict):
        raise invalid(where, "axes", "a mapping of dotted paths to value lists", axes)
    for k, v in axes.items():
        if not isinstance(v, list) or not v:
            raise invalid(where, f"axes.{k}", "a non-empty list of values", v)
    duration = data.get("duration")
    if duration is not None and not (isinstance(duration, int | float) and duration > 0):
        raise invalid(where, "duration", "> 0 [s]", duration)
    max_agents = data.get("max_agents")
    if max_agents is not None and not (isinstance(max_agents, int) and max_agents >= 1):
        raise invalid(where, "max_agents", "an integer >= 1", max_agents)
    spec = SweepSpec(scenario=scenario, seeds=tuple(seeds), planners=tuple(planners),
                     axes=dict(axes), duration=duration, poses=bool(data.get("poses", False)),
                     max_agents=max_agents)
    for trial in trials_of(spec):  # every combination must make a valid scenario
        scenario_of(spec, trial)
    return spec


def _slug(value) -> str:
    text = json.dumps(value) if not isinstance(value, str) else value
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in text)[:40]


def trials_of(spec: SweepSpec) -> list[Trial]:
    """Every combination of axes, planners and seeds, in a stable order."""
    keys = sorted(spec.axes)
    out = []
    for combo in itertools.product(*(spec.axes[k] for k in keys)):
        values = tuple(zip(keys, combo, strict=True))
        for planner in spec.planners:
            for seed in spec.seeds:
                parts = [f"{k}={_slug(v)}" for k, v in values]
                parts += [f"planner={planner or 'scenario'}", f"seed={seed}"]
                out.append(Trial("__".join(parts), seed, planner, values))
    return out


def _set_dotted(data: dict, dotted: str, value) -> None:
    node = data
    keys = dotted.split(".")
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node.setdefault(k, {})
    last = keys[-1]
    if isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value


def scenario_of(spec: SweepSpec, trial: Trial):
    """The validated :class:`~crowdwalk.scenario.Scenario` of one trial."""
    import yaml

    from crowdwalk.scenario import parse_scenario

    data = yaml.safe_load(spec.scenario.read_text())
    for dotted, value in trial.values:
        try:
            _set_dotted(data, dotted, value)
        except (KeyError, IndexError, ValueError, TypeError):
            raise invalid(f"{spec.scenario}", f"axes.{dotted}", "a path into the scenario",
                          dotted) from None
    data.setdefault("simulation", {})["seed"] = trial.seed
    return parse_scenario(yaml.safe_dump(data, sort_keys=False), source=str(spec.scenario),
                          base_dir=spec.scenario.parent)


def run_trial(spec: SweepSpec, trial: Trial, out: str | Path) -> dict:
    """Run one trial into ``out/trials/<name>/`` (atomically: a temporary folder renamed
    when complete) unless it is there already; returns its manifest row."""
    from crowdwalk.crowd.run import RunOverrides, run_scenario

    final = Path(out) / "trials" / trial.name
    if not (final / "summary.json").exists():
        tmp = final.parent / f".tmp-{trial.name}-{uuid.uuid4().hex[:8]}"
        overrides = RunOverrides(planner=trial.planner, duration=spec.duration,
                                 poses=spec.poses, max_agents=spec.max_agents,
                                 workers=0)  # one trial per core already
        run_scenario(scenario_of(spec, trial), tmp, overrides=overrides)
        try:
            os.replace(tmp, final)
        except OSError:  # finished by another worker meanwhile (a retried task)
            shutil.rmtree(tmp, ignore_errors=True)
    return manifest_row(trial, _summary(final))


def _summary(folder: Path) -> dict:
    """A finished trial's ``summary.json`` (read through :func:`crowdwalk.record.open_run`)."""
    from crowdwalk.record import open_run

    return open_run(folder).summary


def manifest_row(trial: Trial, summary: dict) -> dict:
    """A trial's manifest row: name, seed, planner, axis values and :data:`METRICS`
    (means over the trial's agents where per agent)."""
    agents = summary["agents"]

    def mean(key):
        vals = [a[key] for a in agents if a.get(key) is not None]
        return float(np.mean(vals)) if vals else float("nan")

    dist = sum(a["distance_m"] for a in agents)
    row = {"trial": trial.name, "seed": trial.seed,
           "planner": trial.planner or ",".join(sorted({a["planner"] for a in agents}))}
    row.update({k: v for k, v in trial.values})
    row.update(
        agents_total=summary["agents_total"], agents_arrived=summary["agents_arrived"],
        simulated_time_s=summary["simulated_time_s"],
        energy_per_metre_J_per_kg_m=(sum(a["energy_J_per_kg"] for a in agents) / dist
                                     if dist > 0 else float("nan")),
        energy_J_per_kg=mean("energy_J_per_kg"), travel_time_s=mean("travel_time_s"),
        waiting_s=mean("waiting_s"), steps=mean("steps"),
        planner_runs=summary["planning"]["planner_runs"],
        max_overlap_m=summary["max_overlap_m"], wall_s=summary["timing"]["wall_s"])
    return row


def _warm() -> float:
    """Compile (or load) the numba kernels in a worker (:mod:`crowdwalk.warm`)."""
    from crowdwalk.warm import warm_kernels

    return warm_kernels()


def run_sweep(spec: SweepSpec, out: str | Path, *, scheduler: str | None = None,
              workers: int | None = None, progress=None) -> Path:
    """Run every trial of ``spec`` not yet finished in ``out`` on Dask distributed (a
    ``LocalCluster`` of ``workers`` processes, one thread each — default one per core —
    or the running scheduler at ``scheduler``), then write ``out/manifest.csv`` and
    ``out/report.md``. ``progress(done, total, trial)`` after each trial. Returns the
    report's path."""
    from distributed import Client, LocalCluster, as_completed

    out = Path(out)
    (out / "trials").mkdir(parents=True, exist_ok=True)
    trials = trials_of(spec)
    todo = [t for t in trials if not (out / "trials" / t.name / "summary.json").exists()]
    cluster = None
    if todo:
        if scheduler is None:
            n = workers or os.cpu_count() or 1
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        else:
            client = Client(scheduler)
        try:
            client.run(_warm)  # every worker's kernels compiled before work starts
            futures = [client.submit(run_trial, spec, t, str(out), key=f"trial-{t.name}",
                                     pure=False, retries=2) for t in todo]
            for done, fut in enumerate(as_completed(futures), 1):
                row = fut.result()
                if progress is not None:
                    progress(done, len(todo), row["trial"])
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    rows = [manifest_row(t, _summary(out / "trials" / t.name)) for t in trials]
    write_manifest(rows, out / "manifest.csv")
    report = out / "report.md"
    report.write_text(report_text(spec, rows))
    return report


def write_manifest(rows: list[dict], path: Path) -> None:
    """The manifest CSV (one row per trial)."""
    columns = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)


def mean_interval(values) -> tuple[float, float, float, int]:
    """Mean, 95 % t interval (low, high) across seeds, and the count of finite values."""
    from scipy import stats

    x = np.asarray([v for v in values if v is not None and np.isfinite(v)], float)
    if x.size == 0:
        return (math.nan, math.nan, math.nan, 0)
    m = float(x.mean())
    if x.size < 2:
        return (m, math.nan, math.nan, 1)
    half = float(stats.t.ppf(0.975, x.size - 1) * x.std(ddof=1) / math.sqrt(x.size))
    return (m, m - half, m + half, int(x.size))


def _fmt(m, lo, hi, n) -> str:
    if not np.isfinite(m):
        return "–"
    return f"{m:.3g} [{lo:.3g}, {hi:.3g}] (n={n})" if np.isfinite(lo) else f"{m:.3g} (n={n})"


def report_text(spec: SweepSpec, rows: list[dict]) -> str:
    """The sweep report (markdown): headline planned vs unplanned energy per metre paired
    by seed, then the mean and 95 % interval across seeds of every metric per combination
    of planner and axes."""
    keys = sorted(spec.axes)
    lines = [f"# Sweep of {spec.scenario.name}", "",
             f"{len(rows)} trials: seeds {list(spec.seeds)}, planners "
             f"{[p or 'scenario' for p in spec.planners]}, axes {dict(spec.axes)}.",
             "Intervals: 95 % Student t over seeds (each seed one independent run).", ""]
    combos = sorted({tuple(r.get(k) for k in keys) for r in rows}, key=repr)
    planners = sorted({r["planner"] for r in rows})
    if {"best_first", "fixed"} <= set(planners):
        lines += ["## Headline: planned (best_first) against unplanned (fixed) walkers", "",
                  "| " + " | ".join([*keys, "energy/m planned", "energy/m unplanned",
                                     "difference (planned − unplanned) [J/(kg m)]",
                                     "relative"]) + " |",
                  "|" + "---|" * (len(keys) + 4)]
        for combo in combos:
            sel = [r for r in rows if tuple(r.get(k) for k in keys) == combo]
            by = {p: {r["seed"]: r["energy_per_metre_J_per_kg_m"] for r in sel
                      if r["planner"] == p} for p in ("best_first", "fixed")}
            seeds = sorted(set(by["best_first"]) & set(by["fixed"]))
            diff = [by["best_first"][s] - by["fixed"][s] for s in seeds]
            rel = [d / by["fixed"][s] for d, s in zip(diff, seeds, strict=True)]
            cells = [str(c) for c in combo]
            cells += [_fmt(*mean_interval([by["best_first"][s] for s in seeds])),
                      _fmt(*mean_interval([by["fixed"][s] for s in seeds])),
                      _fmt(*mean_interval(diff)),
                      _fmt(*mean_interval([100 * r for r in rel])) + " %"]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    metrics = [m for m in METRICS if m != "wall_s"]
    lines += ["## Every metric, mean [95 % interval] over seeds", "",
              "| " + " | ".join([*keys, "planner", *metrics]) + " |",
              "|" + "---|" * (len(keys) + 1 + len(metrics))]
    for combo in combos:
        for p in planners:
            sel = [r for r in rows if tuple(r.get(k) for k in keys) == combo
                   and r["planner"] == p]
            if not sel:
                continue
            cells = [str(c) for c in combo] + [p]
            cells += [_fmt(*mean_interval([r[m] for r in sel])) for m in metrics]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
