"""Static meshes of the world: terrain shaded by height, walkable-area outline, route graph.

Pure functions from the world's objects (``Terrain``, shapely geometry, networkx graph)
to pyvista meshes; lines are draped on the terrain (densified and lifted a little) so
they stay visible on slopes and stairs.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid

__all__ = [
    "terrain_mesh",
    "flat_ground",
    "terrain_edges",
    "outline_lines",
    "closed_walls",
    "route_lines",
    "node_positions",
    "polylines",
]


def terrain_mesh(terrain) -> pv.PolyData:
    """The terrain surface with the point scalar ``height`` [m].

    Parameters
    ----------
    terrain : crowdwalk.terrain.Terrain
        Anything with ``mesh() -> trimesh.Trimesh`` (vertices in metres, z up).
    """
    tm = terrain.mesh()
    vertices = np.asarray(tm.vertices, dtype=float)
    faces = np.asarray(tm.faces, dtype=np.int64)
    mesh = pv.PolyData(vertices, faces=np.column_stack([np.full(len(faces), 3), faces]).ravel())
    mesh.point_data["height"] = vertices[:, 2]
    return mesh


def flat_ground(geometry, z: float = 0.0) -> pv.PolyData:
    """A flat surface at height ``z`` [m] filling a shapely (multi)polygon [m], for runs
    whose terrain cannot be rebuilt; carries the point scalar ``height`` like the terrain."""
    import shapely

    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(geometry))
    if len(tris) == 0:
        return pv.PolyData()
    corners = shapely.get_coordinates(tris).reshape(len(tris), 4, 2)[:, :3]
    points = np.column_stack([corners.reshape(-1, 2), np.full(3 * len(tris), z)])
    faces = np.column_stack([np.full(len(tris), 3), np.arange(3 * len(tris)).reshape(-1, 3)])
    mesh = pv.PolyData(points, faces=faces.ravel()).clean()
    mesh.point_data["height"] = mesh.points[:, 2]
    return mesh


def terrain_edges(mesh: pv.PolyData, feature_angle: float = 30.0) -> pv.PolyData:
    """Sharp edges of the terrain (stair nosings, obstacle rims) as lines.

    Parameters
    ----------
    feature_angle : float
        Dihedral angle above which an edge is drawn [deg].
    """
    return mesh.extract_feature_edges(
        feature_angle=feature_angle, boundary_edges=False, non_manifold_edges=False,
        manifold_edges=False,
    )


def _drape(xy: np.ndarray, terrain, lift: float) -> np.ndarray:
    """Lift plan points (n,2) [m] onto the terrain; returns (n,3) [m]."""
    if terrain is None:
        return np.column_stack([xy, np.full(len(xy), lift)])
    return np.column_stack([xy, terrain.height(xy) + lift])


def polylines(paths: list[np.ndarray]) -> pv.PolyData:
    """One line mesh from several polylines, each (m_i, 3) [m]."""
    paths = [np.asarray(p, dtype=float) for p in paths if len(p) >= 2]
    if not paths:
        return pv.PolyData()
    sizes = np.array([len(p) for p in paths])
    starts = np.r_[0, np.cumsum(sizes)[:-1]]
    lines = np.concatenate(
        [np.r_[n, np.arange(s, s + n)] for n, s in zip(sizes, starts, strict=True)]
    )
    return pv.PolyData(np.concatenate(paths), lines=lines)


def _densify(points: np.ndarray, spacing: float) -> np.ndarray:
    """Insert points along a polyline (m,2) so no segment is longer than spacing [m]."""
    seg = np.diff(points, axis=0)
    lengths = np.hypot(seg[:, 0], seg[:, 1])
    pieces = np.maximum(1, np.ceil(lengths / spacing).astype(int))
    out = [points[i] + seg[i] * (np.arange(n) / n)[:, None] for i, n in enumerate(pieces)]
    return np.concatenate(out + [points[-1:]])


def outline_lines(geometry, terrain=None, lift: float = 0.03, spacing: float = 0.25):
    """Boundary of a shapely (multi)polygon draped on the terrain, as lines.

    Parameters
    ----------
    geometry : shapely geometry
        Walkable area [m].
    lift : float
        Height above the ground [m].
    spacing : float
        Longest segment before draping [m].
    """
    import shapely

    boundary = shapely.get_parts(shapely.boundary(geometry))
    rings = []
    for part in boundary:
        for line in shapely.get_parts(part):
            xy = np.asarray(line.coords)[:, :2]
            if len(xy) >= 2:
                rings.append(_drape(_densify(xy, spacing), terrain, lift))
    return polylines(rings)


def closed_walls(everywhere, now, terrain=None, height: float = 1.2,
                 min_area: float = 1e-3) -> pv.PolyData:
    """What is walkable at some time of a run but not ``now`` (shut doors: ``everywhere``
    minus ``now``, shapely geometries [m]) as solid walls ``height`` [m] tall standing on
    the ground; pieces smaller than ``min_area`` [m²] (slivers of the difference) left out.
    """
    import shapely

    parts = [p for p in shapely.get_parts(shapely.difference(everywhere, now))
             if p.geom_type == "Polygon" and p.area >= min_area]
    walls = pv.PolyData()
    for part in parts:
        base = 0.0
        if terrain is not None:
            xy = np.asarray(part.representative_point().coords)[:, :2]
            base = float(np.asarray(terrain.height(xy)).ravel()[0])
        top = flat_ground(part, z=base)
        if top.n_points:
            walls = walls.append_polydata(top.extrude((0.0, 0.0, height), capping=True))
    return walls


def node_positions(graph) -> dict:
    """Plan position (2,) [m] of every route-graph node.

    Reads the node attribute ``pos`` (or ``xy``, or ``x`` and ``y``).
    """
    out = {}
    for node, data in graph.nodes(data=True):
        if "pos" in data:
            xy = data["pos"]
        elif "xy" in data:
            xy = data["xy"]
        elif "x" in data and "y" in data:
            xy = (data["x"], data["y"])
        else:
            constraint = "a node with 'pos' (or 'x' and 'y') [m]"
            raise invalid("RouteGraph", f"nodes[{node!r}]", constraint, data)
        out[node] = np.asarray(xy, dtype=float)[:2]
    return out


def route_lines(graph, terrain=None, lift: float = 0.05, spacing: float = 0.25):
    """Route-graph edges along their corridors' centre lines (the edge attribute
    ``geometry``, a shapely line through the corridor's ``via`` points; a straight chord
    when absent), once per corridor, draped on the terrain, and the nodes as points.

    Returns
    -------
    (pyvista.PolyData, pyvista.PolyData)
        Edge lines and node points [m].
    """
    pos = node_positions(graph)
    edges, seen = [], set()
    for a, b, data in graph.edges(data=True):
        if frozenset((a, b)) in seen:
            continue  # the way back of a two-way corridor is the same line
        seen.add(frozenset((a, b)))
        line = data.get("geometry")
        xy = (np.asarray(line.coords, dtype=float)[:, :2] if line is not None
              else np.stack([pos[a], pos[b]]))
        edges.append(_drape(_densify(xy, spacing), terrain, lift))
    nodes = np.array([pos[n] for n in graph.nodes()]).reshape(-1, 2)
    return polylines(edges), pv.PolyData(_drape(nodes, terrain, lift)) if len(nodes) else None
