"""Planned against unplanned walkers: the same scenario, seed and agents with each planner.

:func:`compare_planners` runs the scenario once per planner (every group switched to that
planner; the population — bodies, speeds, spawn places and times — is drawn from the same
seed, so the agents are identical), each into ``OUT/<planner>/``, and writes
``OUT/report.md`` with PNG plots: energy per metre, travel time and steps per agent,
footholds on obstacles, and energy per metre by terrain type (``Terrain.kind`` under each
foothold).

Reading the numbers. Energy per metre by terrain type is the sum of the step energies
over the sum of the step lengths of the footholds on that terrain, so a run's mix of
steps up, down and along matters (a stair row of a run in which more walkers reached the
stairs up within the simulated time is dearer per metre, whoever planned), and a step
onto a stair counts its whole length as stairs. The report therefore also splits by the
step's direction (up / level / down), gives 95 % confidence intervals from resampling
the agents (bootstrap, seed 0), and compares the same agents on the same trips: the
energy [J/kg] of each agent that arrived in both runs (same spawn, same destination),
paired. Differences whose interval contains zero are reported as not significant.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from crowdwalk.errors import invalid
from crowdwalk.steps import FootstepTable

__all__ = ["check_planners", "compare_planners", "terrain_table", "paired_trips", "BOOTSTRAP"]

ProgressCallback = Callable[[str, float, float, int], None]

#: Bootstrap resamples for the confidence intervals (agents resampled with replacement).
BOOTSTRAP = 2000
#: A step with a larger height change [m] is a step up or down (else level).
LEVEL_RISE = 0.02
#: Fewest agents behind a row for a confidence interval (else none is given).
MIN_AGENTS_CI = 5


def _kind_names() -> dict[int, str]:
    from crowdwalk.terrain import TerrainKind

    return {int(k): k.name.lower() for k in TerrainKind}


def _ratio_draws(energy, length, agent, rng) -> np.ndarray:
    """Bootstrap draws (BOOTSTRAP,) of sum(energy) / sum(length), resampling agents."""
    ids, inverse = np.unique(agent, return_inverse=True)
    e = np.bincount(inverse, weights=energy, minlength=ids.size)
    n = np.bincount(inverse, weights=length, minlength=ids.size)
    pick = rng.integers(0, ids.size, size=(BOOTSTRAP, ids.size))
    with np.errstate(divide="ignore", invalid="ignore"):
        return e[pick].sum(axis=1) / n[pick].sum(axis=1)


def terrain_table(steps: FootstepTable, *, by_direction: bool = False,
                  draws: bool = False) -> dict[str, dict]:
    """Footstep statistics per terrain type (optionally per step direction).

    Parameters
    ----------
    steps : crowdwalk.steps.FootstepTable
        ``footsteps.csv`` as read by ``record.Run.footsteps``.
    by_direction : bool
        Split each terrain type by the step's height change: ``"<type> up"`` and
        ``"<type> down"`` (more than ``LEVEL_RISE``), ``"<type>"`` level.
    draws : bool
        Also return the bootstrap draws of the energy per metre (``"draws"``).

    Returns
    -------
    dict
        terrain type name -> ``footholds``, ``agents``, ``energy_per_metre`` [J/(kg m)]
        (sum of step energies over the sum of step lengths), ``ci`` (its 95 % interval,
        agents resampled; NaN with fewer than ``MIN_AGENTS_CI`` agents),
        ``mean_step_length`` [m], ``on_obstacle`` (footholds on obstacles).
    """
    names = _kind_names()
    out: dict[str, dict] = {}
    kind = np.asarray(steps.kind).astype(int)
    direction = np.zeros(kind.size, dtype=int)  # 0 level, 1 up, 2 down
    if by_direction:
        rise = np.asarray(steps.step_height, dtype=float)
        direction = np.where(rise > LEVEL_RISE, 1, np.where(rise < -LEVEL_RISE, 2, 0))
    suffix = ("", " up", " down")
    groups = sorted(set(zip(kind.tolist(), direction.tolist(), strict=True)))
    rng = np.random.default_rng(0)
    agent = np.asarray(steps.agent)
    for code, way in groups:
        m = (kind == code) & (direction == way)
        label = names.get(code, str(code)) + suffix[way]
        length = float(steps.step_length[m].sum())
        boot = _ratio_draws(steps.energy[m], steps.step_length[m], agent[m], rng)
        if np.unique(agent[m]).size < MIN_AGENTS_CI:
            boot = np.full(BOOTSTRAP, np.nan)
        row = {
            "footholds": int(m.sum()),
            "agents": int(np.unique(agent[m]).size),
            "energy_per_metre": float(steps.energy[m].sum() / length) if length > 0
            else float("nan"),
            "ci": (tuple(float(x) for x in np.percentile(boot, [2.5, 97.5]))
                   if np.isfinite(boot).all() else (float("nan"), float("nan"))),
            "mean_step_length": float(steps.step_length[m].mean()),
            "on_obstacle": int(steps.on_obstacle[m].sum()),
        }
        if draws:
            row["draws"] = boot
        out[label] = row
    return out


def paired_trips(summaries: dict[str, dict], baseline: str) -> dict[str, dict]:
    """The same agents on the same trips: energy of the agents that arrived in both runs.

    Parameters
    ----------
    summaries : mapping planner -> summary dict (``summary.json``)
    baseline : str
        The planner the others are compared with.

    Returns
    -------
    dict
        planner -> ``agents`` (arrived in both runs), ``energy`` and ``baseline_energy``
        (mean energy per trip [J/kg]), ``difference`` [J/kg] with its 95 % ``ci``
        (paired bootstrap over agents), ``relative`` (difference over the baseline's
        energy [-]) with ``relative_ci``, ``distance_difference`` (mean difference of
        the walked distance [m]), ``significant`` (the interval excludes 0). With fewer
        than ``MIN_AGENTS_CI`` agents there is no interval (NaN) and ``significant`` is
        False.
    """
    base = {a["id"]: a for a in summaries[baseline]["agents"] if a.get("arrived")}
    out = {}
    rng = np.random.default_rng(0)
    for name, s in summaries.items():
        if name == baseline:
            continue
        ids = [a["id"] for a in s["agents"] if a.get("arrived") and a["id"] in base]
        mine = {a["id"]: a for a in s["agents"]}
        e = np.array([mine[i]["energy_J_per_kg"] for i in ids], dtype=float)
        b = np.array([base[i]["energy_J_per_kg"] for i in ids], dtype=float)
        d = np.array([mine[i]["distance_m"] - base[i]["distance_m"] for i in ids], dtype=float)
        row = {"agents": len(ids), "energy": float("nan"), "baseline_energy": float("nan"),
               "difference": float("nan"), "ci": (float("nan"), float("nan")),
               "relative": float("nan"), "relative_ci": (float("nan"), float("nan")),
               "distance_difference": float("nan"), "significant": False}
        if ids:
            row.update(energy=float(e.mean()), baseline_energy=float(b.mean()),
                       difference=float((e - b).mean()),
                       relative=float((e - b).mean() / b.mean()),
                       distance_difference=float(d.mean()))
        if len(ids) >= MIN_AGENTS_CI:
            pick = rng.integers(0, len(ids), size=(BOOTSTRAP, len(ids)))
            diff = (e - b)[pick].mean(axis=1)
            rel = diff / b[pick].mean(axis=1)
            ci = tuple(float(x) for x in np.percentile(diff, [2.5, 97.5]))
            row.update(ci=ci,
                       relative_ci=tuple(float(x) for x in np.percentile(rel, [2.5, 97.5])),
                       significant=bool(ci[0] > 0 or ci[1] < 0))
        out[name] = row
    return out


def _fmt(x, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "–"
    return f"{x:.{digits}g}" if isinstance(x, float) else str(x)


def check_planners(planners: list[str]) -> None:
    """Raise ``InputError`` unless ``planners`` is a non-empty list of distinct names from
    ``planners.PLANNERS``."""
    from planners import PLANNERS

    if not planners:
        raise invalid("compare", "planners", "a non-empty comma-separated list", planners)
    for name in planners:
        if name not in PLANNERS:
            raise invalid("compare", "planners", f"names from {sorted(PLANNERS)}", name)
    if len(set(planners)) != len(planners):
        raise invalid("compare", "planners", "without repeats", planners)


def compare_planners(
    scenario,
    planners: list[str],
    out: str | Path,
    *,
    duration: float | None = None,
    max_agents: int | None = None,
    poses: bool | None = None,
    progress: ProgressCallback | None = None,
) -> Path:
    """Run ``scenario`` with each planner and write ``out/report.md``.

    Parameters
    ----------
    scenario : path
        Scenario YAML file.
    planners : list of str
        Planner names (``planners.PLANNERS``), at least one, no repeats.
    out : path
        Folder for the runs (``out/<planner>/``), the plots and ``report.md``.
    duration : float, optional
        Simulated time limit [s] (default: the scenario's).
    max_agents : int, optional
        Keep only the first agents (tests).
    poses : bool, optional
        Write poses for each run (default: as the scenario's ``outputs.poses`` says), so
        that the runs can be viewed side by side as walking figures.
    progress : callable, optional
        ``progress(planner, simulated_time [s], duration [s], agents_remaining)``.

    Returns
    -------
    pathlib.Path
        The report file.
    """
    from crowdwalk.crowd.run import RunOverrides, run_scenario
    from crowdwalk.plots import plot_by_terrain, plot_planner_comparison
    from crowdwalk.record import open_run

    check_planners(planners)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    summaries, tables, directions = {}, {}, {}
    for name in planners:
        def update(t, total, remaining, name=name):
            if progress is not None:
                progress(name, t, total, remaining)

        summaries[name] = run_scenario(
            scenario, out / name, progress=update,
            overrides=RunOverrides(planner=name, duration=duration, poses=poses,
                                   max_agents=max_agents),
        )
        steps = open_run(out / name).footsteps()
        tables[name] = terrain_table(steps)
        directions[name] = terrain_table(steps, by_direction=True, draws=True)
    baseline = "fixed" if "fixed" in planners else planners[-1]
    trips = paired_trips(summaries, baseline) if len(planners) > 1 else {}

    def per_agent(key: str) -> dict[str, np.ndarray]:
        return {n: np.array([np.nan if a[key] is None else a[key]
                             for a in s["agents"] if a["steps"] > 0], dtype=float)
                for n, s in summaries.items()}

    metrics = {"energy per metre": per_agent("energy_per_metre_J_per_kg_m"),
               "travel time": per_agent("travel_time_s"),
               "steps": per_agent("steps")}
    units = {"energy per metre": "J/(kg m)", "travel time": "s", "steps": "-"}
    pngs = {}
    shown = {k: v for k, v in metrics.items()
             if all(np.isfinite(x).any() for x in v.values())}
    if shown:
        pngs["agents"] = plot_planner_comparison(shown, out / "per_agent.png", units=units,
                                                 title="Per agent, by planner")
    energy = {n: {k: v["energy_per_metre"] for k, v in t.items()}
              for n, t in directions.items()}
    spread = {n: {k: v["ci"] for k, v in t.items()} for n, t in directions.items()}
    pngs["energy"] = plot_by_terrain(energy, out / "energy_by_terrain.png",
                                     ylabel="energy per metre [J/(kg m)]",
                                     title="Energy per metre walked, by terrain type and "
                                           "step direction (95 % CI)", errors=spread)
    obstacle = {n: {k: float(v["on_obstacle"]) for k, v in t.items()} for n, t in tables.items()}
    pngs["obstacle"] = plot_by_terrain(obstacle, out / "footholds_on_obstacles.png",
                                       ylabel="footholds on obstacles [-]",
                                       title="Footholds on obstacles, by terrain type")
    steps_by = {n: {k: float(v["footholds"]) for k, v in t.items()} for n, t in tables.items()}
    pngs["steps"] = plot_by_terrain(steps_by, out / "footholds_by_terrain.png",
                                    ylabel="footholds [-]", title="Footholds by terrain type")

    report = out / "report.md"
    report.write_text(_report_text(scenario, planners, summaries, tables, pngs, out,
                                   directions=directions, trips=trips, baseline=baseline))
    return report


def _ci(ci, digits: int = 3, scale: float = 1.0) -> str:
    lo, hi = ci
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return "–"
    return f"{_fmt(scale * lo, digits)}…{_fmt(scale * hi, digits)}"


def _trip_lines(trips: dict, baseline: str) -> list[str]:
    """The paired same-trip comparison section."""
    lines = [
        "## Same agents, same trips",
        "",
        f"The like-for-like comparison: the agents that arrived in both runs (same body, "
        f"speed, spawn and destination), energy per trip [J/kg] against `{baseline}`, "
        "paired; 95 % confidence intervals from resampling the agents.",
        "",
        f"| planner | agents | energy per trip [J/kg] | {baseline} [J/kg] | difference "
        "[J/kg] (95 % CI) | difference [%] (95 % CI) | distance difference [m] | verdict |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, r in trips.items():
        if r["agents"] == 0:
            verdict = "no agent arrived in both runs"
        elif r["agents"] < MIN_AGENTS_CI:
            verdict = (f"{'less' if r['difference'] < 0 else 'more'} energy than "
                       f"`{baseline}` ({r['agents']} agents: too few for an interval)"
                       if r["difference"] != 0 else "the same energy")
        elif not r["significant"]:
            verdict = "no significant difference"
        else:
            verdict = (f"{'less' if r['difference'] < 0 else 'more'} energy than "
                       f"`{baseline}`")
        lines.append(
            f"| {name} | {r['agents']} | {_fmt(r['energy'])} | {_fmt(r['baseline_energy'])} "
            f"| {_fmt(r['difference'], 2)} ({_ci(r['ci'], 2)}) | "
            f"{_fmt(100 * r['relative'], 2)} ({_ci(r['relative_ci'], 2, 100.0)}) | "
            f"{_fmt(r['distance_difference'], 2)} | {verdict} |")
    return lines + [""]


def _direction_lines(planners, directions: dict, baseline: str) -> list[str]:
    """Energy per metre by terrain type and step direction, with intervals."""
    lines = [
        "## By terrain type and step direction",
        "",
        "Steps up or down (a height change of more than "
        f"{100 * LEVEL_RISE:.0f} cm) apart from level ones, so that rows compare like with "
        f"like; the last column is the difference from `{baseline}` on the same row "
        "(intervals from resampling each run's agents; none for rows of fewer than "
        f"{MIN_AGENTS_CI} agents). A difference whose interval contains 0 is noise "
        "(different walkers reaching a place within the simulated time, different paths "
        "in the crowd), not an effect of planning. Per metre, a step up or down is "
        "cheaper the longer it is, and the level step before it then shorter: a planner "
        "that approaches a curb or stair differently moves energy per metre between "
        "rows without changing what the stretch costs. Whether planning saves energy is "
        "answered by the trips above.",
        "",
        "| planner | terrain | footholds | agents | mean step length [m] | energy per metre "
        f"[J/(kg m)] (95 % CI) | vs {baseline} [%] (95 % CI) |",
        "|---|---|---|---|---|---|---|",
    ]
    base = directions.get(baseline, {})
    for name in planners:
        for kind, v in directions[name].items():
            versus = "–"
            if name != baseline and kind in base:
                with np.errstate(divide="ignore", invalid="ignore"):
                    rel = v["draws"] / base[kind]["draws"] - 1
                    point = v["energy_per_metre"] / base[kind]["energy_per_metre"] - 1
                lo, hi = (np.percentile(rel, [2.5, 97.5]) if np.isfinite(rel).all()
                          else (np.nan, np.nan))
                mark = "" if not (lo > 0 or hi < 0) else " *"
                versus = f"{_fmt(100 * point, 2)} ({_ci((lo, hi), 2, 100.0)}){mark}"
            lines.append(f"| {name} | {kind} | {v['footholds']} | {v['agents']} | "
                         f"{_fmt(v['mean_step_length'])} | {_fmt(v['energy_per_metre'])} "
                         f"({_ci(v['ci'])}) | {versus} |")
    return lines + ["", "\\* the interval excludes 0.", ""]


def _style_lines(planners, summaries) -> list[str]:
    """The "By style" table (KLAW styles, :func:`crowdwalk.style.summary_by_style`)."""
    from crowdwalk.style import summary_by_style

    rows = [(name, style, v) for name in planners
            for style, v in summary_by_style(summaries[name]["agents"]).items()]
    if len({style for _, style, _ in rows}) < 2:
        return []
    lines = ["## By style", "",
             "| planner | style | gait | agents | arrived | travel time [s] | energy per "
             "metre [J/(kg m)] | step length [m] | cadence [steps/s] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, style, v in rows:
        lines.append(f"| {name} | {style} | {', '.join(v['gait'])} | {v['agents']} | "
                     f"{v['arrived']} | {_fmt(v['travel_time_s'])} | "
                     f"{_fmt(v['energy_per_metre_J_per_kg_m'])} | "
                     f"{_fmt(v['mean_step_length_m'])} | {_fmt(v['cadence_steps_per_s'])} |")
    return lines + [""]


def _report_text(scenario, planners, summaries, tables, pngs, out: Path, *,
                 directions=None, trips=None, baseline=None) -> str:
    first = summaries[planners[0]]
    lines = [
        f"# Planner comparison: {first['scenario'] or Path(str(scenario)).stem}",
        "",
        f"Scenario `{scenario}`, seed {first['seed']}, {first['agents_total']} agents, "
        f"{first['simulated_time_s']:.1f} s simulated per run. Every run uses the same "
        "agents (bodies, free speeds, spawn places and times); only the planner differs. "
        "Runs: " + ", ".join(f"[`{p}/`]({p}/)" for p in planners) + ".",
        "",
        "## Overall",
        "",
        "| planner | arrived | travel time [s] | steps | energy per metre [J/(kg m)] | "
        "footholds on obstacles | plan failures | planner runs | wall time [s] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name in planners:
        s = summaries[name]
        agents = [a for a in s["agents"] if a["steps"] > 0]
        travel = [a["travel_time_s"] for a in agents if a["travel_time_s"] is not None]
        steps = [a["steps"] for a in agents]
        energy = sum(a["energy_J_per_kg"] for a in agents)
        dist = sum(a["distance_m"] for a in agents)
        on_obstacle = sum(v["on_obstacle"] for v in tables[name].values())
        lines.append(
            f"| {name} | {s['agents_arrived']}/{s['agents_total']} | "
            f"{_fmt(float(np.mean(travel)) if travel else None)} | "
            f"{_fmt(float(np.mean(steps)) if steps else None)} | "
            f"{_fmt(energy / dist if dist > 0 else None)} | {on_obstacle} | "
            f"{s['planning']['failures']} | {s['planning']['planner_runs']} | "
            f"{s['timing']['wall_s']:.1f} |"
        )
    lines += [
        "",
        "Travel time and steps are means over the agents that arrived / stepped; energy per "
        "metre is the planners' energy model (Chen & Li Eq. 4, J/kg per step) summed over "
        "all steps and divided by the distance the bodies walked (including the agents "
        "still walking at the end, wherever they are then).",
        "",
    ]
    if trips:
        lines += _trip_lines(trips, baseline)
    lines += _style_lines(planners, summaries)
    lines += [
        "## By terrain type",
        "",
        "Each step counts on the terrain under its landing foot, with its whole length "
        "(a step onto a stair is a stairs step). Up, down and level steps are mixed here: "
        "compare planners in the next table.",
        "",
        "| planner | terrain | footholds | mean step length [m] | energy per metre "
        "[J/(kg m)] (95 % CI) | on obstacles |",
        "|---|---|---|---|---|---|",
    ]
    for name in planners:
        for kind, v in tables[name].items():
            lines.append(f"| {name} | {kind} | {v['footholds']} | "
                         f"{_fmt(v['mean_step_length'])} | {_fmt(v['energy_per_metre'])} "
                         f"({_ci(v['ci'])}) | {v['on_obstacle']} |")
    if directions:
        lines += [""] + _direction_lines(planners, directions, baseline)
    lines += ["", "## Plots", ""]
    titles = {"agents": "Energy per metre, travel time and steps per agent",
              "energy": "Energy per metre by terrain type and step direction",
              "obstacle": "Footholds on obstacles by terrain type",
              "steps": "Footholds by terrain type"}
    for key, path in pngs.items():
        lines += [f"![{titles[key]}]({Path(path).relative_to(out)})", ""]
    return "\n".join(lines)
