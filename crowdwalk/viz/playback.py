"""Playback state of the viewer: current time, play/pause, single steps, speed.

Pure Python (no pyvista) so the viewer's key bindings can be tested without a window.
"""

from __future__ import annotations

from dataclasses import dataclass

from crowdwalk.errors import invalid

__all__ = ["Playback"]


@dataclass
class Playback:
    """Simulated-time cursor.

    Parameters
    ----------
    start, end : float
        Time range of the run [s].
    frame_dt : float
        Output frame interval, the size of a single step [s].
    speed : float
        Simulated seconds per wall-clock second while playing.
    loop : bool
        Start again at ``start`` after ``end`` instead of pausing.
    """

    start: float
    end: float
    frame_dt: float
    speed: float = 1.0
    loop: bool = True
    playing: bool = False
    time: float | None = None

    MIN_SPEED = 1 / 16
    MAX_SPEED = 16.0

    def __post_init__(self) -> None:
        if not self.end >= self.start:
            raise invalid("Playback", "end", f">= start = {self.start} [s]", self.end)
        if not self.frame_dt > 0:
            raise invalid("Playback", "frame_dt", "> 0 [s]", self.frame_dt)
        if not self.MIN_SPEED <= self.speed <= self.MAX_SPEED:
            raise invalid("Playback", "speed", f"in [{self.MIN_SPEED}, {self.MAX_SPEED}]",
                          self.speed)
        self.time = self.start if self.time is None else self.clamp(self.time)

    def clamp(self, t: float) -> float:
        """``t`` limited to the run's time range [s]."""
        return min(max(float(t), self.start), self.end)

    def seek(self, t: float) -> float:
        """Jump to time ``t`` [s] (clamped); returns the new time."""
        self.time = self.clamp(t)
        return self.time

    def toggle(self) -> bool:
        """Play or pause; playing from the end restarts at the start. Returns ``playing``."""
        self.playing = not self.playing
        if self.playing and self.time >= self.end:
            self.time = self.start
        return self.playing

    def step(self, frames: int = 1) -> float:
        """Pause and move by whole output frames (negative goes back); returns the time."""
        self.playing = False
        return self.seek(self.time + frames * self.frame_dt)

    def faster(self) -> float:
        """Double the playback speed (up to ``MAX_SPEED``)."""
        self.speed = min(self.speed * 2.0, self.MAX_SPEED)
        return self.speed

    def slower(self) -> float:
        """Halve the playback speed (down to ``MIN_SPEED``)."""
        self.speed = max(self.speed / 2.0, self.MIN_SPEED)
        return self.speed

    def advance(self, wall_dt: float) -> float:
        """Advance by ``wall_dt`` wall-clock seconds when playing; returns the time [s]."""
        if not self.playing:
            return self.time
        t = self.time + self.speed * wall_dt
        if t > self.end:
            if self.loop and self.end > self.start:
                t = self.start + (t - self.start) % (self.end - self.start)
            else:
                t, self.playing = self.end, False
        self.time = t
        return t
