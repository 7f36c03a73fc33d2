"""Terrain features: blocks, slopes, stair flights, rough heightfields, meshes.

Each feature is piecewise planar and answers, for (n, 2) points [m]: ``covers`` (on its
closed footprint), ``surface(xy, ref)`` (heights of the planar piece that contains
``ref``, evaluated at ``xy`` — exact on both sides of an edge), ``gradient``, ``breaks``
(2-D segments where its plane changes) and ``outline`` (segments drawn in the mesh).
"""

from __future__ import annotations

import enum
import functools
from dataclasses import dataclass, field

import numpy as np
import shapely
import trimesh
from shapely.geometry import Polygon

from crowdwalk.errors import existing_file, invalid

__all__ = [
    "TerrainKind",
    "Block",
    "Slope",
    "StairFlight",
    "Heightfield",
    "MeshFeature",
    "Feature",
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


_BOXES: dict[int, tuple[Polygon, bool]] = {}  # id(polygon) -> (polygon, it is its bbox)


def _is_box(poly: Polygon, bbox) -> bool:
    """Whether ``poly`` is the axis-aligned rectangle ``bbox`` (no holes, four corners):
    then a point is on it (closed) exactly when it is in the closed bbox, which is what
    GEOS's exact point-in-polygon test gives for axis-aligned edges."""
    known = _BOXES.get(id(poly))
    if known is not None and known[0] is poly:
        return known[1]
    corners = {(bbox[0], bbox[1]), (bbox[2], bbox[1]), (bbox[2], bbox[3]), (bbox[0], bbox[3])}
    ring = [tuple(c) for c in shapely.get_coordinates(poly.exterior)]
    box = (len(poly.interiors) == 0 and len(ring) == 5 and ring[0] == ring[-1]
           and set(ring[:-1]) == corners and len(corners) == 4)
    if len(_BOXES) > 4096:
        _BOXES.clear()
    _BOXES[id(poly)] = (poly, box)  # the polygon is kept: its id stays its own
    return box


def _covers_polygon(poly: Polygon, bbox, xy: np.ndarray) -> np.ndarray:
    mask = _in_bbox(xy, bbox)
    if mask.any() and not _is_box(poly, bbox):
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
        for name in ("width", "going", "rise"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
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
            mask[mask] = self._on_flight(xy[mask])
        return mask

    def _on_flight(self, xy) -> np.ndarray:
        """Whether each point (n, 2) [m] (inside the bbox) is on the flight; (n,) bool."""
        u, v = self._uv(xy)
        return (u >= 0) & (u <= self.length) & (np.abs(v) <= self.width / 2)

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
        """Footprint sides and inner risers (m, 2, 2) [m]; risers reach ``overshoot`` [m]
        beyond the sides."""
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
             rotate_z: float = 0.0, up: str = "z") -> MeshFeature:
        """Read OBJ/STL/PLY/GLB/... from ``path``; turn a ``up="y"`` file (the glTF
        convention, most DCC exports) to z up, scale, rotate about z by ``rotate_z``
        [rad], then translate (3,) [m]."""
        path = existing_file(path)
        if not scale > 0:
            raise invalid("MeshFeature", "scale", "> 0", scale)
        if up not in ("y", "z"):
            raise invalid("MeshFeature", "up", "'y' or 'z'", up)
        try:
            mesh = trimesh.load(path, force="mesh")
        except Exception as exc:  # noqa: BLE001 - loaders raise many types
            raise invalid("MeshFeature", "path", "a mesh file trimesh can read",
                          f"{path} ({exc})") from exc
        if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
            raise invalid("MeshFeature", "path", "a file with triangles", str(path))
        m = trimesh.transformations.rotation_matrix(rotate_z, [0, 0, 1])
        if up == "y":  # y up → z up: +90° about x
            m = m @ trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0])
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
