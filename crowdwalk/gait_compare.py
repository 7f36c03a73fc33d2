"""Gait engines against people (``crowdwalk gait-compare``).

The same lone walker (level 40 m strip, body height 1.75 m, planner ``best_first``) is
run through :func:`crowdwalk.crowd.run.run_scenario` — what ``crowdwalk run`` does — once
per gait engine and free speed, and each run is measured from its output by
:func:`crowdwalk.gait_report.run_figures` (hip/knee/ankle against Winter 1991 at the
walker's cadence, step length and cadence against the WBDS normal-mode relation).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["SPEEDS", "CompareRow", "lone_walker_yaml", "run_comparison", "comparison_table",
           "plot_comparison"]

SPEEDS = (1.0, 1.33, 1.7)
"""Free speeds of the comparison [m/s] (the issue's slow, natural and fast walkers)."""


def lone_walker_yaml(*, speed: float, gait: str, body_height: float = 1.75,
                     duration: float = 14.0, fps: int = 50, seed: int = 1) -> str:  # fmt: skip
    """The scenario of one walker on a level 40 m strip at ``speed`` [m/s] with ``gait``."""
    return f"""\
name: gait_compare_{gait}_{speed:g}
description: One walker on level ground (crowdwalk gait-compare).
terrain:
  extent: [-1, -2, 41, 2]
  base: 0.0
routes:
  nodes:
    - {{name: start, xy: [1.0, 0.0], area: [[0.5, -0.5], [1.5, -0.5], [1.5, 0.5], [0.5, 0.5]]}}
    - {{name: end, xy: [38.0, 0.0]}}
  edges:
    - {{from: start, to: end, width: 3.0}}
groups:
  - name: walker
    count: 1
    spawn: start
    destinations: [end]
    body_height: {{mean: {body_height}, sd: 0.0}}
    free_speed: {{mean: {speed}, sd: 0.0}}
    planner: best_first
    gait: {gait}
simulation:
  duration: {duration}
  seed: {seed}
  dt: 0.04
  fps: {fps}
outputs:
  poses: true
"""


@dataclass(frozen=True)
class CompareRow:
    """One engine at one free speed: its run folder and the walker's gait figures."""

    engine: str
    free_speed: float
    run_dir: Path
    figures: object  # crowdwalk.gait_report.GaitFigures


def run_comparison(out_dir: str | Path, *, engines: tuple[str, ...],
                   speeds: tuple[float, ...] = SPEEDS,
                   progress=None) -> list[CompareRow]:  # fmt: skip
    """Run every (engine, speed) lone walker into ``out_dir/<engine>_<speed>/`` and measure it."""
    from crowdwalk.crowd.run import run_scenario
    from crowdwalk.gait_report import run_figures

    out = Path(out_dir)
    rows = []
    for engine in engines:
        for speed in speeds:
            folder = out / f"{engine}_{speed:g}"
            folder.mkdir(parents=True, exist_ok=True)
            scenario = folder / "scenario_in.yaml"
            scenario.write_text(lone_walker_yaml(speed=speed, gait=engine), encoding="utf-8")
            run_dir = folder / "run"
            run_scenario(scenario, run_dir)
            (fig,) = run_figures(run_dir)
            rows.append(CompareRow(engine, speed, run_dir, fig))
            if progress is not None:
                progress(engine, speed)
    return rows


def comparison_table(rows: list[CompareRow]) -> str:
    """A Markdown table: per engine and speed, joint RMS / r against Winter and the
    step length and cadence against WBDS at the achieved speed."""
    from planners import normal_mode

    head = ("| engine | v free | v [m/s] | step [m] (WBDS) | cadence [/min] (WBDS) | "
            "hip RMS° / r | knee RMS° / r | ankle RMS° / r |")
    lines = [head, "|" + "---|" * 8]
    for row in rows:
        f = row.figures
        leg = float(normal_mode.leg_length_from_height(f.body_height))
        ok = np.isfinite(f.speed)
        sl_ref = float(normal_mode.step_length(f.speed, leg)) if ok else np.nan
        cad_ref = 60.0 * float(normal_mode.step_frequency(f.speed, leg)) if ok else np.nan
        joints = " | ".join(f"{f.joint_rms[j]:.1f} / {f.joint_r[j]:.2f}" for j in range(3))
        lines.append(f"| {row.engine} | {row.free_speed:g} | {f.speed:.2f} | "
                     f"{f.step_length:.2f} ({sl_ref:.2f}) | {f.cadence:.0f} ({cad_ref:.0f}) | "
                     f"{joints} |")  # fmt: skip
    return "\n".join(lines)


def plot_comparison(rows: list[CompareRow], path: str | Path) -> Path:
    """Hip, knee, ankle level-cycle curves of every engine and speed with Winter's mean ± SD
    at each walker's cadence (one PNG, a row per speed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crowdwalk.gait_report import SAMPLES, winter_at

    speeds = sorted({r.free_speed for r in rows})
    engines = list(dict.fromkeys(r.engine for r in rows))
    x = np.linspace(0, 100, SAMPLES)
    fig, axes = plt.subplots(len(speeds), 3, figsize=(12, 3.0 * len(speeds)), squeeze=False)
    for i, speed in enumerate(speeds):
        here = [r for r in rows if r.free_speed == speed]
        cadence = np.nanmean([r.figures.cadence for r in here])
        ref, sd = winter_at(cadence) if np.isfinite(cadence) else (None, None)
        for j, name in enumerate(("hip flexion", "knee flexion", "ankle dorsiflexion")):
            ax = axes[i, j]
            if ref is not None:
                ax.fill_between(x, ref[j] - sd[j], ref[j] + sd[j], color="0.85",
                                label="Winter ± SD")  # fmt: skip
                ax.plot(x, ref[j], color="k", lw=1)
            for r in here:
                ax.plot(x, r.figures.level_curves[j], lw=1.5,
                        label=r.engine, color=f"C{engines.index(r.engine)}")  # fmt: skip
            ax.set_title(f"{name}, {speed:g} m/s")
            ax.set_xlabel("% stride")
            ax.set_ylabel("deg")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
