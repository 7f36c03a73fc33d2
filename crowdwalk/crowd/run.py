"""Run a scenario end to end: build the world and the population, simulate, write the run
folder (:mod:`crowdwalk.record`), summarise.

Everything is flushed once per simulated second, so a run that is interrupted stays
readable; Ctrl-C (and SIGTERM at the CLI) still writes ``summary.json`` with
``"interrupted": true`` before the process ends.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from crowdwalk import interrupts
from crowdwalk.crowd.simulation import (
    ARRIVED,
    WAITING,
    CrowdParams,
    CrowdSimulation,
    build_parts,
)
from crowdwalk.errors import invalid
from crowdwalk.sinks import BackgroundSink, OverlapMonitor, RunInfo, RunSink
from crowdwalk.style import summary_by_style
from crowdwalk.workers import WorkerError, Workers, worker_count

__all__ = ["RunOverrides", "check_overrides", "run_scenario", "prepare", "summarise"]


@dataclass(frozen=True)
class RunOverrides:
    """Changes to a scenario for one run (tests, benchmarks, comparisons).

    Attributes
    ----------
    planner : str or None
        Every group uses this planner.
    max_agents : int or None
        Keep only the first agents of the population (in spawn order) [-].
    duration : float or None
        Simulated time limit [s].
    poses : bool or None
        Write poses or not.
    fps : float or None
        Output frame rate [1/s].
    seed : int or None
        The scenario's random seed (``simulation.seed``) [-].
    workers : int or None
        Worker processes beside this one (:func:`crowdwalk.workers.worker_count`; None:
        one per further core for runs of at least 500 walkers, 0: one process).
    """

    planner: str | None = None
    max_agents: int | None = None
    duration: float | None = None
    poses: bool | None = None
    fps: float | None = None
    seed: int | None = None
    workers: int | None = None


ProgressCallback = Callable[[float, float, int], None]


def check_overrides(overrides: RunOverrides) -> None:
    """Raise ``InputError`` for an override outside its range."""
    from planners import PLANNERS

    o = overrides
    if o.planner is not None and o.planner not in PLANNERS:
        raise invalid("RunOverrides", "planner", f"one of {sorted(PLANNERS)}", o.planner)
    if o.seed is not None and not (isinstance(o.seed, int) and o.seed >= 0):
        raise invalid("RunOverrides", "seed", "an integer >= 0", o.seed)
    if o.workers is not None and not (isinstance(o.workers, int) and o.workers >= 0):
        raise invalid("RunOverrides", "workers", "an integer >= 0", o.workers)
    if o.max_agents is not None and o.max_agents < 1:
        raise invalid("RunOverrides", "max_agents", ">= 1", o.max_agents)
    for name in ("duration", "fps"):
        value = getattr(o, name)
        if value is not None and not (np.isfinite(value) and value > 0):
            raise invalid("RunOverrides", name, "> 0 [s]" if name == "duration" else "> 0 [1/s]",
                          value)


def prepare(scenario, overrides: RunOverrides | None = None, *,
            params: CrowdParams | None = None, parallel: bool = False):
    """World, population and simulation of a scenario (a path or a loaded Scenario).

    With ``parallel`` the simulation gets worker processes (``overrides.workers``) for
    its steering and posing; ``simulation.workers`` then needs closing.

    Returns
    -------
    (scenario, world, simulation, pose_note, scenario_text)
        ``pose_note`` says whether poses are written ("written") or why not.
    """
    import yaml

    overrides = overrides or RunOverrides()
    check_overrides(overrides)
    params = params or CrowdParams()
    from crowdwalk.checks import world_and_population
    from crowdwalk.scenario import Scenario, load_scenario

    if isinstance(scenario, Scenario):
        sc = scenario
        text = yaml.safe_dump(sc.model_dump(mode="json", by_alias=True), sort_keys=False)
    else:
        path = Path(scenario)
        sc = load_scenario(path)
        text = path.read_text()
    if overrides.seed is not None and overrides.seed != sc.simulation.seed:
        sc = sc.model_copy(update={"simulation": sc.simulation.model_copy(
            update={"seed": overrides.seed})})
        text = yaml.safe_dump(sc.model_dump(mode="json", by_alias=True), sort_keys=False)
    world, pop = world_and_population(sc)
    if overrides.planner is not None:
        pop = pop.with_planner(overrides.planner)
    if overrides.max_agents is not None:
        order = np.argsort(pop.spawn_time, kind="stable")[: overrides.max_agents]
        pop = pop.take(np.sort(order))
    duration = overrides.duration if overrides.duration is not None else sc.simulation.duration
    fps = overrides.fps if overrides.fps is not None else sc.simulation.fps
    want_poses = sc.outputs.poses if overrides.poses is None else overrides.poses
    count = worker_count(len(pop), overrides.workers, poses=want_poses) if parallel else 0
    workers = Workers(count) if count else None
    try:
        gait, pose_note = None, "disabled (outputs.poses is false)"
        if want_poses:
            try:
                if workers is None:
                    gait = _make_gait(pop, world.terrain)
                else:  # posing in worker 0, beside the simulation
                    from crowdwalk.gait.remote import RemoteEngine

                    gait = RemoteEngine(partial(_make_gait, pop, world.terrain), workers)
                pose_note = "written"
            except ImportError as exc:  # a build without the gait package: say so, go on
                pose_note = f"not available in this build ({exc})"
        parts = build_parts(world, pop, params=params)
        sim = CrowdSimulation(world, pop, parts=parts, dt=sc.simulation.dt, fps=fps,
                              duration=duration, params=params, gait=gait, workers=workers)
    except BaseException:
        if workers is not None:
            workers.close()
        raise
    return sc, world, sim, pose_note, text


def _make_gait(pop, terrain):
    """The gait engine of the population: each group's (``groups[].gait``) over all bodies,
    behind one :class:`~crowdwalk.gait.engine.MixedEngine` when groups differ."""
    from crowdwalk.body import Body
    from crowdwalk.gait.engine import MixedEngine, make_engine

    body = Body.from_heights(pop.body_height)
    names, choice = np.unique(pop.gait.astype(str), return_inverse=True)
    engines = [make_engine(str(name), body=body, ground=terrain.height, attributes=pop.style)
               for name in names]
    return engines[0] if len(engines) == 1 else MixedEngine(engines, choice)


def run_scenario(
    scenario,
    out: str | Path,
    *,
    overrides: RunOverrides | None = None,
    progress: ProgressCallback | None = None,
    params: CrowdParams | None = None,
    sinks: Sequence[RunSink] = (),
) -> dict:
    """Simulate ``scenario`` and write the run folder ``out``.

    Parameters
    ----------
    scenario : path or Scenario
    out : path
        Run folder (created; run files in it are replaced).
    overrides : RunOverrides
    progress : callable, optional
        ``progress(simulated_time [s], duration [s], agents_remaining)`` once per frame.
    params : CrowdParams
    sinks : sequence of crowdwalk.sinks.RunSink
        Further observers of the run, after the run folder's writer and the overlap
        monitor.

    Returns
    -------
    dict
        The summary also written to ``summary.json``.
    """
    with interrupts.deferred():
        wall0 = time.perf_counter()
        sc, world, sim, pose_note, text = prepare(scenario, overrides, params=params,
                                                  parallel=True)
        try:
            return _run(sc, world, sim, pose_note, text, out=out, wall0=wall0,
                        progress=progress, sinks=sinks)
        finally:
            if sim.workers is not None:
                sim.workers.close()


def _run(sc, world, sim, pose_note, text, *, out, wall0, progress, sinks) -> dict:
    """The body of :func:`run_scenario`, within deferred interrupts."""
    from crowdwalk.record import RunWriter

    skeleton = sim.gait.skeleton if sim.gait is not None else None
    # the run folder is written in a thread of its own, beside the simulation
    writer = BackgroundSink(partial(RunWriter, out, scenario_text=text, fps=sim.fps,
                                    walkable_wkt=world.routes.walkable_area.wkt,
                                    skeleton=skeleton))
    # and the outlines are checked in another (cKDTree and numpy release the GIL): the
    # check's result is read once, for the summary
    overlap = OverlapMonitor()
    checker = BackgroundSink(lambda: overlap, name="crowdwalk-overlap")
    everyone: list[RunSink] = [writer, checker, *sinks]
    pop = sim.pop
    info = RunInfo(fps=sim.fps, body_height=pop.body_height, shape=sim.shape,
                   group=np.asarray(pop.group_names, dtype=object)[pop.group].astype(str),
                   planner=pop.planner.astype(str))
    for sink in everyone:
        sink.begin(info)
    setup = time.perf_counter() - wall0
    timing = {"setup_s": setup, "poses_s": 0.0, "writing_s": 0.0}
    interrupted = False

    def deliver(frame) -> None:
        """The steps decided up to an output frame, then the frame (its poses awaited)."""
        t, snapshot, steps, poses_later = frame
        w0 = time.perf_counter()
        poses = poses_later()
        w1 = time.perf_counter()
        if steps is not None:
            for sink in everyone:
                sink.steps(steps)
        if snapshot is not None:
            for sink in everyone:
                sink.frame(t, snapshot, poses)
        timing["poses_s"] += w1 - w0
        timing["writing_s"] += time.perf_counter() - w1

    # a frame is delivered when the next one has been asked for: a gait engine in a
    # worker process (crowdwalk.gait.remote) poses it while the next ticks are simulated
    waiting = None
    walkable = sim.routes.graph
    try:
        deliver((sim.time, sim.snapshot(), None, lambda: None))
        while not sim.finished:
            interrupts.check()
            if not sim.step():
                continue
            w0 = time.perf_counter()
            frame = (sim.time, sim.snapshot(), sim.take_steps(), sim.poses_later())
            timing["poses_s"] += time.perf_counter() - w0
            if waiting is not None:
                deliver(waiting)
            if sim.routes.graph is not walkable:  # an event shut or opened a door: the
                walkable = sim.routes.graph  # frames from this one on have the new area
                writer.call("set_walkable", walkable.walkable_area.wkt)
            waiting = frame
            if progress is not None:
                progress(sim.time, sim.duration, sim.remaining)
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        if waiting is not None:
            try:
                deliver(waiting)
            except WorkerError:  # lost with its worker: keep the error already raised
                if sys.exc_info()[0] is None:
                    raise
        deliver((sim.time, None, sim.take_steps(), lambda: None))  # steps after the last frame
        wall = time.perf_counter() - wall0
        timing.update(wall_s=wall, planning_s=sim.wall_planning, steering_s=sim.wall_steering,
                      step_commands_s=sim.wall_commands)
        checker.wait()
        summary = summarise(sim, sc, timing=timing, max_overlap=overlap.max_overlap,
                            interrupted=interrupted, poses=pose_note)
        for sink in everyone:
            sink.end(summary)
    if not interrupted and (sc.measurement.lines or sc.measurement.areas):
        from crowdwalk.analysis import analyse_run

        summary["measurement"] = analyse_run(out, sc.measurement)
    return summary


def _stats(values: np.ndarray) -> dict:
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {"mean": None, "sd": None, "min": None, "max": None}
    return {"mean": float(values.mean()), "sd": float(values.std()),
            "min": float(values.min()), "max": float(values.max())}


def summarise(sim: CrowdSimulation, scenario, *, timing: dict, max_overlap: float,
              interrupted: bool, poses: str) -> dict:
    """Per-agent and per-group statistics of a simulation (units in the key names)."""
    st, pop = sim.state, sim.pop
    arrived = st.status == ARRIVED
    spawned = st.status != WAITING
    travel = np.where(arrived, st.arrival_time - st.start_time, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        per_m = np.where(st.distance > 0, st.energy / st.distance, np.nan)
        walk_time = np.where(arrived, travel, sim.time - st.start_time) - st.wait
        cadence = np.where(walk_time > 0, st.steps / walk_time, np.nan)
        mean_sl = np.where(st.steps > 0, st.distance / st.steps, np.nan)
    groups = np.asarray(pop.group_names, dtype=object)[pop.group]
    planner = pop.planner.astype(str)

    def opt(x: float):
        return None if not np.isfinite(x) else float(x)

    gaits, styles = pop.gait, pop.style.preset_name
    agents = [
        {
            "id": i, "group": str(groups[i]), "planner": str(planner[i]),
            "body_height_m": float(pop.body_height[i]), "free_speed_m_s": float(pop.free_speed[i]),
            "spawned": bool(spawned[i]), "arrived": bool(arrived[i]),
            "start_time_s": opt(st.start_time[i]), "travel_time_s": opt(travel[i]),
            "distance_m": float(st.distance[i]), "steps": int(st.steps[i]),
            "energy_J_per_kg": float(st.energy[i]), "energy_per_metre_J_per_kg_m": opt(per_m[i]),
            "climb_m": float(st.climb[i]), "waiting_s": float(st.wait[i]),
            "mean_step_length_m": opt(mean_sl[i]), "cadence_steps_per_s": opt(cadence[i]),
            "plans": int(st.plans[i]), "plan_failures": int(st.plan_failures[i]),
            "shortened_steps": int(st.shortened[i]), "reroutes": int(st.reroutes[i]),
            "gait": str(gaits[i]), "style": str(styles[i]),  # "" without a preset
        }
        for i in range(sim.n)
    ]
    by_group = {}
    for gi, name in enumerate(pop.group_names):
        m = pop.group == gi
        if not m.any():
            continue
        dist = float(st.distance[m].sum())
        by_group[name] = {
            "planner": pop.planner_names[gi], "agents": int(m.sum()),
            "arrived": int(arrived[m].sum()),
            "travel_time_s": _stats(travel[m]), "distance_m": _stats(st.distance[m]),
            "steps": _stats(st.steps[m].astype(float)),
            "energy_J_per_kg": _stats(st.energy[m]),
            "energy_per_metre_J_per_kg_m": float(st.energy[m].sum() / dist) if dist > 0
            else None,
            "waiting_s": _stats(st.wait[m]),
            "planning": {"plans": int(st.plans[m].sum()),
                         "failures": int(st.plan_failures[m].sum()),
                         "shortened_steps": int(st.shortened[m].sum()),
                         "reroutes": int(st.reroutes[m].sum())},
        }
    wall = float(timing.get("wall_s", float("nan")))
    return {
        "scenario": scenario.name, "seed": scenario.simulation.seed,
        "complete": bool(sim.remaining == 0 or sim.time >= sim.duration - 1e-9),
        "interrupted": interrupted,
        "simulated_time_s": float(sim.time), "duration_s": sim.duration,
        "dt_s": sim.dt, "fps": sim.fps,
        "agents_total": sim.n, "agents_arrived": int(arrived.sum()),
        "agents_remaining": sim.remaining,
        "max_overlap_m": float(max_overlap),
        "poses": poses,
        "planning": {"requests": sim.footsteps.calls, "cache_hits": sim.footsteps.hits,
                     "planner_runs": sim.footsteps.calls - sim.footsteps.hits,
                     "retries_half_leg_trailing": sim.footsteps.retries,
                     "failures": int(st.plan_failures.sum()),
                     "shortened_steps": int(st.shortened.sum()),
                     "reroutes": int(st.reroutes.sum())},
        "timing": {**{k: float(v) for k, v in timing.items()},
                   "simulated_s_per_wall_s": float(sim.time / wall) if wall > 0 else None},
        "groups": by_group,
        "events": sim.events.summary() if sim.events is not None else [],
        "waiting_areas": sim.holding.summary() if sim.holding is not None else [],
        "styles": summary_by_style(agents),
        "agents": agents,
    }
