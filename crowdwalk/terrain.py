"""2.5-D ground: flat base, slopes, stair flights, blocks, rough heightfields, meshes.

A :class:`Terrain` is a flat base plane over a rectangular extent plus an ordered tuple of
features. **Composition is by override order**: where several feature footprints cover a
point, the *last* one listed decides its height (a painter's rule). This lets a later
feature cut into an earlier one (a stair flight going down from a platform, a curb on a
slope) and keeps every height exact: no feature is ever blended with another, so every
edge stays a sharp vertical step exactly where it was built.

Every feature is *piecewise planar*: a block top, a stair tread, a ramp, a triangle of a
rough heightfield's grid, a triangle of a mesh. Each feature lists the 2-D segments where
its plane changes (``breaks``). That makes the ground profile along a path
(:meth:`Terrain.profile`, the input of the footstep planner, Chen & Li §3: "the locations
where height changes along a given path") exact up to floating point: the path is cut at
every break, each piece lies on one plane, and a height change shows as two profile rows
with the same arc length.

Footprints are closed sets (a point on a block's edge is on the block); stair treads are
half-open along the walking direction (a point on a riser line belongs to the upper tread
of an up flight).
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely
import trimesh
from shapely.geometry import Polygon

from crowdwalk.errors import invalid

__all__ = [
    "TerrainKind",
    "Block",
    "Slope",
    "StairFlight",
    "Heightfield",
    "MeshFeature",
    "Terrain",
]


class TerrainKind(enum.IntEnum):
    """Terrain-type codes returned by :meth:`Terrain.kind`."""

    FLAT = 0
    SLOPE = 1
    STAIRS = 2
    BLOCK = 3
    ROUGH = 4
    MESH = 5


def _points(xy, owner: str = "Terrain", name: str = "xy") -> np.ndarray:
    arr = np.asarray(xy, dtype=float)
    if arr.ndim == 1 and arr.shape == (2,):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise invalid(owner, name, "an (n, 2) array of points [m]", f"shape {arr.shape}")
    return arr


def _ring_segments(geom) -> np.ndarray:
    """Segments (m, 2, 2) [m] of every ring / line of a shapely geometry."""
    out = []
    for line in shapely.get_parts(shapely.boundary(geom) if geom.geom_type.endswith("Polygon")
                                  else geom):
        c = shapely.get_coordinates(line)
        if len(c) >= 2:
            out.append(np.stack([c[:-1], c[1:]], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2, 2))


def _in_bbox(xy: np.ndarray, bbox) -> np.ndarray:
    x, y = xy[:, 0], xy[:, 1]
    return (x >= bbox[0]) & (x <= bbox[2]) & (y >= bbox[1]) & (y <= bbox[3])


def _covers_polygon(poly: Polygon, bbox, xy: np.ndarray) -> np.ndarray:
    mask = _in_bbox(xy, bbox)
    if mask.any():
        sub = xy[mask]
        mask[mask] = shapely.intersects_xy(poly, sub[:, 0], sub[:, 1])
    return mask


def _check_polygon(owner: str, poly) -> Polygon:
    if not isinstance(poly, Polygon):
        try:
            poly = Polygon(np.asarray(poly, dtype=float))
        except Exception as exc:  # noqa: BLE001 - shapely raises many types
            raise invalid(owner, "footprint", "a polygon [m]", poly) from exc
    if not poly.is_valid or poly.area <= 0:
        raise invalid(owner, "footprint", "a valid polygon with positive area [m²]", poly.wkt)
    shapely.prepare(poly)
    return poly


# --- features -----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Block:
    """A block, curb or obstacle: a flat top at height ``top`` [m] over ``footprint``.

    Parameters
    ----------
    footprint : shapely Polygon or (k, 2) vertices [m]
    top : float
        Height of the top face, world z [m]. Sides are vertical.
    """

    footprint: Polygon
    top: float
    kind: TerrainKind = field(default=TerrainKind.BLOCK, init=False)

    def __post_init__(self):
        object.__setattr__(self, "footprint", _check_polygon("Block", self.footprint))
        if not np.isfinite(self.top):
            raise invalid("Block", "top", "a finite height [m]", self.top)

    @classmethod
    def box(cls, center, size, top: float, heading: float = 0.0) -> Block:
        """A rectangular block: ``center`` (2,) [m], ``size`` (length, width) [m] with the
        length along ``heading`` [rad]."""
        return cls(_rectangle(center, size, heading), top)

    @functools.cached_property
    def bbox(self) -> tuple[float, float, float, float]:
        return self.footprint.bounds

    def covers(self, xy: np.ndarray) -> np.ndarray:
        """Whether each point (n, 2) [m] is on the footprint (closed); (n,) bool."""
        return _covers_polygon(self.footprint, self.bbox, xy)

    def surface(self, xy: np.ndarray, ref: np.ndarray) -> np.ndarray:
        """Height [m] at ``xy`` of the plane piece containing ``ref``; (n,)."""
        return np.full(len(xy), float(self.top))

    def gradient(self, xy: np.ndarray) -> np.ndarray:
        """Height gradient (n, 2) [m/m]."""
        return np.zeros((len(xy), 2))

    def breaks(self) -> np.ndarray:
        """Segments (m, 2, 2) [m] where the surface plane changes."""
        return _ring_segments(self.footprint)

    outline = breaks


def _rectangle(start_or_center, size, heading: float, from_start: bool = False) -> Polygon:
    length, width = (float(v) for v in size)
    d = np.array([np.cos(heading), np.sin(heading)])
    lat = np.array([-d[1], d[0]])
    p = np.asarray(start_or_center, dtype=float)
    u0, u1 = (0.0, length) if from_start else (-length / 2, length / 2)
    corners = [p + u * d + v * lat for u, v in
               ((u0, -width / 2), (u1, -width / 2), (u1, width / 2), (u0, width / 2))]
    return Polygon(corners)


@dataclass(frozen=True, eq=False)
class Slope:
    """A planar slope over ``footprint``: ``z = z0 + grade · (cos ψ, sin ψ) · (p − origin)``.

    Parameters
    ----------
    footprint : shapely Polygon or (k, 2) vertices [m]
    origin : (2,) point where the height is ``z0`` [m]
    z0 : float, height at ``origin`` [m]
    heading : float, direction of steepest ascent ψ [rad]
    grade : float, rise per horizontal metre along ``heading`` [m/m]
    """

    footprint: Polygon
    origin: tuple[float, float]
    z0: float
    heading: float
    grade: float
    kind: TerrainKind = field(default=TerrainKind.SLOPE, init=False)

    def __post_init__(self):
        object.__setattr__(self, "footprint", _check_polygon("Slope", self.footprint))
        object.__setattr__(self, "origin", tuple(float(v) for v in self.origin))
        for name in ("z0", "heading", "grade"):
            if not np.isfinite(getattr(self, name)):
                raise invalid("Slope", name, "finite", getattr(self, name))

    @classmethod
    def ramp(cls, start, heading: float, length: float, width: float,
             z_start: float, z_end: float) -> Slope:
        """A rectangular ramp from the middle of its lower edge ``start`` (2,) [m] along
        ``heading`` [rad]; ``length``, ``width`` [m]; heights at both ends [m]."""
        if not length > 0:
            raise invalid("Ramp", "length", "> 0 [m]", length)
        if not width > 0:
            raise invalid("Ramp", "width", "> 0 [m]", width)
        poly = _rectangle(start, (length, width), heading, from_start=True)
        return cls(poly, tuple(start), z_start, heading, (z_end - z_start) / length)

    @functools.cached_property
    def bbox(self):
        return self.footprint.bounds

    @functools.cached_property
    def _grad(self) -> np.ndarray:
        return self.grade * np.array([np.cos(self.heading), np.sin(self.heading)])

    def covers(self, xy):
        return _covers_polygon(self.footprint, self.bbox, xy)

    def surface(self, xy, ref):
        return self.z0 + (xy - np.asarray(self.origin)) @ self._grad

    def gradient(self, xy):
        return np.broadcast_to(self._grad, (len(xy), 2)).copy()

    def breaks(self):
        return _ring_segments(self.footprint)

    outline = breaks


@dataclass(frozen=True, eq=False)
class StairFlight:
    """A straight stair flight of ``steps`` treads.

    The first riser stands on the line through ``start`` perpendicular to ``heading``;
    tread k (0-based) spans ``k·going ≤ u < (k+1)·going`` along the heading at height
    ``z0 ± (k+1)·rise`` (+ for ``up``). The flight ends at ``u = steps·going``; whatever
    is beyond (a landing block) is another feature.

    Parameters
    ----------
    start : (2,) middle of the first riser's base line [m]
    heading : walking direction of the flight ψ [rad]
    width : flight width [m]
    going : tread depth [m]
    rise : riser height [m], > 0
    steps : number of treads
    z0 : ground height in front of the first riser [m]
    up : True if the flight climbs along ``heading``
    """

    start: tuple[float, float]
    heading: float
    width: float
    going: float
    rise: float
    steps: int
    z0: float = 0.0
    up: bool = True
    kind: TerrainKind = field(default=TerrainKind.STAIRS, init=False)

    def __post_init__(self):
        object.__setattr__(self, "start", tuple(float(v) for v in self.start))
        for name, lo in (("width", 0), ("going", 0), ("rise", 0)):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > lo):
                raise invalid("StairFlight", name, "> 0 [m]", v)
        if int(self.steps) != self.steps or self.steps < 1:
            raise invalid("StairFlight", "steps", "an integer ≥ 1", self.steps)

    @functools.cached_property
    def _axes(self):
        d = np.array([np.cos(self.heading), np.sin(self.heading)])
        return np.asarray(self.start), d, np.array([-d[1], d[0]])

    @property
    def length(self) -> float:
        """Horizontal length of the flight [m]."""
        return self.steps * self.going

    @property
    def top(self) -> float:
        """Height of the last tread [m]."""
        return self.z0 + (1 if self.up else -1) * self.steps * self.rise

    @functools.cached_property
    def footprint(self) -> Polygon:
        return _rectangle(self.start, (self.length, self.width), self.heading, from_start=True)

    @functools.cached_property
    def bbox(self):
        return self.footprint.bounds

    def _uv(self, xy):
        p, d, lat = self._axes
        r = xy - p
        return r @ d, r @ lat

    def covers(self, xy):
        mask = _in_bbox(xy, self.bbox)
        if mask.any():
            u, v = self._uv(xy[mask])
            mask[mask] = (u >= 0) & (u <= self.length) & (np.abs(v) <= self.width / 2)
        return mask

    def step_index(self, xy) -> np.ndarray:
        """Tread index (n,) of each point, clipped to 0..steps-1."""
        u, _ = self._uv(xy)
        return np.clip(np.floor(u / self.going), 0, self.steps - 1).astype(int)

    def surface(self, xy, ref):
        k = self.step_index(ref)
        return self.z0 + (1.0 if self.up else -1.0) * (k + 1) * self.rise

    def gradient(self, xy):
        return np.zeros((len(xy), 2))

    def breaks(self, overshoot: float = 0.0):
        p, d, lat = self._axes
        u = np.arange(1, self.steps)[:, None] * self.going
        half = self.width / 2 + overshoot
        risers = np.stack([p + u * d - lat * half, p + u * d + lat * half], axis=1)
        return np.concatenate([_ring_segments(self.footprint), risers.reshape(-1, 2, 2)])

    def outline(self):
        # risers overshoot the sides by 0.1 µm so that noding sees a true crossing (a
        # T-junction computed in floating point may miss the side line); the dangling
        # ends are dropped by polygonize and are too short to make walls
        return self.breaks(overshoot=1e-7)


@dataclass(frozen=True, eq=False)
class Heightfield:
    """Rough ground: heights on a regular grid, each cell split into two planar triangles.

    Parameters
    ----------
    origin : (2,) position of grid node [0, 0] [m]
    cell : grid spacing [m]
    heights : (ny, nx) world z at the grid nodes [m]; node [j, i] is at
        ``origin + (i·cell, j·cell)``.
    """

    origin: tuple[float, float]
    cell: float
    heights: np.ndarray
    kind: TerrainKind = field(default=TerrainKind.ROUGH, init=False)

    def __post_init__(self):
        h = np.asarray(self.heights, dtype=float)
        if h.ndim != 2 or min(h.shape) < 2:
            raise invalid("Heightfield", "heights", "a 2-D array at least 2×2 [m]",
                          f"shape {h.shape}")
        if not np.isfinite(h).all():
            raise invalid("Heightfield", "heights", "finite [m]", "non-finite values")
        if not (np.isfinite(self.cell) and self.cell > 0):
            raise invalid("Heightfield", "cell", "> 0 [m]", self.cell)
        h.setflags(write=False)
        object.__setattr__(self, "heights", h)
        object.__setattr__(self, "origin", tuple(float(v) for v in self.origin))

    @classmethod
    def noise(cls, origin, size, cell: float, amplitude: float, correlation: float,
              seed: int, base: float = 0.0, taper: float = 0.0) -> Heightfield:
        """Seeded Gaussian-filtered white noise with standard deviation ``amplitude`` [m],
        correlation length ``correlation`` [m], over ``size`` (lx, ly) [m] from ``origin``;
        heights fade linearly to ``base`` over ``taper`` [m] at the border."""
        from scipy.ndimage import gaussian_filter

        for name, v in (("cell", cell), ("correlation", correlation)):
            if not v > 0:
                raise invalid("Heightfield", name, "> 0 [m]", v)
        if not amplitude >= 0:
            raise invalid("Heightfield", "amplitude", "≥ 0 [m]", amplitude)
        nx, ny = (int(np.ceil(s / cell)) + 1 for s in size)
        rng = np.random.default_rng(seed)
        g = gaussian_filter(rng.standard_normal((ny, nx)), correlation / cell, mode="wrap")
        g *= amplitude / max(g.std(), 1e-12)
        if taper > 0:
            x = np.arange(nx) * cell
            y = np.arange(ny) * cell
            wx = np.clip(np.minimum(x, x[-1] - x) / taper, 0, 1)
            wy = np.clip(np.minimum(y, y[-1] - y) / taper, 0, 1)
            g *= wy[:, None] * wx[None, :]
        return cls(origin, cell, base + g)

    @functools.cached_property
    def bbox(self):
        ny, nx = self.heights.shape
        x0, y0 = self.origin
        return (x0, y0, x0 + (nx - 1) * self.cell, y0 + (ny - 1) * self.cell)

    @functools.cached_property
    def footprint(self) -> Polygon:
        return shapely.box(*self.bbox)

    def covers(self, xy):
        return _in_bbox(xy, self.bbox)

    def _cell(self, xy):
        ny, nx = self.heights.shape
        f = (xy - np.asarray(self.origin)) / self.cell
        i = np.clip(np.floor(f[:, 0]), 0, nx - 2).astype(int)
        j = np.clip(np.floor(f[:, 1]), 0, ny - 2).astype(int)
        return i, j, f[:, 0] - i, f[:, 1] - j

    def _plane(self, ref):
        """Plane of the triangle containing ``ref``: (z at cell corner, dz/dfx, dz/dfy)."""
        h = self.heights
        i, j, fx, fy = self._cell(ref)
        z00, z10, z01, z11 = h[j, i], h[j, i + 1], h[j + 1, i], h[j + 1, i + 1]
        lower = fx + fy <= 1
        gx = np.where(lower, z10 - z00, z11 - z01)
        gy = np.where(lower, z01 - z00, z11 - z10)
        # the plane's value at the cell corner (0, 0): z00 below the diagonal, else
        # extrapolated back from z11
        anchor = np.where(lower, z00, z11 - gx - gy)
        return i, j, anchor, gx, gy

    def surface(self, xy, ref):
        i, j, z00, gx, gy = self._plane(ref)
        f = (xy - np.asarray(self.origin)) / self.cell
        return z00 + (f[:, 0] - i) * gx + (f[:, 1] - j) * gy

    def gradient(self, xy):
        _, _, _, gx, gy = self._plane(xy)
        return np.stack([gx, gy], axis=1) / self.cell

    def outline(self):
        return _ring_segments(self.footprint)

    def breaks(self):
        ny, nx = self.heights.shape
        x0, y0, x1, y1 = self.bbox
        xs = x0 + np.arange(nx) * self.cell
        ys = y0 + np.arange(ny) * self.cell
        vert = np.stack([np.stack([xs, np.full(nx, y0)], 1), np.stack([xs, np.full(nx, y1)], 1)], 1)
        horz = np.stack([np.stack([np.full(ny, x0), ys], 1), np.stack([np.full(ny, x1), ys], 1)], 1)
        gi, gj = np.meshgrid(xs[:-1], ys[:-1])
        a = np.stack([gi.ravel() + self.cell, gj.ravel()], 1)
        b = np.stack([gi.ravel(), gj.ravel() + self.cell], 1)
        return np.concatenate([vert, horz, np.stack([a, b], 1)])

    def triangles(self) -> np.ndarray:
        """The grid's planar triangles projected to 2-D, (m, 3, 2) [m]."""
        ny, nx = self.heights.shape
        x0, y0 = self.origin
        gi, gj = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1))
        p00 = np.stack([x0 + gi.ravel() * self.cell, y0 + gj.ravel() * self.cell], 1)
        dx, dy = np.array([self.cell, 0.0]), np.array([0.0, self.cell])
        lower = np.stack([p00, p00 + dx, p00 + dy], 1)
        upper = np.stack([p00 + dx + dy, p00 + dy, p00 + dx], 1)
        return np.concatenate([lower, upper])


@dataclass(frozen=True, eq=False)
class MeshFeature:
    """Any surface trimesh reads; heights are the topmost hit of a vertical ray.

    Parameters
    ----------
    mesh : trimesh.Trimesh in world coordinates [m], z up.
    """

    mesh: trimesh.Trimesh
    kind: TerrainKind = field(default=TerrainKind.MESH, init=False)

    def __post_init__(self):
        if not isinstance(self.mesh, trimesh.Trimesh) or len(self.mesh.faces) == 0:
            raise invalid("MeshFeature", "mesh", "a non-empty triangle mesh", type(self.mesh))

    @classmethod
    def load(cls, path, translate=(0.0, 0.0, 0.0), scale: float = 1.0,
             rotate_z: float = 0.0) -> MeshFeature:
        """Read OBJ/STL/PLY/GLB/... from ``path``; scale, rotate about z by ``rotate_z``
        [rad], then translate (3,) [m]."""
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(2, "No such file", str(path))
        mesh = trimesh.load(path, force="mesh")
        if not scale > 0:
            raise invalid("MeshFeature", "scale", "> 0", scale)
        m = trimesh.transformations.rotation_matrix(rotate_z, [0, 0, 1])
        m[:3, :3] *= scale
        m[:3, 3] = translate
        mesh.apply_transform(m)
        return cls(mesh)

    @functools.cached_property
    def _up_faces(self) -> np.ndarray:
        """Indices of faces that are not vertical (they can be stood on)."""
        return np.flatnonzero(np.abs(self.mesh.face_normals[:, 2]) > 1e-9)

    @functools.cached_property
    def _centroid_tree(self):
        from scipy.spatial import cKDTree

        return cKDTree(self.mesh.triangles_center[self._up_faces, :2])

    @functools.cached_property
    def footprint(self) -> Polygon:
        tri = self.triangles()
        geom = shapely.union_all(shapely.polygons(np.concatenate([tri, tri[:, :1]], axis=1)))
        geom = shapely.make_valid(geom)
        polys = [g for g in shapely.get_parts(geom) if g.geom_type == "Polygon"]
        return shapely.union_all(polys)

    @functools.cached_property
    def bbox(self):
        (x0, y0, _), (x1, y1, _) = self.mesh.bounds
        return (x0, y0, x1, y1)

    def _hit_faces(self, xy) -> np.ndarray:
        top = self.mesh.bounds[1, 2] + 1.0
        origins = np.column_stack([xy, np.full(len(xy), top)])
        dirs = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
        return self.mesh.ray.intersects_first(origins, dirs)

    def covers(self, xy):
        mask = _in_bbox(xy, self.bbox)
        if mask.any():
            mask[mask] = self._hit_faces(xy[mask]) >= 0
        return mask

    def _plane(self, ref):
        f = self._hit_faces(ref)
        miss = f < 0
        if miss.any():  # a ray grazing the rim: the face with the nearest centroid
            _, k = self._centroid_tree.query(ref[miss])
            f[miss] = self._up_faces[k]
        n = self.mesh.face_normals[f]
        v0 = self.mesh.vertices[self.mesh.faces[f, 0]]
        return v0, n

    def surface(self, xy, ref):
        v0, n = self._plane(ref)
        dx, dy = xy[:, 0] - v0[:, 0], xy[:, 1] - v0[:, 1]
        return v0[:, 2] - (n[:, 0] * dx + n[:, 1] * dy) / n[:, 2]

    def gradient(self, xy):
        _, n = self._plane(xy)
        return -n[:, :2] / n[:, 2:3]

    def triangles(self) -> np.ndarray:
        """The non-vertical faces projected to 2-D, (m, 3, 2) [m]."""
        return self.mesh.vertices[self.mesh.faces[self._up_faces]][:, :, :2]

    def outline(self):
        return _ring_segments(self.footprint)

    def breaks(self):
        tri = self.triangles()
        e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
        swap = (e[:, 0, 0] > e[:, 1, 0]) | ((e[:, 0, 0] == e[:, 1, 0]) & (e[:, 0, 1] > e[:, 1, 1]))
        e[swap] = e[swap][:, ::-1]
        _, idx = np.unique(np.round(e.reshape(len(e), 4), 9), axis=0, return_index=True)
        e = e[idx]
        return e[np.linalg.norm(e[:, 1] - e[:, 0], axis=1) > 1e-12]


Feature = Block | Slope | StairFlight | Heightfield | MeshFeature


# --- the composed terrain ---------------------------------------------------------------


class _EdgeIndex:
    """Break segments (k, 2, 2) [m] with a bounding-box test, or an STRtree when many."""

    def __init__(self, edges: np.ndarray):
        self.edges = edges
        self.lo, self.hi = edges.min(axis=1), edges.max(axis=1)
        self.tree = shapely.STRtree(shapely.linestrings(edges)) if len(edges) > 256 else None

    def pairs(self, a: np.ndarray, b: np.ndarray):
        """Candidate (segment, edge) index pairs whose bounding boxes overlap."""
        if self.tree is not None:
            boxes = shapely.box(*np.minimum(a, b).T - 1e-9, *np.maximum(a, b).T + 1e-9)
            i, j = self.tree.query(boxes)
            yield i, j
            return
        chunk = max(1, 200_000 // max(len(self.edges), 1))
        for c0 in range(0, len(a), chunk):
            aa, bb = a[c0:c0 + chunk, None, :], b[c0:c0 + chunk, None, :]
            near = ((np.maximum(aa, bb) >= self.lo - 1e-9).all(-1)
                    & (np.minimum(aa, bb) <= self.hi + 1e-9).all(-1))
            i, j = np.nonzero(near)
            yield i + c0, j


def _crossings(a: np.ndarray, b: np.ndarray, index: _EdgeIndex):
    """Where segments a→b (m, 2) [m] cross the indexed edges: (segment index (h,),
    parameter t ∈ [0, 1] along it (h,))."""
    seg_idx, ts = [], []
    edges = index.edges
    e0, e = edges[:, 0], edges[:, 1] - edges[:, 0]
    tol = 1e-12
    for i, j in index.pairs(a, b):
        if len(i) == 0:
            continue
        d = b[i] - a[i]
        r = e0[j] - a[i]
        ej = e[j]
        den = d[:, 0] * ej[:, 1] - d[:, 1] * ej[:, 0]
        ok = np.abs(den) > 1e-15
        den = np.where(ok, den, 1.0)
        t = (r[:, 0] * ej[:, 1] - r[:, 1] * ej[:, 0]) / den
        u = (r[:, 0] * d[:, 1] - r[:, 1] * d[:, 0]) / den
        ok &= (t >= -tol) & (t <= 1 + tol) & (u >= -tol) & (u <= 1 + tol)
        seg_idx.append(i[ok])
        ts.append(np.clip(t[ok], 0.0, 1.0))
    if not seg_idx:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    return np.concatenate(seg_idx), np.concatenate(ts)


class _FeatureGrid:
    """A uniform grid over the extent listing the features whose bounding box touches each
    cell, so that a query tests each feature only on the points near it (many obstacles).
    Features spanning many cells are tested on all points (their bounding-box test is
    cheaper than gathering)."""

    MAX_CELLS = 64

    def __init__(self, extent, features):
        x0, y0, x1, y1 = extent
        bb = np.array([f.bbox for f in features])
        size = np.maximum(bb[:, 2] - bb[:, 0], bb[:, 3] - bb[:, 1])
        self.cell = max(float(np.median(size)), math.sqrt((x1 - x0) * (y1 - y0) / 65536))
        self.origin = np.array([x0, y0])
        self.shape = (max(1, math.ceil((x1 - x0) / self.cell)),
                      max(1, math.ceil((y1 - y0) / self.cell)))
        lo = self._cell_xy(bb[:, :2])
        hi = self._cell_xy(bb[:, 2:])
        self.cells: list[np.ndarray | None] = []
        for (i0, j0), (i1, j1) in zip(lo, hi, strict=True):
            if (i1 - i0 + 1) * (j1 - j0 + 1) > self.MAX_CELLS:
                self.cells.append(None)
                continue
            ii, jj = np.meshgrid(np.arange(i0, i1 + 1), np.arange(j0, j1 + 1))
            self.cells.append((ii + self.shape[0] * jj).ravel())

    def _cell_xy(self, xy: np.ndarray) -> np.ndarray:
        ij = np.floor((xy - self.origin) / self.cell).astype(np.int64)
        return np.clip(ij, 0, np.array(self.shape) - 1)

    def candidates(self, xy: np.ndarray):
        """A function: feature index → indices of the points in its cells (or None)."""
        ij = self._cell_xy(xy)
        cid = ij[:, 0] + self.shape[0] * ij[:, 1]
        order = np.argsort(cid, kind="stable")
        sorted_cid = cid[order]

        def points_of(i: int):
            cells = self.cells[i]
            if cells is None:
                return None
            start = np.searchsorted(sorted_cid, cells, "left")
            stop = np.searchsorted(sorted_cid, cells, "right")
            if len(cells) == 1:
                return order[start[0]:stop[0]]
            return np.concatenate([order[a:b] for a, b in zip(start, stop, strict=True)])

        return points_of


@dataclass(frozen=True, eq=False)
class Terrain:
    """A flat base plane over ``extent`` plus features composed in override order.

    Parameters
    ----------
    extent : (xmin, ymin, xmax, ymax) of the ground [m]
    base : height of the flat base plane [m]
    features : features; where footprints overlap the last one listed wins.
    """

    extent: tuple[float, float, float, float]
    base: float = 0.0
    features: tuple[Feature, ...] = ()

    def __post_init__(self):
        ext = tuple(float(v) for v in self.extent)
        if len(ext) != 4 or not (ext[2] > ext[0] and ext[3] > ext[1]):
            raise invalid("Terrain", "extent", "(xmin, ymin, xmax, ymax) with max > min [m]",
                          self.extent)
        object.__setattr__(self, "extent", ext)
        object.__setattr__(self, "features", tuple(self.features))
        if not np.isfinite(self.base):
            raise invalid("Terrain", "base", "a finite height [m]", self.base)
        area = shapely.box(*ext)
        for i, f in enumerate(self.features):
            if not area.buffer(1e-9).covers(shapely.box(*f.bbox)):
                raise invalid("Terrain", f"features[{i}]", f"inside the extent {ext} [m]",
                              tuple(round(v, 3) for v in f.bbox))

    @classmethod
    def flat(cls, extent, base: float = 0.0) -> Terrain:
        """Flat ground at height ``base`` [m] over ``extent`` [m]."""
        return cls(extent, base)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the ground [m]."""
        return self.extent

    @functools.cached_property
    def area(self) -> Polygon:
        """The ground's extent as a shapely polygon [m]."""
        return shapely.box(*self.extent)

    # -- point queries --

    @functools.cached_property
    def _grid(self) -> _FeatureGrid | None:
        return _FeatureGrid(self.extent, self.features) if len(self.features) > 16 else None

    def owner(self, xy) -> np.ndarray:
        """Index of the feature that decides each point's height, −1 for the base; (n,)."""
        xy = _points(xy)
        own = np.full(len(xy), -1, dtype=np.int64)
        if self._grid is None or len(xy) < 64:
            for i, f in enumerate(self.features):
                own[f.covers(xy)] = i
            return own
        candidates = self._grid.candidates(xy)
        for i, f in enumerate(self.features):  # in order: later features override
            idx = candidates(i)
            if idx is None:
                own[f.covers(xy)] = i
            elif len(idx):
                own[idx[f.covers(xy[idx])]] = i
        return own

    @staticmethod
    def _by_owner(own: np.ndarray):
        """(feature index, point indices) for every feature that owns points."""
        idx = np.flatnonzero(own >= 0)
        if len(idx) == 0:
            return
        order = idx[np.argsort(own[idx], kind="stable")]
        feats, starts = np.unique(own[order], return_index=True)
        stops = np.append(starts[1:], len(order))
        for f, a, b in zip(feats, starts, stops, strict=True):
            yield int(f), order[a:b]

    def _surface(self, xy: np.ndarray, ref: np.ndarray, own: np.ndarray) -> np.ndarray:
        z = np.full(len(xy), float(self.base))
        for i, k in self._by_owner(own):
            z[k] = self.features[i].surface(xy[k], ref[k])
        return z

    def height(self, xy) -> np.ndarray:
        """Ground height z [m] at points ``xy`` (n, 2) [m]; (n,)."""
        xy = _points(xy)
        return self._surface(xy, xy, self.owner(xy))

    def normal(self, xy) -> np.ndarray:
        """Unit upward surface normal (n, 3) at ``xy`` (n, 2) [m] (of the tread or top face
        at an edge, never of a riser)."""
        xy = _points(xy)
        own = self.owner(xy)
        g = np.zeros((len(xy), 2))
        for i, k in self._by_owner(own):
            g[k] = self.features[i].gradient(xy[k])
        n = np.column_stack([-g, np.ones(len(xy))])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def kind(self, xy) -> np.ndarray:
        """Terrain-type code (:class:`TerrainKind`) of each point (n, 2) [m]; (n,) int."""
        own = self.owner(xy)
        codes = np.array([int(f.kind) for f in self.features] + [int(TerrainKind.FLAT)])
        return codes[own]

    # -- profile --

    @functools.cached_property
    def _breaks(self) -> _EdgeIndex:
        parts = [f.breaks() for f in self.features]
        return _EdgeIndex(np.concatenate(parts) if parts else np.zeros((0, 2, 2)))

    def profile_arrays(self, polyline) -> tuple[np.ndarray, np.ndarray]:
        """Ground profile along ``polyline`` (k, 2) [m]: arc length s (m,) [m] from the first
        point and height z (m,) [m], piecewise linear; two rows with equal s are a vertical
        height change. Exact at every edge (floating-point precision)."""
        p = _points(polyline, "Terrain", "polyline")
        if len(p) < 2:
            raise invalid("Terrain", "polyline", "at least 2 points [m]", len(p))
        return self.profiles([p])[0]

    def profiles(self, polylines) -> list[tuple[np.ndarray, np.ndarray]]:
        """:meth:`profile_arrays` for many polylines in one batched pass (one terrain query
        for all of them): a list of (s, z) pairs [m]."""
        lines = [_points(pl, "Terrain", "polyline") for pl in polylines]
        a_list, b_list, line_of, s0_list, singles = [], [], [], [], {}
        for li, pl in enumerate(lines):
            if len(pl) < 2:
                raise invalid("Terrain", "polyline", "at least 2 points [m]", len(pl))
            seg = np.linalg.norm(np.diff(pl, axis=0), axis=1)
            keep = np.concatenate([[True], seg > 1e-9])  # drop repeated points
            pl, seg = pl[keep], seg[seg > 1e-9]
            if len(pl) < 2:
                singles[li] = pl[:1]
                continue
            a_list.append(pl[:-1])
            b_list.append(pl[1:])
            line_of.append(np.full(len(seg), li))
            s0_list.append(np.concatenate([[0.0], np.cumsum(seg)[:-1]]))
        out: list = [None] * len(lines)
        for li, pt in singles.items():
            out[li] = (np.zeros(1), self.height(pt))
        if not a_list:
            return out
        a, b = np.concatenate(a_list), np.concatenate(b_list)
        line_of, s_seg0 = np.concatenate(line_of), np.concatenate(s0_list)
        seg_len = np.linalg.norm(b - a, axis=1)
        m = len(a)
        index = self._breaks
        hit_seg, hit_t = _crossings(a, b, index) if len(index.edges) else (
            np.zeros(0, dtype=np.int64), np.zeros(0))
        seg = np.concatenate([np.arange(m), np.arange(m), hit_seg])
        t = np.concatenate([np.zeros(m), np.ones(m), hit_t])
        order = np.lexsort((t, seg))
        seg, t = seg[order], t[order]
        s = s_seg0[seg] + t * seg_len[seg]
        pts = a[seg] + t[:, None] * (b[seg] - a[seg])
        # pieces between consecutive cut points of the same segment, each on one plane
        i0 = np.flatnonzero((seg[1:] == seg[:-1]) & (s[1:] - s[:-1] > 1e-12))
        mid = 0.5 * (pts[i0] + pts[i0 + 1])
        own = self.owner(mid)
        za = self._surface(pts[i0], mid, own)
        zb = self._surface(pts[i0 + 1], mid, own)
        n = len(i0)
        s_rows = np.empty(2 * n)
        z_rows = np.empty(2 * n)
        s_rows[0::2], s_rows[1::2] = s[i0], s[i0 + 1]
        z_rows[0::2], z_rows[1::2] = za, zb
        row_line = np.repeat(line_of[seg[i0]], 2)
        # drop a row that repeats the previous one (continuous ground at a cut)
        same_line = np.concatenate([[False], row_line[1:] == row_line[:-1]])
        dup = same_line & np.concatenate([[False], (np.abs(np.diff(s_rows)) <= 1e-12)
                                          & (np.abs(np.diff(z_rows)) <= 1e-12)])
        s_rows, z_rows, row_line = s_rows[~dup], z_rows[~dup], row_line[~dup]
        # snap the two rows of a vertical change to exactly the same s
        same_line = np.concatenate([[False], row_line[1:] == row_line[:-1]])
        step = same_line & np.concatenate([[False], np.abs(np.diff(s_rows)) <= 1e-12])
        s_rows[step] = s_rows[np.flatnonzero(step) - 1]
        bounds = np.searchsorted(row_line, np.arange(len(lines) + 1))
        for li in range(len(lines)):
            if out[li] is None:
                out[li] = (s_rows[bounds[li]:bounds[li + 1]], z_rows[bounds[li]:bounds[li + 1]])
        return out

    def profile(self, polyline):
        """Ground profile along ``polyline`` (k, 2) [m] as a ``planners.GroundProfile``
        (s = 0 at the polyline's first point)."""
        s, z = self.profile_arrays(polyline)
        from planners.profile import GroundProfile

        return GroundProfile(s, z)

    # -- mesh --

    @functools.cached_property
    def _arrangement(self):
        """All feature outlines and the extent, noded into one line network [m]."""
        lines = [_ring_segments(self.area)] + [f.outline() for f in self.features]
        return shapely.union_all(shapely.linestrings(np.concatenate(lines)))

    def steps(self, min_height: float = 0.0) -> np.ndarray:
        """Edges where the ground changes height by more than ``min_height`` [m] (risers,
        curbs, block sides, walls) as segments (m, 2, 2) [m]."""
        a, b, zla, zlb, zra, zrb, _, _ = self._edge_steps(self._arrangement)
        ja, jb = zla - zra, zlb - zrb  # the step height varies linearly along an edge
        out = []
        for sign in (1.0, -1.0):  # where sign·j(t) > min_height, t ∈ [0, 1]
            fa, fb = sign * ja - min_height, sign * jb - min_height
            with np.errstate(divide="ignore", invalid="ignore"):
                t0 = np.where(fa == fb, 0.0, fa / (fa - fb))  # root of the linear function
            lo = np.where(fa > 0, 0.0, np.clip(t0, 0, 1))
            hi = np.where(fb > 0, 1.0, np.clip(t0, 0, 1))
            keep = ((fa > 0) | (fb > 0)) & (hi - lo > 1e-12)
            d = b - a
            out.append(np.stack([a + lo[:, None] * d, a + hi[:, None] * d], axis=1)[keep])
        return np.concatenate(out)

    def mesh(self) -> trimesh.Trimesh:
        """The whole ground as one triangle mesh [m]: treads, tops and slopes as exact
        planar faces, vertical risers and block sides, rough and mesh features by their
        own triangles (clipped to where they are visible)."""
        noded = self._arrangement
        faces = np.asarray(shapely.get_parts(shapely.polygonize(shapely.get_parts(noded))))
        faces = faces[shapely.area(faces) > 1e-12]
        rep = shapely.get_coordinates(shapely.point_on_surface(faces))
        own = self.owner(rep)
        tris, refs, owners = [], [], []
        planar = np.array([o < 0 or not hasattr(self.features[o], "triangles") for o in own])
        if planar.any():
            t, ref, k = self._triangulate(faces[planar], rep[planar])
            tris.append(t)
            refs.append(ref)
            owners.append(own[planar][k])
        as_is = []  # meshes: their own faces, where visible
        for o in np.unique(own[~planar]):
            region = shapely.union_all(faces[own == o])
            feat = self.features[o]
            if isinstance(feat, MeshFeature):
                # faces seen from above or from the side (a bottom face is hidden)
                tri3 = feat.mesh.triangles
                c = tri3.mean(axis=1)
                seen = shapely.intersects_xy(region.buffer(1e-6), c[:, 0], c[:, 1])
                seen &= feat.mesh.face_normals[:, 2] > -1e-9
                as_is.append(tri3[seen])
                continue
            # rough ground: its planar triangles, clipped to the visible region, each
            # lifted onto the plane of its source triangle (via the triangle's centroid)
            src = feat.triangles()
            polys = shapely.polygons(np.concatenate([src, src[:, :1]], axis=1))
            idx = shapely.STRtree(polys).query(region, predicate="intersects")
            clipped = shapely.intersection(polys[idx], region)
            ok = shapely.area(clipped) > 1e-12
            centroid = src[idx[ok]].mean(axis=1)
            t, ref, _ = self._triangulate(clipped[ok], centroid)
            tris.append(t)
            refs.append(ref)
            owners.append(np.full(len(t), o))
        tri2 = np.concatenate(tris)
        flat = tri2.reshape(-1, 2)
        rref = np.repeat(np.concatenate(refs), 3, axis=0)
        z = self._surface(flat, rref, np.repeat(np.concatenate(owners), 3))
        verts = [np.column_stack([flat, z])] + [t.reshape(-1, 3) for t in as_is]
        # vertical walls along every noded edge where the two sides differ in height
        walls = self._walls(noded)
        if len(walls):
            verts.append(walls.reshape(-1, 3))
        v = np.concatenate(verts)
        f = np.arange(len(v)).reshape(-1, 3)
        mesh = trimesh.Trimesh(v, f, process=True)
        # orient every face upward / outward
        flip = mesh.face_normals[:, 2] < -1e-9
        if flip.any():
            faces_ = mesh.faces.copy()
            faces_[flip] = faces_[flip][:, ::-1]
            mesh = trimesh.Trimesh(mesh.vertices, faces_, process=False)
        return mesh

    @staticmethod
    def _triangulate(polys, rep):
        """Triangles (t, 3, 2) [m] of polygons, each polygon's reference point (t, 2) and
        the polygon index (t,)."""
        cdt = shapely.constrained_delaunay_triangles(polys)
        parts, idx = shapely.get_parts(cdt, return_index=True)
        coords = shapely.get_coordinates(parts).reshape(-1, 4, 2)[:, :3]
        return coords, rep[idx], idx

    def _edge_steps(self, noded):
        """Noded edges with different heights on their two sides: end points a, b (m, 2)
        and the heights at a and b on the left and right side (m,) each [m], and the
        owners of the left and right side (m,) each."""
        segs = _ring_segments(noded)
        if len(segs) == 0:
            return (np.zeros((0, 2)),) * 2 + (np.zeros(0),) * 4 + (np.zeros(0, int),) * 2
        a, b = segs[:, 0], segs[:, 1]
        d = b - a
        length = np.linalg.norm(d, axis=1)
        segs, a, b, d, length = (x[length > 1e-6] for x in (segs, a, b, d, length))
        nrm = np.column_stack([-d[:, 1], d[:, 0]]) / length[:, None]
        mid = 0.5 * (a + b)
        left, right = mid + 1e-6 * nrm, mid - 1e-6 * nrm
        x0, y0, x1, y1 = self.extent
        inside = ((_in_bbox(left, (x0, y0, x1, y1))) & (_in_bbox(right, (x0, y0, x1, y1))))
        a, b, left, right = a[inside], b[inside], left[inside], right[inside]
        ol, orr = self.owner(left), self.owner(right)
        ab = np.concatenate([a, b])
        zl = self._surface(ab, np.concatenate([left, left]), np.concatenate([ol, ol]))
        zr = self._surface(ab, np.concatenate([right, right]), np.concatenate([orr, orr]))
        n = len(a)
        zla, zlb, zra, zrb = zl[:n], zl[n:], zr[:n], zr[n:]
        diff = (np.abs(zla - zra) > 1e-9) | (np.abs(zlb - zrb) > 1e-9)
        return tuple(x[diff] for x in (a, b, zla, zlb, zra, zrb, ol, orr))

    def _walls(self, noded) -> np.ndarray:
        """Vertical wall triangles (m, 3, 3) [m] along every height change."""
        a, b, zla, zlb, zra, zrb, ol, orr = self._edge_steps(noded)
        # a closed mesh brings its own sides
        closed = np.array([isinstance(f, MeshFeature) and f.mesh.is_watertight
                           for f in self.features] + [False])
        keep = ~(closed[ol] | closed[orr])
        a, b, zla, zlb, zra, zrb = (x[keep] for x in (a, b, zla, zlb, zra, zrb))
        pa_l = np.column_stack([a, zla])
        pb_l = np.column_stack([b, zlb])
        pa_r = np.column_stack([a, zra])
        pb_r = np.column_stack([b, zrb])
        t1 = np.stack([pa_l, pb_l, pb_r], axis=1)
        t2 = np.stack([pa_l, pb_r, pa_r], axis=1)
        tri = np.concatenate([t1, t2])
        area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        return tri[area > 1e-12]
