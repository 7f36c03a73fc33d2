"""Footprints: every foot placement of a run as one mesh of flat foot outlines.

The outlines are built with numpy (one small polygon per placement, turned to the
walking direction), sorted by time, so the footprints placed in a time window are a
contiguous run of triangles: moving the time slider only re-slices the cell array.
Point scalars ``energy`` [J/kg], ``planner`` (category code) and ``agent`` colour them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid

__all__ = ["COARSE_ABOVE", "Footsteps", "FootprintMesh", "foot_outline", "walking_headings"]

COLOR_FIELDS = ("energy", "planner", "agent")


COARSE_ABOVE = 20_000
"""Footprint count above which each outline is a 2-triangle quad instead of 6 triangles."""


def foot_outline(
    heel: float = 0.06, toe: float = 0.20, width: float = 0.10, coarse: bool = False
) -> np.ndarray:
    """Sole outline (V,2) in the foot frame [m]: x forward from the ankle, y to the left;
    a convex polygon starting at the heel.

    Parameters
    ----------
    heel, toe : float
        Distance of the heel behind and the toe ahead of the ankle [m].
    width : float
        Width across the ball of the foot [m].
    coarse : bool
        A tapered quad (4 vertices) instead of the 8-vertex sole, for very many footprints.
    """
    if coarse:
        x = np.array([-heel, 0.85 * toe, 0.85 * toe, -heel])
        y = 0.5 * width * np.array([0.7, 0.95, -0.95, -0.7])
        return np.column_stack([x, y])
    x = np.array([-heel, -0.8 * heel, 0.3 * toe, 0.8 * toe, toe, 0.8 * toe, 0.3 * toe, -0.8 * heel])
    y = 0.5 * width * np.array([0.0, 0.75, 0.95, 0.8, 0.0, -0.8, -0.95, -0.75])
    return np.column_stack([x, y])


def walking_headings(agent: np.ndarray, time: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Walking direction at each foot placement from the agent's neighbouring placements.

    The central difference between the previous and next placement of the same agent
    cancels the left/right alternation of the feet; the first and last placements use
    one-sided differences; an agent with a single placement gets heading 0.

    Parameters
    ----------
    agent : (n,) int
        Agent id of each placement.
    time : (n,) float
        Placement time [s].
    xy : (n, 2) float
        Foothold position [m].

    Returns
    -------
    (n,) float
        Heading ψ from +x [rad].
    """
    n = len(agent)
    order = np.lexsort((time, agent))
    a, p = np.asarray(agent)[order], np.asarray(xy, dtype=float)[order]
    same_prev = np.r_[False, a[1:] == a[:-1]]
    same_next = np.r_[a[1:] == a[:-1], False]
    idx = np.arange(n)
    prev_i = np.where(same_prev, idx - 1, idx)
    next_i = np.where(same_next, np.minimum(idx + 1, n - 1), idx)
    d = p[next_i] - p[prev_i]
    heading_sorted = np.where(np.hypot(d[:, 0], d[:, 1]) > 1e-9, np.arctan2(d[:, 1], d[:, 0]), 0.0)
    heading = np.empty(n)
    heading[order] = heading_sorted
    return heading


@dataclass(frozen=True)
class Footsteps:
    """Foot placements of a run, struct of arrays (one row of ``footsteps.csv`` each).

    Parameters
    ----------
    agent : (n,) int
        Agent id.
    time : (n,) float
        Time the foot is placed [s].
    position : (n, 3) float
        Foothold (ground point below the ankle), world frame [m].
    energy : (n,) float
        Energy of the step that ends here [J/kg] (Eq. 4).
    planner : (n,) str
        Planner that chose the foothold.
    heading : (n,) float, optional
        Walking direction [rad]; derived from neighbouring placements when omitted.
    """

    agent: np.ndarray
    time: np.ndarray
    position: np.ndarray
    energy: np.ndarray
    planner: np.ndarray
    heading: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.agent)
        position = np.asarray(self.position, dtype=float).reshape(-1, 3)
        for name in ("time", "energy", "planner"):
            size = len(getattr(self, name))
            if size != n:
                raise invalid("Footsteps", name, f"of length {n} like agent", size)
        if len(position) != n:
            raise invalid("Footsteps", "position", f"shaped ({n}, 3) [m]", np.shape(self.position))
        object.__setattr__(self, "position", position)
        object.__setattr__(self, "agent", np.asarray(self.agent, dtype=np.int64))
        object.__setattr__(self, "time", np.asarray(self.time, dtype=float))
        object.__setattr__(self, "energy", np.asarray(self.energy, dtype=float))
        object.__setattr__(self, "planner", np.asarray(self.planner).astype(str))
        if self.heading is None:
            heading = walking_headings(self.agent, self.time, position[:, :2])
            object.__setattr__(self, "heading", heading)

    def __len__(self) -> int:
        return len(self.agent)

    @classmethod
    def empty(cls) -> Footsteps:
        """No placements."""
        return cls(np.zeros(0, int), np.zeros(0), np.zeros((0, 3)), np.zeros(0), np.zeros(0, str))

    @classmethod
    def from_table(cls, table) -> Footsteps:
        """From a mapping of columns (a pandas DataFrame or dict of arrays).

        Needs the columns ``agent, time, x, y, z, energy, planner``; uses ``heading``
        [rad] when present.
        """
        needed = ("agent", "time", "x", "y", "z", "energy", "planner")
        missing = [c for c in needed if c not in table]
        if missing:
            constraint = f"a table with the columns {','.join(needed)}"
            raise invalid("Footsteps", "columns", constraint, missing)
        position = np.column_stack([np.asarray(table[c], dtype=float) for c in ("x", "y", "z")])
        heading = np.asarray(table["heading"], dtype=float) if "heading" in table else None
        return cls(
            np.asarray(table["agent"]),
            np.asarray(table["time"], dtype=float),
            position,
            np.asarray(table["energy"], dtype=float),
            np.asarray(table["planner"]),
            heading,
        )


@dataclass
class FootprintMesh:
    """All footprints in one mesh; :meth:`show_window` picks those placed in a time window.

    Parameters
    ----------
    steps : Footsteps
        The run's foot placements.
    lift : float
        Height of the outline above the foothold, against z-fighting [m].
    coarse : bool, optional
        Quad outlines; by default when there are more than ``COARSE_ABOVE`` footprints.
    """

    steps: Footsteps
    lift: float = 0.006
    coarse: bool | None = None
    mesh: pv.PolyData = field(init=False, repr=False)

    def __post_init__(self) -> None:
        order = np.argsort(self.steps.time, kind="stable")
        self.times = self.steps.time[order]
        if self.coarse is None:
            self.coarse = len(self.steps) > COARSE_ABOVE
        outline = foot_outline(coarse=self.coarse)
        v = len(outline)
        heading = self.steps.heading[order]
        c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]
        pos = self.steps.position[order]
        x = pos[:, :1] + c * outline[None, :, 0] - s * outline[None, :, 1]
        y = pos[:, 1:2] + s * outline[None, :, 0] + c * outline[None, :, 1]
        z = np.broadcast_to(pos[:, 2:3] + self.lift, x.shape)
        points = np.stack([x, y, z], axis=-1).reshape(-1, 3)
        fan = np.column_stack([np.zeros(v - 2, int), np.arange(1, v - 1), np.arange(2, v)])
        tris = (fan[None] + (v * np.arange(len(pos)))[:, None, None]).reshape(-1, 3)
        self._faces = np.column_stack([np.full(len(tris), 3), tris]).ravel()
        self._cells_per_step = len(fan)
        self.planners = sorted(set(self.steps.planner.tolist()))
        code = {name: i for i, name in enumerate(self.planners)}
        planner_code = np.array([code[p] for p in self.steps.planner[order]], dtype=float)
        self.mesh = pv.PolyData(points.astype(np.float32), faces=self._faces)
        for name, values in (
            ("energy", self.steps.energy[order]),
            ("planner", planner_code),
            ("agent", self.steps.agent[order].astype(float)),
        ):
            self.mesh.point_data[name] = np.repeat(values, v).astype(np.float32)
        self.window = (0, len(pos))

    def show_window(self, start: float, end: float) -> int:
        """Keep only the footprints placed in ``[start, end]`` [s]; returns how many."""
        lo = int(np.searchsorted(self.times, start, side="left"))
        hi = int(np.searchsorted(self.times, end, side="right"))
        if (lo, hi) != self.window:
            width = 4 * self._cells_per_step
            self.mesh.faces = self._faces[lo * width : hi * width]
            self.window = (lo, hi)
        return hi - lo
