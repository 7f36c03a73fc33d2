"""Footprints: every foot placement of a run as one mesh of flat foot outlines.

The outlines are built with numpy (one small polygon per placement, turned to the
walking direction, laid in the ground's tangent plane), sorted by time, so the
footprints placed in a time window are a contiguous run of triangles: moving the time
slider only re-slices the cell array. No z-fighting: each outline is lifted along the
ground normal, later ones a little more than earlier ones (so overlapping footprints
stack in time order). Colours are direct RGB point scalars (``"rgb"``) that fade towards
a light grey with the footprint's age.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid

__all__ = ["COARSE_ABOVE", "COLOR_FIELDS", "FADED", "Footsteps", "FootprintMesh", "foot_outline",
           "walking_headings"]

COLOR_FIELDS = ("energy", "group", "planner", "style", "agent")


FADED = np.array([236, 236, 232], dtype=float)
"""The colour old footprints fade towards (RGB 0-255)."""

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
    group : (n,) str, optional
        Group of the walker.
    step_length : (n,) float, optional
        Length of the step that ends here [m].
    """

    agent: np.ndarray
    time: np.ndarray
    position: np.ndarray
    energy: np.ndarray
    planner: np.ndarray
    heading: np.ndarray | None = None
    group: np.ndarray | None = None
    step_length: np.ndarray | None = None

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
        for name, dtype in (("group", str), ("step_length", float)):
            value = getattr(self, name)
            if value is not None:
                if len(value) != n:
                    raise invalid("Footsteps", name, f"of length {n} like agent", len(value))
                object.__setattr__(self, name, np.asarray(value).astype(dtype))

    def __len__(self) -> int:
        return len(self.agent)

    @classmethod
    def empty(cls) -> Footsteps:
        """No placements."""
        return cls(np.zeros(0, int), np.zeros(0), np.zeros((0, 3)), np.zeros(0), np.zeros(0, str))

    @classmethod
    def from_table(cls, table) -> Footsteps:
        """From a :class:`~crowdwalk.steps.FootstepTable` (``Run.footsteps()``) or a
        mapping of columns (a pandas DataFrame or dict of arrays).

        Needs the columns ``agent, time, x, y, z, energy, planner``; uses ``heading``
        [rad], ``group`` and ``step_length`` [m] when present.
        """
        from crowdwalk.steps import FootstepTable

        if isinstance(table, FootstepTable):
            table = table.columns()
        needed = ("agent", "time", "x", "y", "z", "energy", "planner")
        missing = [c for c in needed if c not in table]
        if missing:
            constraint = f"a table with the columns {','.join(needed)}"
            raise invalid("Footsteps", "columns", constraint, missing)
        position = np.column_stack([np.asarray(table[c], dtype=float) for c in ("x", "y", "z")])
        optional = {c: np.asarray(table[c]) if c in table else None
                    for c in ("heading", "group", "step_length")}
        return cls(
            np.asarray(table["agent"]),
            np.asarray(table["time"], dtype=float),
            position,
            np.asarray(table["energy"], dtype=float),
            np.asarray(table["planner"]),
            **optional,
        )




@dataclass
class FootprintMesh:
    """All footprints in one mesh; :meth:`show_window` picks those placed in a time window
    and fades them with age.

    Parameters
    ----------
    steps : Footsteps
    normals : (n, 3) float, optional
        Unit ground normal at each foothold (vertical when omitted).
    lift : float
        Height of the outlines above the ground along its normal [m].
    stack : float
        Extra lift spread over the footprints in time order [m] (the last placed is
        highest).
    coarse : bool, optional
        Quads instead of 8-vertex soles (default: above :data:`COARSE_ABOVE` placements).
    """

    steps: Footsteps
    normals: np.ndarray | None = None
    lift: float = 0.008
    stack: float = 0.006
    coarse: bool | None = None
    mesh: pv.PolyData = field(init=False, repr=False)

    def __post_init__(self) -> None:
        order = np.argsort(self.steps.time, kind="stable")
        self.order = order
        self.times = self.steps.time[order]
        n = len(order)
        if self.coarse is None:
            self.coarse = n > COARSE_ABOVE
        outline = foot_outline(coarse=self.coarse)
        v = self.vertices_per_step = len(outline)
        normal = (np.tile([0.0, 0.0, 1.0], (n, 1)) if self.normals is None
                  else np.asarray(self.normals, dtype=float)[order])
        heading = self.steps.heading[order]
        c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]
        pos = self.steps.position[order]
        dx = c * outline[None, :, 0] - s * outline[None, :, 1]
        dy = s * outline[None, :, 0] + c * outline[None, :, 1]
        # in the tangent plane: n . (dx, dy, dz) = 0
        nz = np.maximum(normal[:, 2:3], 0.2)
        dz = -(normal[:, :1] * dx + normal[:, 1:2] * dy) / nz
        offset = self.lift + self.stack * (np.arange(n) / max(n - 1, 1))
        base = pos + offset[:, None] * normal
        points = np.stack([base[:, :1] + dx, base[:, 1:2] + dy, base[:, 2:3] + dz], axis=-1)
        fan = np.column_stack([np.zeros(v - 2, int), np.arange(1, v - 1), np.arange(2, v)])
        tris = (fan[None] + (v * np.arange(n))[:, None, None]).reshape(-1, 3)
        self._faces = np.column_stack([np.full(len(tris), 3), tris]).ravel()
        self._cells_per_step = len(fan)
        self.mesh = pv.PolyData(points.reshape(-1, 3).astype(np.float32), faces=self._faces)
        self.mesh.point_data["rgb"] = np.zeros((n * v, 3), np.uint8)
        self._base = np.zeros((n, 3))
        self._fade: tuple[float, int, int] | None = None  # (fade, faded up to, written up to)
        self.window = (0, n)

    def set_colors(self, colors: np.ndarray) -> None:
        """Colour of each placement (n, 3) uint8, in the order of ``steps``."""
        self._base = np.asarray(colors, dtype=float).reshape(-1, 3)[self.order]
        self._fade = None
        self._paint(0, len(self._base), np.zeros(len(self._base)))

    def _paint(self, lo: int, hi: int, age_fraction: np.ndarray) -> None:
        """Write the colours of placements lo..hi-1 faded by ``age_fraction`` (hi-lo,)."""
        if hi <= lo:
            return
        f = 0.8 * np.clip(age_fraction, 0.0, 1.0)[:, None]
        rgb = (1.0 - f) * self._base[lo:hi] + f * FADED
        out = self.mesh.point_data["rgb"].reshape(-1, self.vertices_per_step, 3)
        out[lo:hi] = rgb.astype(np.uint8)[:, None]
        self.mesh.point_data["rgb"].Modified()

    def show_window(self, start: float, end: float, fade: float | None = None) -> int:
        """Keep only the footprints placed in ``[start, end]`` [s], faded over ``fade``
        [s] of age at time ``end`` (older ones stay at the faded colour; no fading when
        None); returns how many are shown."""
        lo = int(np.searchsorted(self.times, start, side="left"))
        hi = int(np.searchsorted(self.times, end, side="right"))
        if (lo, hi) != self.window:
            width = 4 * self._cells_per_step
            self.mesh.faces = self._faces[lo * width : hi * width]
            self.window = (lo, hi)
        if fade is not None:
            young = int(np.searchsorted(self.times, end - fade, side="left"))
            last = self._fade
            if last is None or last[0] != fade:
                a, b = 0, len(self.times)
            else:  # only what changed: newly placed, aged, or all when time went back
                a, b = min(young, last[1]), max(hi, last[2])
            self._paint(a, b, (end - self.times[a:b]) / fade)
            self._fade = (fade, young, hi)
        return hi - lo
