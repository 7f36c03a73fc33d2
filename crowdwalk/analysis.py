"""Measurement lines and areas of a run folder, analysed with PedPy.

Reads ``trajectories.sqlite`` (JuPedSim format v2, as PedPy loads it) and the scenario's
``measurement`` section from the run folder and writes ``analysis/``:

- per area ``area_<name>.csv`` (``time_s, density_per_m2, speed_m_s``: PedPy's classic
  density and the mean individual speed of the walkers inside) and ``area_<name>.png``;
- per line ``line_<name>.csv`` (``time_s, crossed, density_per_m2, speed_m_s``: PedPy's
  N–t count, and density and mean speed in the 1 m deep strip centred on the line) and
  ``line_<name>.png``;
- ``measurement.json``, the figures :func:`analyse_run` returns (also merged into the
  run's ``summary.json`` under ``"measurement"``).

Individual speeds are PedPy's over ±``speed_window``/2 [s] (single-sided at the ends of a
trajectory). The flow across a line is (N − 1) / (t_N − t_1) [1/s] over its N crossings.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from crowdwalk.errors import invalid

__all__ = ["LineFigures", "AreaFigures", "analyse_run", "STRIP_DEPTH"]

#: Depth of the strip around a measurement line where density and speed are taken [m].
STRIP_DEPTH = 1.0


@dataclass(frozen=True)
class LineFigures:
    """What crossed a measurement line: ``crossings`` [-], ``flow_per_s`` [1/s] (None with
    fewer than two crossings), mean ``density_per_m2`` [1/m²] and ``speed_m_s`` [m/s] in
    its strip while occupied."""

    name: str
    crossings: int
    flow_per_s: float | None
    density_per_m2: float | None
    speed_m_s: float | None


@dataclass(frozen=True)
class AreaFigures:
    """Density [1/m²] (mean and peak over the occupied frames) and mean speed [m/s] in a
    measurement area."""

    name: str
    density_per_m2: float | None
    peak_density_per_m2: float | None
    speed_m_s: float | None


def _mean(values) -> float | None:
    values = np.asarray(values, float)
    values = values[np.isfinite(values)]
    return float(values.mean()) if values.size else None


def _area_series(pedpy, traj, speeds, polygon) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frames (f,), classic density (f,) [1/m²] and mean speed (f,) [m/s] (NaN where
    nobody is inside) in ``polygon``."""
    area = pedpy.MeasurementArea(polygon)
    dens = pedpy.compute_classic_density(traj_data=traj, measurement_area=area)
    frames = dens.index.to_numpy() if "frame" not in dens else dens["frame"].to_numpy()
    density = dens["density"].to_numpy(float)
    speed = np.full(frames.size, np.nan)
    mean = pedpy.compute_mean_speed_per_frame(traj_data=traj, individual_speed=speeds,
                                              measurement_area=area)
    if len(mean):
        got = mean.index.to_numpy() if "frame" not in mean else mean["frame"].to_numpy()
        pos = np.searchsorted(frames, got)
        ok = (pos < frames.size) & (frames[np.minimum(pos, frames.size - 1)] == got)
        speed[pos[ok]] = mean["speed"].to_numpy(float)[ok]
    speed[density <= 0] = np.nan
    return frames, density, speed


def _plot(path: Path, title: str, t: np.ndarray, panels: list[tuple[str, np.ndarray]]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(panels), 1, figsize=(7, 2.2 * len(panels)), sharex=True)
    for ax, (label, y) in zip(np.atleast_1d(axes), panels, strict=True):
        ax.plot(t, y, lw=1.2)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[-1].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _write_csv(path: Path, header: str, columns: list[np.ndarray]) -> None:
    np.savetxt(path, np.column_stack(columns), delimiter=",", header=header, comments="",
               fmt="%.6g")


def analyse_run(run_dir, measurement=None, *, speed_window: float = 1.0,
                plots: bool = True) -> dict:
    """Analyse the measurement lines and areas of a run folder into ``analysis/``.

    Parameters
    ----------
    run_dir : path
        Run folder written by ``crowdwalk run``.
    measurement : crowdwalk.behaviours.MeasurementSpec or None
        Default: the ``measurement`` section of the run's ``scenario.yaml``.
    speed_window : float
        Time window of the individual speeds [s].
    plots : bool
        Write the PNG figures.

    Returns
    -------
    dict
        ``{"lines": [LineFigures as dict], "areas": [AreaFigures as dict]}``.
    """
    import pedpy

    from crowdwalk.record import open_run
    from crowdwalk.scenario import parse_scenario

    run = open_run(run_dir)
    if measurement is None:
        measurement = parse_scenario(run.scenario_path.read_text(encoding="utf-8"),
                                     str(run.scenario_path)).measurement
    if not measurement.lines and not measurement.areas:
        raise invalid("analyse", "measurement", "a scenario with measurement lines or areas",
                      str(run.scenario_path))
    out = Path(run_dir) / "analysis"
    out.mkdir(exist_ok=True)
    traj = pedpy.load_trajectory_from_jupedsim_sqlite(trajectory_file=run.trajectory_path)
    fps = float(traj.frame_rate)
    speeds = pedpy.compute_individual_speed(
        traj_data=traj, frame_step=max(1, int(round(0.5 * speed_window * fps))),
        speed_calculation=pedpy.SpeedCalculation.BORDER_SINGLE_SIDED)
    areas = []
    for spec in measurement.areas:
        frames, density, speed = _area_series(pedpy, traj, speeds, spec.polygon)
        t = frames / fps
        _write_csv(out / f"area_{spec.name}.csv", "time_s,density_per_m2,speed_m_s",
                   [t, density, speed])
        if plots:
            _plot(out / f"area_{spec.name}.png", f"area {spec.name}", t,
                  [("density [1/m²]", density), ("speed [m/s]", speed)])
        occupied = density > 0
        areas.append(AreaFigures(spec.name, _mean(density[occupied]),
                                 float(density.max()) if density.size else None,
                                 _mean(speed)))
    lines = []
    for spec in measurement.lines:
        import shapely

        line = pedpy.MeasurementLine(list(spec.line))
        nt, crossing = pedpy.compute_n_t(traj_data=traj, measurement_line=line)
        strip = shapely.LineString(spec.line).buffer(STRIP_DEPTH / 2, cap_style="flat")
        frames, density, speed = _area_series(pedpy, traj, speeds,
                                              list(strip.exterior.coords)[:-1])
        crossed = np.zeros(frames.size)
        if len(nt):
            nt_frames = nt.index.to_numpy() if "frame" not in nt else nt["frame"].to_numpy()
            counts = nt["cumulative_pedestrians"].to_numpy(float)
            idx = np.searchsorted(nt_frames, frames, side="right") - 1
            crossed = np.where(idx >= 0, counts[np.maximum(idx, 0)], 0.0)
        t = frames / fps
        _write_csv(out / f"line_{spec.name}.csv", "time_s,crossed,density_per_m2,speed_m_s",
                   [t, crossed, density, speed])
        if plots:
            _plot(out / f"line_{spec.name}.png", f"line {spec.name}", t,
                  [("crossed [-]", crossed), ("density [1/m²]", density),
                   ("speed [m/s]", speed)])
        times = np.sort(crossing["frame"].to_numpy(float)) / fps if len(crossing) else []
        n = len(times)
        flow = (float((n - 1) / (times[-1] - times[0])) if n >= 2 and times[-1] > times[0]
                else None)
        occupied = density > 0
        lines.append(LineFigures(spec.name, n, flow, _mean(density[occupied]), _mean(speed)))
    result = {"lines": [asdict(x) for x in lines], "areas": [asdict(x) for x in areas]}
    (out / "measurement.json").write_text(json.dumps(result, indent=2))
    if run.summary_path.exists():
        summary = run.summary
        summary["measurement"] = result
        run.summary_path.write_text(json.dumps(summary, indent=2))
    return result
