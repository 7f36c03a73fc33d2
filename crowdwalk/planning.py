"""The ``crowdwalk plan`` command: read an ``s,z`` profile CSV and walk or plan on it.

By default the walker walks the whole profile by receding horizon
(:func:`planners.walk.walk`); ``horizon=True`` plans one horizon from ``s = 0``.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from crowdwalk.errors import InputError, invalid

__all__ = ["read_profile_csv", "plan_profile", "format_plan"]


def read_profile_csv(path: str | Path):
    """Read a ground profile from a CSV file with columns ``s,z`` [m].

    A header row naming the columns ``s`` and ``z`` is optional (other columns are
    ignored when there is a header). Rows are piecewise-linear vertices; a vertical
    height change is two rows with the same ``s``. Blank lines and lines starting with
    ``#`` are skipped.

    Returns
    -------
    planners.GroundProfile

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        A row is not two numbers, or the profile is invalid (empty, NaN, unsorted).
    """
    from planners import GroundProfile

    path = Path(path)
    with path.open(newline="", encoding="utf-8") as handle:
        rows = [(i + 1, row) for i, row in enumerate(csv.reader(handle))
                if row and any(cell.strip() for cell in row)
                and not row[0].strip().startswith("#")]
    cols = (0, 1)
    if rows:
        line, cells = rows[0]
        header = [cell.strip().lower() for cell in cells]
        if not _is_number(header[0]):
            if "s" not in header or "z" not in header:
                raise _at(path, line, "header", "columns named s and z", ",".join(header))
            cols = (header.index("s"), header.index("z"))
            rows = rows[1:]
    if len(rows) < 2:
        raise _at(path, rows[-1][0] if rows else 1, "rows", "at least two s,z rows", len(rows))
    s, z = [], []
    for line, row in rows:
        try:
            s_i, z_i = float(row[cols[0]]), float(row[cols[1]])
        except (IndexError, ValueError):
            raise _at(path, line, "s,z", "two numbers [m]", ",".join(row)) from None
        if not (math.isfinite(s_i) and math.isfinite(z_i)):
            raise _at(path, line, "s,z", "finite [m]", ",".join(row))
        if s and s_i < s[-1]:
            raise _at(path, line, "s", f"non-decreasing (previous row {s[-1]:g}) [m]", s_i)
        s.append(s_i)
        z.append(z_i)
    return GroundProfile(np.array(s), np.array(z))


def _at(path: Path, line: int, field: str, constraint: str, value: object) -> InputError:
    """One-line error naming ``path:line``, the field, its constraint and the value."""
    return InputError(f"{path}:{line}: profile {field} must be {constraint}; got {value!r}.")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def plan_profile(profile_path: str | Path, planner: str = "best_first_multistart",
                 body_height: float = 1.75, speed: float = 1.34, plot: str | Path | None = None,
                 *, horizon: bool = False):
    """Walk (or, with ``horizon``, plan one horizon) on the profile in ``profile_path``.

    The walker, ``body_height`` [m] tall at ``speed`` [m/s], starts with its stance foot
    at ``s = 0``. Returns the :class:`planners.Plan` (for a walk, every step taken); with
    ``plot`` also writes the plan plot (PNG). A profile ending less than one neutral step
    beyond ``s = 0`` is bad input.
    """
    from planners import PLANNERS, Leg, ProfileError, plan
    from planners.walk import walk

    if planner not in PLANNERS:
        raise invalid("plan", "planner", f"one of {', '.join(sorted(PLANNERS))}", planner)
    if not (math.isfinite(body_height) and 0.5 <= body_height <= 2.5):
        raise invalid("plan", "body_height", "in [0.5, 2.5] [m]", body_height)
    if not (math.isfinite(speed) and 0 < speed <= 3):
        raise invalid("plan", "speed", "in (0, 3] [m/s]", speed)
    profile = read_profile_csv(profile_path)
    leg = Leg.from_body_height(body_height)
    if horizon:
        result = plan(profile, leg, speed, planner)
    else:
        try:
            result = walk(profile, leg, speed, planner)
        except ProfileError as err:
            raise InputError(f"{profile_path}: {err}") from None
    if plot is not None:
        from crowdwalk.plots import plot_plan

        plot_plan(profile, result, plot, title=f"{Path(profile_path).name}: {planner}")
    return result


def format_plan(result, as_json: bool = False) -> str:
    """The plan as one JSON object or as a short human-readable table."""
    if as_json:
        return json.dumps(result.to_dict())
    lines = [f"status: {result.message or result.status}"]
    lines.append(f"{'step':>4} {'s [m]':>8} {'z [m]':>7} {'length':>7} {'rise':>6} "
                 f"{'E [J/kg]':>9} {'time [s]':>8}")
    lines.append(f"{0:>4} {result.footholds_s[0]:>8.3f} {result.footholds_z[0]:>7.3f}")
    for i in range(result.step_lengths.size):
        lines.append(
            f"{i + 1:>4} {result.footholds_s[i + 1]:>8.3f} {result.footholds_z[i + 1]:>7.3f} "
            f"{result.step_lengths[i]:>7.3f} {result.step_heights[i]:>+6.3f} "
            f"{result.E[i]:>9.3f} {result.phase_durations[i].sum():>8.3f}")
    if result.step_lengths.size:
        lines.append(f"energy {result.energy_total:.3f} J/kg over {result.distance:.3f} m = "
                     f"{result.energy_per_metre:.3f} J/(kg m); efficiency "
                     f"{result.efficiency:.4f} m kg/J")
    st = result.stats
    plans = f"{st['plans']} plans, " if "plans" in st else ""
    lines.append(f"search: {plans}{st['nodes_expanded']} nodes expanded, "
                 f"{st['legality_checks']} legality checks, {st['lattice_steps']} lattice "
                 f"steps ({st['key_frame_solves']} key-frame solves), {st['swing_curves']} "
                 f"swing curves built ({st['swing_adjustments']} adjustments, "
                 f"{st['swing_curves_reused']} reused), {1e3 * st['time_s']:.1f} ms")
    return "\n".join(lines)
