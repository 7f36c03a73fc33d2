"""Walking speeds along the true 3-D path: PedPy's individual speeds plus the height.

PedPy reads a run's ``trajectories.sqlite`` but ignores the extra ``trajectory_z`` table,
so its speeds on stairs and slopes are horizontal. Over the very same frame window PedPy
uses (``BORDER_SINGLE_SIDED``: ±``frame_step`` frames, one-sided at a trajectory's ends) the
height change Δz is taken from ``trajectory_z``, and the speed along the path is

    v_3d = sqrt(v_pedpy² + (Δz / Δt)²)                                       [m/s]

:func:`walking_speeds` returns the table, :func:`write_walking_speeds` writes it to
``RUN/analysis/speeds_3d.csv`` (``crowdwalk analyse`` calls it).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["WalkingSpeeds", "walking_speeds", "write_walking_speeds", "SLOPED_GRADE"]

#: |vertical / horizontal speed| above which a sample counts as on stairs or a slope [-].
SLOPED_GRADE = 0.05


@dataclass(frozen=True)
class WalkingSpeeds:
    """Per trajectory row (n,): ``id``, ``frame``, ``time`` [s], PedPy's horizontal speed
    ``speed_xy`` [m/s], the vertical speed ``speed_z`` [m/s] over the same window, and the
    speed along the 3-D path ``speed_3d`` [m/s]."""

    id: np.ndarray
    frame: np.ndarray
    time: np.ndarray
    speed_xy: np.ndarray
    speed_z: np.ndarray
    speed_3d: np.ndarray

    @property
    def sloped(self) -> np.ndarray:
        """Rows on stairs or a slope (n,) bool (|speed_z| > SLOPED_GRADE · speed_xy)."""
        return np.abs(self.speed_z) > SLOPED_GRADE * np.maximum(self.speed_xy, 1e-9)


def _window(frame: np.ndarray, agent: np.ndarray, step: int) -> tuple[np.ndarray, np.ndarray]:
    """Row indices (n,), (n,) of the window ends PedPy's single-sided speeds use: ``step``
    rows back and ahead, each end the row itself where the trajectory has no such row. Rows
    are sorted by agent then frame, frames consecutive per agent."""
    n = frame.size
    i = np.arange(n)
    start = np.maximum.accumulate(np.where(np.r_[True, agent[1:] != agent[:-1]], i, 0))
    end = np.minimum.accumulate(
        np.where(np.r_[agent[1:] != agent[:-1], True], i, n - 1)[::-1])[::-1]
    return np.where(i - step >= start, i - step, i), np.where(i + step <= end, i + step, i)


def walking_speeds(run_dir, *, speed_window: float = 1.0) -> WalkingSpeeds:
    """PedPy's individual speeds of a run over ``speed_window`` [s], with the height.

    Parameters
    ----------
    run_dir : path
        Run folder written by ``crowdwalk run``.
    speed_window : float
        Time window of the speeds [s] (PedPy's ``frame_step`` = window / 2 · fps).
    """
    import pedpy

    from crowdwalk.record import open_run

    run = open_run(run_dir)
    traj = pedpy.load_trajectory_from_jupedsim_sqlite(trajectory_file=run.trajectory_path)
    fps = float(traj.frame_rate)
    step = max(1, int(round(0.5 * speed_window * fps)))
    ped = pedpy.compute_individual_speed(
        traj_data=traj, frame_step=step,
        speed_calculation=pedpy.SpeedCalculation.BORDER_SINGLE_SIDED)
    ped = ped.sort_values(["id", "frame"])
    rows = run.trajectories()
    order = np.lexsort((rows.frame, rows.id))
    agent, frame, z = rows.id[order], rows.frame[order], rows.z[order]
    lo, hi = _window(frame, agent, step)
    dt = np.maximum(frame[hi] - frame[lo], 1) / fps
    speed_z = (z[hi] - z[lo]) / dt
    key = agent.astype(np.int64) * (1 << 32) + frame
    ped_key = ped["id"].to_numpy(np.int64) * (1 << 32) + ped["frame"].to_numpy(np.int64)
    speed_xy = np.full(frame.size, np.nan)
    pos = np.searchsorted(key, ped_key)
    speed_xy[pos] = ped["speed"].to_numpy(float)
    return WalkingSpeeds(id=agent, frame=frame, time=frame / fps, speed_xy=speed_xy,
                         speed_z=speed_z, speed_3d=np.hypot(speed_xy, speed_z))


def write_walking_speeds(run_dir, *, speed_window: float = 1.0) -> str:
    """Write ``analysis/speeds_3d.csv``; one line saying what it holds."""
    s = walking_speeds(run_dir, speed_window=speed_window)
    out = Path(run_dir) / "analysis"
    out.mkdir(exist_ok=True)
    path = out / "speeds_3d.csv"
    np.savetxt(path, np.column_stack([s.id, s.frame, s.time, s.speed_xy, s.speed_z,
                                      s.speed_3d]),
               delimiter=",", header="id,frame,time_s,speed_xy_pedpy_m_s,speed_z_m_s,"
               "speed_3d_m_s", comments="", fmt=["%d", "%d", "%.4f", "%.5g", "%.5g", "%.5g"])
    on = s.sloped
    text = (f"wrote {path}: speeds along the 3-D path, mean {np.nanmean(s.speed_3d):.3f} m/s "
            f"(PedPy, horizontal: {np.nanmean(s.speed_xy):.3f} m/s)")
    if on.any():
        a, b = np.nanmean(s.speed_3d[on]), np.nanmean(s.speed_xy[on])
        text += (f"; on stairs and slopes ({on.sum()} samples) {a:.3f} m/s vs {b:.3f} m/s "
                 f"horizontal (+{100 * (a / b - 1):.1f} %)")
    return text + "."
