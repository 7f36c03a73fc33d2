"""Conventions every ``crowdwalk`` command follows at its edges.

- An output folder that already holds files is refused unless ``--overwrite``.
- A run folder without ``summary.json`` is an incomplete run (killed before it could write
  one); readers say so and go on with what was flushed.
- A time outside the run is an error, not silently clamped.
- A command that writes names what and where, and the command to run next.
"""

from __future__ import annotations

from pathlib import Path

from crowdwalk.errors import InputError, invalid

__all__ = ["check_out_folder", "incomplete_note", "check_time", "next_hint"]


def check_out_folder(out: Path, overwrite: bool, command: str) -> None:
    """Refuse ``out`` when it is a file, or a folder with files in it and no ``overwrite``."""
    if out.exists() and not out.is_dir():
        raise InputError(f"{command} --out must be a folder; got the file {out}.")
    if not overwrite and out.is_dir() and any(out.iterdir()):
        raise InputError(f"{command} --out must be an empty or new folder; got {out}, which "
                         "has files in it (add --overwrite to replace its run files).")


def incomplete_note(path: Path) -> str | None:
    """The warning for a run folder that has trajectories but no ``summary.json``."""
    from crowdwalk.record import open_run

    if not path.is_dir() or not (path / "trajectories.sqlite").exists():
        return None
    run = open_run(path)
    if run.complete:
        return None
    try:
        tr = run.trajectories()
        written = f"{tr.frame.max() / tr.fps:.1f} s" if len(tr.frame) else "no frame"
    except Exception:  # noqa: BLE001 - a database damaged beyond its journal
        written = "an unknown time"
    return (f"{path} is an incomplete run (no summary.json: the run was killed before it "
            f"finished); showing what it wrote, {written} of simulation.")


def check_time(value: float | None, time_range: tuple[float, float], *, option: str,
               command: str) -> None:
    """``value`` [s] of ``command``'s ``--option`` must lie inside the run's ``time_range``."""
    if value is None:
        return
    t0, t1 = time_range
    if not t0 - 1e-6 <= value <= t1 + 1e-6:
        raise invalid(command, option, f"within the run's time range [{t0:g}, {t1:g}] [s]",
                      value)


def next_hint(*commands: str) -> str:
    """``"next: A  or  B"``."""
    return "next: " + "  or  ".join(f"`{c}`" for c in commands)
