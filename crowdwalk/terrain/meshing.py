"""The ground as one triangle mesh, and where its height changes.

The outlines of all features and the extent are noded into one planar arrangement
(shapely ``union_all`` + ``polygonize``). Every face of it has a single owner (the base
or one feature, by the override rule) and lies on one plane, so it is triangulated
exactly (``constrained_delaunay_triangles``) and lifted onto that plane; rough ground is
drawn by its own grid triangles clipped to its visible region, meshes by their own faces.
Along every noded edge whose two sides differ in height a vertical wall is added (stair
risers, block sides): no smoothing across an edge.
"""

from __future__ import annotations

import numpy as np
import shapely
import trimesh

from crowdwalk.terrain.features import MeshFeature, _in_bbox, _ring_segments

__all__ = ["ground_mesh", "height_steps"]


def height_steps(terrain, min_height: float = 0.0) -> np.ndarray:
    """Edges where the ground of ``terrain`` changes height by more than ``min_height``
    [m] (risers, curbs, block sides, walls) as segments (m, 2, 2) [m]; an edge whose step
    height varies (a slope's side) is kept only where it exceeds ``min_height``."""
    a, b, zla, zlb, zra, zrb, _, _ = _edge_steps(terrain, terrain._arrangement)
    ja, jb = zla - zra, zlb - zrb  # the step height varies linearly along an edge
    d = b - a
    out = []
    for sign in (1.0, -1.0):  # where sign·j(t) > min_height, t ∈ [0, 1]
        fa, fb = sign * ja - min_height, sign * jb - min_height
        with np.errstate(divide="ignore", invalid="ignore"):
            t0 = np.where(fa == fb, 0.0, fa / (fa - fb))  # root of the linear function
        lo = np.where(fa > 0, 0.0, np.clip(t0, 0, 1))
        hi = np.where(fb > 0, 1.0, np.clip(t0, 0, 1))
        keep = ((fa > 0) | (fb > 0)) & (hi - lo > 1e-12)
        out.append(np.stack([a + lo[:, None] * d, a + hi[:, None] * d], axis=1)[keep])
    return np.concatenate(out)


def ground_mesh(terrain) -> trimesh.Trimesh:
    """The whole ground of ``terrain`` as one triangle mesh [m]: treads, tops and slopes
    as exact planar faces, vertical risers and block sides, rough and mesh features by
    their own triangles (clipped to where they are visible); faces oriented upward."""
    noded = terrain._arrangement
    faces = np.asarray(shapely.get_parts(shapely.polygonize(shapely.get_parts(noded))))
    faces = faces[shapely.area(faces) > 1e-12]
    rep = shapely.get_coordinates(shapely.point_on_surface(faces))
    own = terrain.owner(rep)
    tris, refs, owners = [], [], []
    planar = np.array([o < 0 or not hasattr(terrain.features[o], "triangles") for o in own])
    if planar.any():
        t, ref, k = _triangulate(faces[planar], rep[planar])
        tris.append(t)
        refs.append(ref)
        owners.append(own[planar][k])
    as_is = []  # meshes: their own faces, where visible
    for o in np.unique(own[~planar]):
        region = shapely.union_all(faces[own == o])
        feat = terrain.features[o]
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
        t, ref, _ = _triangulate(clipped[ok], centroid)
        tris.append(t)
        refs.append(ref)
        owners.append(np.full(len(t), o))
    tri2 = np.concatenate(tris)
    flat = tri2.reshape(-1, 2)
    rref = np.repeat(np.concatenate(refs), 3, axis=0)
    z = terrain._surface(flat, rref, np.repeat(np.concatenate(owners), 3))
    verts = [np.column_stack([flat, z])] + [t.reshape(-1, 3) for t in as_is]
    # vertical walls along every noded edge where the two sides differ in height
    walls = _walls(terrain, noded)
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


def _triangulate(polys, rep):
    """Triangles (t, 3, 2) [m] of polygons, each polygon's reference point (t, 2) and
    the polygon index (t,)."""
    cdt = shapely.constrained_delaunay_triangles(polys)
    parts, idx = shapely.get_parts(cdt, return_index=True)
    coords = shapely.get_coordinates(parts).reshape(-1, 4, 2)[:, :3]
    return coords, rep[idx], idx


def _edge_steps(terrain, noded):
    """Noded edges with different heights on their two sides: end points a, b (m, 2)
    and the heights at a and b on the left and right side (m,) each [m], and the
    owners of the left and right side (m,) each."""
    segs = _ring_segments(noded)
    if len(segs) == 0:
        return (np.zeros((0, 2)),) * 2 + (np.zeros(0),) * 4 + (np.zeros(0, int),) * 2
    a, b = segs[:, 0], segs[:, 1]
    d = b - a
    length = np.linalg.norm(d, axis=1)
    a, b, d, length = (x[length > 1e-6] for x in (a, b, d, length))
    nrm = np.column_stack([-d[:, 1], d[:, 0]]) / length[:, None]
    mid = 0.5 * (a + b)
    left, right = mid + 1e-6 * nrm, mid - 1e-6 * nrm
    inside = _in_bbox(left, terrain.extent) & _in_bbox(right, terrain.extent)
    a, b, left, right = a[inside], b[inside], left[inside], right[inside]
    ol, orr = terrain.owner(left), terrain.owner(right)
    ab = np.concatenate([a, b])
    zl = terrain._surface(ab, np.concatenate([left, left]), np.concatenate([ol, ol]))
    zr = terrain._surface(ab, np.concatenate([right, right]), np.concatenate([orr, orr]))
    n = len(a)
    zla, zlb, zra, zrb = zl[:n], zl[n:], zr[:n], zr[n:]
    diff = (np.abs(zla - zra) > 1e-9) | (np.abs(zlb - zrb) > 1e-9)
    return tuple(x[diff] for x in (a, b, zla, zlb, zra, zrb, ol, orr))


def _walls(terrain, noded) -> np.ndarray:
    """Vertical wall triangles (m, 3, 3) [m] along every height change."""
    a, b, zla, zlb, zra, zrb, ol, orr = _edge_steps(terrain, noded)
    # a closed mesh brings its own sides
    closed = np.array([isinstance(f, MeshFeature) and f.mesh.is_watertight
                       for f in terrain.features] + [False])
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
