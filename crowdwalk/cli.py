"""The ``crowdwalk`` command line.

Every command imports its implementation lazily so ``--help`` is fast. Bad input ends
with one line on stderr and exit code 2 (130 on Ctrl-C), never a traceback.
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import typer

app = typer.Typer(
    name="crowdwalk",
    help="Crowds of walking people that plan their footsteps.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # help texts carry units in [brackets]; keep them literal
)


def _version(value: bool) -> None:
    if value:
        from crowdwalk import __version__

        typer.echo(f"crowdwalk {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                 help="Print the version and exit."),
) -> None:
    """Crowds of walking people that plan their footsteps."""


def _fail(message: str, code: int) -> None:
    typer.echo(f"crowdwalk: {message}", err=True)
    raise typer.Exit(code)


def _warn_incomplete(target: Path) -> None:
    """Say on stderr when ``target`` is a run folder a killed run left (no summary.json)."""
    from crowdwalk.cli_conventions import incomplete_note

    note = incomplete_note(target)
    if note:
        typer.echo(f"crowdwalk: warning: {note}", err=True)


_OVERWRITE = typer.Option(False, "--overwrite", help="Replace the run files in a non-empty --out.")


def friendly_errors(func):
    """Turn bad input into one clear line and exit code 2."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except typer.Exit:
            raise
        except KeyboardInterrupt:
            _fail("interrupted; files written so far stay readable.", 130)
        except FileNotFoundError as exc:
            _fail(f"file not found: {exc.filename or exc}", 2)
        except (ValueError, OSError) as exc:
            from crowdwalk.checks import plain

            _fail(plain(str(exc)).splitlines()[0] if str(exc) else type(exc).__name__, 2)

    return wrapper


# --- scenario files -----------------------------------------------------------------


@app.command()
@friendly_errors
def validate(scenario: Path = typer.Argument(..., help="Scenario YAML file.")) -> None:
    """Check a scenario file against the schema and build its world."""
    from collections import Counter

    from crowdwalk.checks import world_and_population
    from crowdwalk.scenario import load_scenario

    sc = load_scenario(scenario)
    world, _ = world_and_population(sc)
    n = sum(g.count for g in sc.groups)
    x0, y0, x1, y1 = world.terrain.bounds
    kinds = Counter(f.type for f in sc.terrain.features)
    feats = ", ".join(f"{k} {v}" for k, v in sorted(kinds.items()))
    typer.echo(
        f"{scenario}: valid — terrain {x1 - x0:g} × {y1 - y0:g} m"
        f"{f' ({feats})' if feats else ''}, "
        f"{world.routes.graph.number_of_nodes()} route nodes, "
        f"{len(world.routes.corridors)} corridors, "
        f"walkable area {world.routes.walkable_area.area:.1f} m², "
        f"{len(sc.groups)} group(s), {n} agent(s)."
    )


@app.command()
@friendly_errors
def schema() -> None:
    """Print the scenario file's JSON Schema."""
    import json

    from crowdwalk.scenario import scenario_json_schema

    typer.echo(json.dumps(scenario_json_schema(), indent=2))


# --- planning (issue 3): plan -------------------------------------------------------


@app.command("plan")
@friendly_errors
def plan_command(
    profile: Path = typer.Option(..., "--profile", help="CSV with columns s,z [m]; a vertical "
                                 "height change is two rows with the same s."),
    planner: str = typer.Option("best_first_multistart", "--planner",
                                help="best_first (Chen & Li as written), "
                                "best_first_multistart, fixed (unplanned) or optimal."),
    body_height: float = typer.Option(1.75, "--body-height", help="Body height [m]."),
    speed: float = typer.Option(1.34, "--speed", help="Walking speed [m/s]."),
    horizon: bool = typer.Option(False, "--horizon", help="Plan one horizon from s = 0 "
                                 "instead of walking the whole profile."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    plot: Path | None = typer.Option(None, "--plot", help="Write a plot of the plan (PNG)."),
) -> None:
    """Walk a ground profile by receding horizon (exit 1 where no legal foothold)."""
    from crowdwalk.planning import format_plan, plan_profile

    result = plan_profile(profile, planner, body_height, speed, plot, horizon=horizon)
    typer.echo(format_plan(result, as_json))
    if plot is not None and not as_json:
        typer.echo(f"wrote the plan plot {plot}")
    if not result.ok:
        raise typer.Exit(1)


# --- simulation (issue 5): run, compare ---------------------------------------------


def _sim_progress(quiet: bool, label: str):
    """A rich progress bar (simulated time, agents remaining) or a silent stand-in."""
    import contextlib

    if quiet:
        return contextlib.nullcontext(None)
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    return Progress(
        TextColumn("[bold]{task.description}"), BarColumn(),
        TextColumn("t = {task.completed:6.1f} / {task.total:.0f} s"),
        TextColumn("{task.fields[remaining]} agents remaining"), TimeElapsedColumn(),
        transient=False,
    )


def _check_before_running(scenario: Path, overrides) -> None:
    """Check the overrides, load the scenario and build its world (milliseconds), so that
    bad input ends with its one-line message before a progress bar is drawn."""
    from crowdwalk.checks import world_and_population
    from crowdwalk.crowd.run import check_overrides
    from crowdwalk.scenario import load_scenario

    check_overrides(overrides)
    world_and_population(load_scenario(scenario))


def _term_as_interrupt() -> None:
    """Let SIGTERM end a run like Ctrl-C (summary written, files closed)."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        def _raise(signum, frame):
            raise KeyboardInterrupt

        signal.signal(signal.SIGTERM, _raise)


@app.command()
@friendly_errors
def run(
    scenario: Path = typer.Argument(..., help="Scenario YAML file."),
    out: Path = typer.Option(..., "--out", help="Run folder to write."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bar."),
    planner: str = typer.Option(None, "--planner", help="Override every group's planner."),
    duration: float = typer.Option(None, "--duration", help="Override the duration [s]."),
    seed: int = typer.Option(None, "--seed", help="Override the scenario's random seed."),
    workers: int = typer.Option(None, "--workers", help="Worker processes beside this one "
                                "(default: one per further core from 500 walkers; 0: none)."),
    crowd_model: str = typer.Option("headway_s175", "--crowd-model", help="Named crowd "
                                    "model: headway_s175 (the default) or free "
                                    "(crowdwalk.crowd.params.CROWD_MODELS)."),
    overwrite: bool = _OVERWRITE,
) -> None:
    """Simulate a scenario and write trajectories, footsteps, poses and a summary."""
    from crowdwalk.cli_conventions import check_out_folder, next_hint
    from crowdwalk.crowd.params import crowd_model as named_model
    from crowdwalk.crowd.run import RunOverrides, run_scenario

    _term_as_interrupt()
    params = named_model(crowd_model)
    check_out_folder(out, overwrite, "run")
    overrides = RunOverrides(planner=planner, duration=duration, seed=seed, workers=workers)
    _check_before_running(scenario, overrides)
    with _sim_progress(quiet, scenario.stem) as bar:
        update = None
        if bar is not None:
            task = bar.add_task(scenario.stem, total=1.0, remaining="?")

            def update(t: float, total: float, remaining: int) -> None:
                bar.update(task, completed=t, total=total, remaining=remaining)

        summary = run_scenario(scenario, out, overrides=overrides, progress=update,
                               params=params)
    arrived = f"{summary['agents_arrived']}/{summary['agents_total']} agents arrived"
    if quiet:
        typer.echo(f"wrote the run folder {out} ({arrived}); {next_hint(f'crowdwalk view {out}')}")
        return
    tm = summary["timing"]
    typer.echo(
        f"{arrived} in {summary['simulated_time_s']:.1f} s simulated, {tm['wall_s']:.1f} s wall "
        f"({tm['simulated_s_per_wall_s']:.2f}× real time); poses {summary['poses']}.\n"
        f"wrote the run folder {out}: trajectories.sqlite (PedPy), footsteps.csv, "
        f"{'poses.sqlite, ' if (out / 'poses.sqlite').exists() else ''}summary.json.\n"
        + next_hint(f"crowdwalk view {out}", f"crowdwalk render {out} --out {out}/frame.png",
                    f"crowdwalk analyse {out}"))


@app.command()
@friendly_errors
def compare(
    scenario: Path = typer.Argument(..., help="Scenario YAML file."),
    planners: str = typer.Option("best_first,best_first_multistart,optimal,fixed",
                                 "--planners", help="Comma-separated planners to compare "
                                 "(each against fixed, the unplanned walker)."),
    out: Path = typer.Option(..., "--out", help="Folder for the runs and report.md."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bar."),
    duration: float = typer.Option(None, "--duration", help="Override the duration [s]."),
    seeds: str = typer.Option(None, "--seeds", help="Seeds A..B: every planner with every "
                              "seed on Dask (resumable); intervals across seeds."),
    poses: bool = typer.Option(None, "--poses/--no-poses", help="Write poses for each run "
                               "(default: as the scenario's outputs.poses)."),
    overwrite: bool = _OVERWRITE,
) -> None:
    """Run the same scenario, seed and agents with each planner; write report.md."""
    from crowdwalk.cli_conventions import check_out_folder, next_hint
    from crowdwalk.compare import check_planners, compare_planners
    from crowdwalk.crowd.run import RunOverrides

    _term_as_interrupt()
    names = [p.strip() for p in planners.split(",") if p.strip()]
    if seeds is not None:
        from crowdwalk.sweep import SweepSpec, parse_seeds, run_sweep

        check_planners(names)
        spec = SweepSpec(scenario=scenario.resolve(), seeds=tuple(parse_seeds(seeds)),
                         planners=tuple(names), duration=duration)
        _check_before_running(scenario, RunOverrides(duration=duration))
        report = run_sweep(spec, out, progress=None if quiet else _sweep_echo)
        typer.echo(f"wrote the report {report} and one run folder per trial in {out}/trials")
        return
    check_out_folder(out, overwrite, "compare")
    check_planners(names)
    _check_before_running(scenario, RunOverrides(duration=duration))
    with _sim_progress(quiet, scenario.stem) as bar:
        update = None
        if bar is not None:
            task = bar.add_task(scenario.stem, total=1.0, remaining="?")

            def update(label: str, t: float, total: float, remaining: int) -> None:
                bar.update(task, description=label, completed=t, total=total,
                           remaining=remaining)

        report = compare_planners(scenario, names, out, duration=duration, poses=poses,
                                  progress=update)
    typer.echo(f"wrote the report {report} and one run folder per planner in {out}; "
               + next_hint(f"crowdwalk view {' '.join(f'{out}/{n}' for n in names)}"))


def _sweep_echo(done: int, total: int, trial: str) -> None:
    typer.echo(f"[{done}/{total}] {trial}")


@app.command()
@friendly_errors
def sweep(
    sweep_file: Path = typer.Argument(..., help="Sweep YAML (scenario, seeds, planners, axes)."),
    out: Path = typer.Option(..., "--out", help="Sweep folder (finished trials are kept)."),
    scheduler: str = typer.Option(None, "--scheduler",
                                  help="Address of a running Dask scheduler (default: a "
                                  "LocalCluster, one worker process per core)."),
    workers: int = typer.Option(None, "--workers", help="LocalCluster worker processes."),
    quiet: bool = typer.Option(False, "--quiet", help="No line per finished trial."),
) -> None:
    """Run a study: one run folder per trial, manifest.csv, report.md (Dask distributed)."""
    from crowdwalk.sweep import load_sweep, run_sweep

    if workers is not None and workers < 1:
        _fail(f"sweep --workers must be >= 1; got {workers}.", 2)
    spec = load_sweep(sweep_file)
    report = run_sweep(spec, out, scheduler=scheduler, workers=workers,
                       progress=None if quiet else _sweep_echo)
    typer.echo(f"wrote {out}/manifest.csv and the report {report}")


# --- measurement and verification (issue 14): analyse, verify ---------------------


@app.command()
@friendly_errors
def analyse(run_dir: Path = typer.Argument(..., help="Run folder.")) -> None:
    """PedPy analysis into RUN/analysis/: speeds along the 3-D path (speeds_3d.csv) and the
    scenario's measurement lines and areas."""
    from crowdwalk.analysis import analyse_run
    from crowdwalk.record import open_run
    from crowdwalk.scenario import parse_scenario
    from crowdwalk.speeds3d import write_walking_speeds

    _warn_incomplete(run_dir)
    typer.echo(write_walking_speeds(run_dir))
    scenario = open_run(run_dir).scenario_path
    measurement = parse_scenario(scenario.read_text(encoding="utf-8"), str(scenario)).measurement
    if not (measurement.lines or measurement.areas):
        typer.echo("no measurement lines or areas in the scenario: nothing more to analyse.")
        return
    result = analyse_run(run_dir, measurement)
    for kind in ("lines", "areas"):
        for row in result[kind]:
            typer.echo(f"{kind[:-1]} {row['name']}: " + ", ".join(
                f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                for k, v in row.items() if k != "name"))


@app.command()
@friendly_errors
def verify(
    full: bool = typer.Option(False, "--full", help="Every case at full size (minutes)."),
    out: Path = typer.Option(Path("docs/verification.md"), "--out", help="Markdown table."),
    only: str = typer.Option("", "--only", help="Comma-separated case names."),
    seeds: int = typer.Option(0, "--seeds", min=0, help="Seeds of the counterflow case "
                              "(0: 1 fast, 5 full)."),
    speed_model: str = typer.Option("", "--speed-model", help="Crowd speed model alone, "
                                    "over the crowd model: free, time_gap, contact_gap or "
                                    "headway."),
    crowd_model: str = typer.Option("", "--crowd-model", help="Named crowd model: "
                                    "headway_s175 (the default) or free."),
) -> None:
    """Run the RiMEA tests that apply, the bottleneck series and the fundamental diagram."""
    from crowdwalk.crowd.params import crowd_model as named_model
    from crowdwalk.errors import invalid
    from crowdwalk.verify import run_verification

    models = ("free", "time_gap", "contact_gap", "headway")
    if speed_model and speed_model not in models:
        raise invalid("verify", "speed_model", f"one of {', '.join(models)}", speed_model)
    params = None
    if speed_model or crowd_model:
        params = named_model(crowd_model or "headway_s175",
                             {"speed_model": speed_model} if speed_model else None)
    run_verification(full=full, out=out, only=[s for s in only.split(",") if s],
                     seeds=seeds or None, params=params, echo=typer.echo,
                     command_options=(f"{f' --crowd-model {crowd_model}' if crowd_model else ''}"
                                      f"{f' --speed-model {speed_model}' if speed_model else ''}"))


# --- gait export (issue 4): export-bvh ----------------------------------------------


@app.command("export-bvh")
@friendly_errors
def export_bvh_command(
    run_dir: Path = typer.Argument(..., help="Run folder with poses.sqlite."),
    agent: int = typer.Option(..., "--agent", help="Agent id to export."),
    out: Path = typer.Option(..., "--out", help="BVH file to write."),
    scale: float = typer.Option(100.0, "--scale", help="BVH units per metre (100: cm)."),
    naming: str = typer.Option("common", "--names", help="Joint names: common (Hips, "
                               "LeftFoot, ...: found by BVH tools) or hanim (H-Anim)."),
) -> None:
    """Write one agent's full-body motion as a BVH file."""
    from crowdwalk.export_bvh import export_bvh

    _warn_incomplete(run_dir)
    path = export_bvh(run_dir, agent, out, scale=scale, naming=naming)
    typer.echo(f"wrote agent {agent}'s motion to {path}; next: import it in Blender "
               "(File > Import > Motion Capture) or any BVH reader")


@app.command("export-gltf")
@friendly_errors
def export_gltf_command(
    run_dir: Path = typer.Argument(..., help="Run folder with poses.sqlite."),
    out: Path = typer.Option(..., "--out", help="glTF binary (.glb) to write."),
    agents: str = typer.Option("", "--agents", help="Comma-separated agent ids (default: all)."),
    naming: str = typer.Option("common", "--names", help="Joint names: common or hanim."),
) -> None:
    """Write every walker (one animated skeleton each) as one glTF binary."""
    from crowdwalk.export_gltf import export_gltf

    _warn_incomplete(run_dir)
    from crowdwalk.errors import invalid

    try:
        ids = [int(a) for a in agents.split(",") if a.strip()] or None
    except ValueError:
        raise invalid("export-gltf", "agents", "comma-separated agent ids", agents) from None
    path = export_gltf(run_dir, out, agents=ids, naming=naming)
    typer.echo(f"wrote {path} (one animated skeleton per walker); next: import it in Blender "
               "(File > Import > glTF 2.0), Unity or Unreal")


@app.command("gait-report")
@friendly_errors
def gait_report_command(
    run_dir: Path = typer.Argument(..., help="Run folder with poses.sqlite."),
    plot: Path = typer.Option(None, "--plot", help="PNG of the joint curves to write."),
) -> None:
    """Gait of a run's walkers against Winter, WBDS and Bovi (measured from the run)."""
    from crowdwalk.gait_report import plot_curves, report_table, run_figures

    figures = run_figures(run_dir)
    typer.echo(report_table(figures))
    if plot is not None:
        typer.echo(f"wrote {plot_curves(figures, plot)}")


# --- viewer (issue 6): view, render -------------------------------------------------

_COLOR_HELP = "Colour by: energy (footprints), group, planner, style or agent."
_TARGETS_HELP = ("Run folders (side by side, linked), a `compare` output folder, or a scenario "
                 "YAML (world only).")
_GL_MISSING = (
    "off-screen rendering needs an EGL/GL stack; install the Debian packages "
    "libegl1 libegl-mesa0 libgl1-mesa-dri (see install.sh)."
)


def _check_times(scene, command: str, **options: float | None) -> None:
    """Each time option [s] must lie within a run's frames (from t = 0 to its last frame)."""
    from crowdwalk.cli_conventions import check_time

    if scene.poses is None:
        return
    t_range = (min(scene.time_range[0], 0.0), scene.time_range[1])
    for option, value in options.items():
        check_time(value, t_range, option=option, command=command)


@app.command()
@friendly_errors
def view(
    targets: list[Path] = typer.Argument(..., help=_TARGETS_HELP),
    follow: int | None = typer.Option(None, "--follow", help="Agent id the camera follows."),
    color: str = typer.Option("energy", "--color", help=_COLOR_HELP),
    time: float | None = typer.Option(None, "--time", help="Start at this simulated time [s]."),
    trail: float | None = typer.Option(
        None, "--trail", help="Show only footprints of the last TRAIL seconds [s]."
    ),
    web: bool = typer.Option(False, "--web", help="Serve the viewer to a web browser."),
    port: int = typer.Option(8080, "--port", help="--web: TCP port (0: any free one)."),
) -> None:
    """Open the interactive viewer (keys: space play/pause, ←/→ one frame, ↑/↓ speed,
    c colour, f follow); with --web, in a browser."""
    from crowdwalk.viz.headless import display_problem

    problem = None if web else display_problem()
    if problem:
        _fail(f"view needs a window, but {problem}; use `crowdwalk view --web` or "
              "`crowdwalk render` for pictures and movies off-screen.", 2)
    for target in targets:
        _warn_incomplete(target)
    from crowdwalk.viz import load_scenes

    scenes = load_scenes(targets, color=color, follow=follow, footprint_trail=trail)
    _check_times(scenes[0], "view", time=time)
    if web:
        from crowdwalk.viz.web import serve

        serve(scenes, port=port, time=time, announce=typer.echo)
    else:
        scenes[0].show(time=time, beside=scenes[1:])


@app.command()
@friendly_errors
def render(
    targets: list[Path] = typer.Argument(..., help=_TARGETS_HELP),
    out: Path = typer.Option(..., "--out", help="Output file: .png, .gif or .mp4."),
    time: float | None = typer.Option(None, "--time", help="PNG: simulated time [s]."),
    start: float | None = typer.Option(None, "--start", help="Movie: first time [s]."),
    end: float | None = typer.Option(None, "--end", help="Movie: last time [s]."),
    size: str = typer.Option("1280x800", "--size", help="Image size WIDTHxHEIGHT [px]."),
    follow: int | None = typer.Option(None, "--follow", help="Agent id the camera follows."),
    color: str = typer.Option("energy", "--color", help=_COLOR_HELP),
    fps: float | None = typer.Option(None, "--fps", help="Movie frame rate [1/s]."),
    speed: float = typer.Option(1.0, "--speed", help="Movie: simulated seconds per second."),
    trail: float | None = typer.Option(
        None, "--trail", help="Show only footprints of the last TRAIL seconds [s]."
    ),
) -> None:
    """Render a run off-screen: one instant to PNG, or a time range to GIF/MP4."""
    from crowdwalk.errors import invalid
    from crowdwalk.viz.scene import MOVIE_SUFFIXES, parse_size

    suffix = out.suffix.lower()
    if suffix not in (".png", *MOVIE_SUFFIXES):
        raise invalid("render", "out", "a .png, .gif or .mp4 file", str(out))
    width_height = parse_size(size)
    if suffix == ".png" and (start is not None or end is not None):
        raise invalid("render", "start", "unset for a .png (use --time) [s]", (start, end))
    if suffix != ".png" and time is not None:
        raise invalid("render", "time", "unset for a movie (use --start/--end) [s]", time)
    from crowdwalk.viz import load_scenes
    from crowdwalk.viz.headless import gl_available

    for target in targets:
        _warn_incomplete(target)
    scene, *beside = load_scenes(targets, color=color, follow=follow, footprint_trail=trail)
    _check_times(scene, "render", time=time, start=start, end=end)
    if not gl_available():
        _fail(_GL_MISSING, 2)
    if suffix == ".png":
        scene.render_png(out, time=time, size=width_height, beside=beside)
    else:
        from rich.progress import Progress

        with Progress(transient=True) as bar:
            task = bar.add_task(f"rendering {out.name}", total=None)
            scene.render_movie(
                out, start=start, end=end, fps=fps, size=width_height, speed=speed, beside=beside,
                progress=lambda done, total: bar.update(task, completed=done, total=total),
            )
    what = "the picture" if suffix == ".png" else "the movie"
    shown = " ".join(str(t) for t in targets)
    typer.echo(f"wrote {what} {out}; next: open it in an image viewer"
               + (f", or `crowdwalk view {shown}` to explore" if targets[0].is_dir() else ""))


# --- gait engines against people (issue 13): gait-compare ---------------------------


@app.command("gait-compare")
@friendly_errors
def gait_compare_command(
    out: Path = typer.Option(Path("gait_compare"), "--out", help="Folder for the runs."),
    plot: Path | None = typer.Option(None, "--plot", help="Write the curves figure (PNG)."),
) -> None:
    """Run the same lone walker at 1.0, 1.33 and 1.7 m/s with every gait engine and print
    joint-angle RMS / r against Winter and step length / cadence against WBDS."""
    from crowdwalk.gait.engine import GAIT_ENGINES
    from crowdwalk.gait_compare import comparison_table, plot_comparison, run_comparison

    engines = tuple(GAIT_ENGINES)
    rows = run_comparison(out, engines=engines,
                          progress=lambda e, v: typer.echo(f"ran {e} at {v:g} m/s", err=True))
    typer.echo(comparison_table(rows))
    if plot is not None:
        typer.echo(f"wrote {plot_comparison(rows, plot)}")


def main() -> None:
    """Entry point of the ``crowdwalk`` script."""
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
