"""Planned against unplanned walkers: the same scenario, seed and agents with each planner.

:func:`compare_planners` runs the scenario once per planner (every group switched to that
planner; the population — bodies, speeds, spawn places and times — is drawn from the same
seed, so the agents are identical), each into ``OUT/<planner>/``, and writes
``OUT/report.md`` with PNG plots: energy per metre, travel time and steps per agent,
footholds on obstacles, and energy per metre by terrain type (``Terrain.kind`` under each
foothold).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from crowdwalk.errors import invalid

__all__ = ["compare_planners", "terrain_table"]

ProgressCallback = Callable[[str, float, float, int], None]


def _kind_names() -> dict[int, str]:
    from crowdwalk.terrain import TerrainKind

    return {int(k): k.name.lower() for k in TerrainKind}


def terrain_table(steps: dict[str, np.ndarray]) -> dict[str, dict[str, float]]:
    """Footstep statistics per terrain type.

    Parameters
    ----------
    steps : dict of columns
        ``footsteps.csv`` as read by ``record.Run.footsteps``.

    Returns
    -------
    dict
        terrain type name -> ``footholds``, ``energy_per_metre`` [J/(kg m)] (sum of step
        energies over the sum of step lengths), ``mean_step_length`` [m],
        ``on_obstacle`` (footholds on obstacles).
    """
    names = _kind_names()
    out: dict[str, dict[str, float]] = {}
    kind = steps["kind"]
    for code in np.unique(kind):
        m = kind == code
        length = float(steps["step_length"][m].sum())
        out[names.get(int(code), str(code))] = {
            "footholds": int(m.sum()),
            "energy_per_metre": float(steps["energy"][m].sum() / length) if length > 0
            else float("nan"),
            "mean_step_length": float(steps["step_length"][m].mean()),
            "on_obstacle": int(steps["on_obstacle"][m].sum()),
        }
    return out


def _fmt(x, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "–"
    return f"{x:.{digits}g}" if isinstance(x, float) else str(x)


def compare_planners(
    scenario,
    planners: list[str],
    out: str | Path,
    *,
    duration: float | None = None,
    max_agents: int | None = None,
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
    from planners import PLANNERS

    if not planners:
        raise invalid("compare", "planners", "a non-empty comma-separated list", planners)
    for name in planners:
        if name not in PLANNERS:
            raise invalid("compare", "planners", f"names from {sorted(PLANNERS)}", name)
    if len(set(planners)) != len(planners):
        raise invalid("compare", "planners", "without repeats", planners)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    summaries, tables = {}, {}
    for name in planners:
        def update(t, total, remaining, name=name):
            if progress is not None:
                progress(name, t, total, remaining)

        summaries[name] = run_scenario(
            scenario, out / name, progress=update,
            overrides=RunOverrides(planner=name, duration=duration, poses=False,
                                   max_agents=max_agents),
        )
        tables[name] = terrain_table(open_run(out / name).footsteps())

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
    energy = {n: {k: v["energy_per_metre"] for k, v in t.items()} for n, t in tables.items()}
    pngs["energy"] = plot_by_terrain(energy, out / "energy_by_terrain.png",
                                     ylabel="energy per metre [J/(kg m)]",
                                     title="Energy per metre walked, by terrain type")
    obstacle = {n: {k: float(v["on_obstacle"]) for k, v in t.items()} for n, t in tables.items()}
    pngs["obstacle"] = plot_by_terrain(obstacle, out / "footholds_on_obstacles.png",
                                       ylabel="footholds on obstacles [-]",
                                       title="Footholds on obstacles, by terrain type")
    steps_by = {n: {k: float(v["footholds"]) for k, v in t.items()} for n, t in tables.items()}
    pngs["steps"] = plot_by_terrain(steps_by, out / "footholds_by_terrain.png",
                                    ylabel="footholds [-]", title="Footholds by terrain type")

    report = out / "report.md"
    report.write_text(_report_text(scenario, planners, summaries, tables, pngs, out))
    return report


def _report_text(scenario, planners, summaries, tables, pngs, out: Path) -> str:
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
        "all steps and divided by the distance the bodies walked.",
        "",
        "## By terrain type",
        "",
        "| planner | terrain | footholds | mean step length [m] | energy per metre "
        "[J/(kg m)] | on obstacles |",
        "|---|---|---|---|---|---|",
    ]
    for name in planners:
        for kind, v in tables[name].items():
            lines.append(f"| {name} | {kind} | {v['footholds']} | "
                         f"{_fmt(v['mean_step_length'])} | {_fmt(v['energy_per_metre'])} | "
                         f"{v['on_obstacle']} |")
    lines += ["", "## Plots", ""]
    titles = {"agents": "Energy per metre, travel time and steps per agent",
              "energy": "Energy per metre by terrain type",
              "obstacle": "Footholds on obstacles by terrain type",
              "steps": "Footholds by terrain type"}
    for key, path in pngs.items():
        lines += [f"![{titles[key]}]({Path(path).relative_to(out)})", ""]
    return "\n".join(lines)
