"""Terrain: exact heights at edges, override composition, profiles, normals, kinds, mesh."""

import math

import numpy as np
import pytest
import shapely
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.errors import InputError
from crowdwalk.terrain import (
    Block,
    Heightfield,
    MeshFeature,
    Slope,
    StairFlight,
    Terrain,
    TerrainKind,
)

EXTENT = (-20.0, -20.0, 20.0, 20.0)
coord = st.floats(-8, 8, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
FAST = settings(max_examples=40, deadline=None)


def profile_height(s_rows, z_rows, s):
    """Height of a piecewise-linear profile at s strictly between its vertices."""
    i = np.searchsorted(s_rows, s, side="right") - 1
    i = np.clip(i, 0, len(s_rows) - 2)
    s0, s1, z0, z1 = s_rows[i], s_rows[i + 1], z_rows[i], z_rows[i + 1]
    w = np.where(s1 > s0, (s - s0) / np.where(s1 > s0, s1 - s0, 1), 0)
    return z0 + w * (z1 - z0)


def demo_terrain():
    return Terrain(EXTENT, 0.0, (
        Slope.ramp((-10, -10), 0.3, 8, 3, 0.0, 0.6),
        StairFlight((0, 0), 0.4, 2.0, 0.28, 0.16, 7),
        Block.box((4.0, 3.0), (3, 2), 1.12, heading=0.4),
        Block([(-5, 5), (-2, 5), (-3, 8)], 0.15),
        Heightfield.noise((6, -12), (6, 5), 0.5, 0.05, 1.0, seed=3, base=0.1),
        StairFlight((-12, 10), -1.2, 2.5, 0.3, 0.15, 4, z0=0.0, up=False),
    ))


@FAST
@given(cx=coord, cy=coord, length=st.floats(0.2, 6), width=st.floats(0.2, 6),
       heading=angle, top=st.floats(-1, 2), base=st.floats(-1, 1),
       pts=st.lists(st.tuples(st.floats(-15, 15), st.floats(-15, 15)), min_size=1, max_size=40))
def test_block_top_inside_base_outside(cx, cy, length, width, heading, top, base, pts):
    block = Block.box((cx, cy), (length, width), top, heading)
    ter = Terrain(EXTENT, base, (block,))
    xy = np.array(pts)
    z = ter.height(xy)
    inside = shapely.contains_xy(block.footprint, xy[:, 0], xy[:, 1])
    outside = ~shapely.intersects_xy(block.footprint, xy[:, 0], xy[:, 1])
    assert np.all(z[inside] == top)
    assert np.all(z[outside] == base)
    assert np.all(ter.kind(xy)[inside] == TerrainKind.BLOCK)
    assert np.all(ter.kind(xy)[outside] == TerrainKind.FLAT)


@FAST
@given(sx=coord, sy=coord, heading=angle, width=st.floats(0.5, 4), going=st.floats(0.2, 0.5),
       rise=st.floats(0.05, 0.25), steps=st.integers(1, 12), up=st.booleans(),
       z0=st.floats(-1, 1))
def test_stair_edges_exactly_where_built(sx, sy, heading, width, going, rise, steps, up, z0):
    flight = StairFlight((sx, sy), heading, width, going, rise, steps, z0, up)
    ter = Terrain((-30, -30, 30, 30), z0, (flight,))
    d = np.array([math.cos(heading), math.sin(heading)])
    lat = np.array([-d[1], d[0]])
    eps = 1e-6
    for k in range(steps + 1):
        for v in (-0.45 * width, 0.0, 0.45 * width):
            before = np.array([sx, sy]) + (k * going - eps) * d + v * lat
            after = np.array([sx, sy]) + (k * going + eps) * d + v * lat
            zb, za = ter.height(np.stack([before, after]))
            sign = 1 if up else -1
            assert zb == pytest.approx(z0 + sign * k * rise, abs=1e-12)
            expect_after = z0 + sign * (k + 1) * rise if k < steps else z0
            assert za == pytest.approx(expect_after, abs=1e-12)
    # sideways off the flight is the base
    side = np.array([sx, sy]) + 0.5 * going * d + (width / 2 + eps) * lat
    assert ter.height(side)[0] == z0


@FAST
@given(pts=st.lists(st.tuples(st.floats(-15, 15), st.floats(-15, 15)), min_size=2, max_size=6),
       frac=st.lists(st.floats(0.001, 0.999), min_size=5, max_size=30))
def test_profile_agrees_with_point_queries(pts, frac):
    ter = demo_terrain()
    poly = np.array(pts)
    s_rows, z_rows = ter.profile_arrays(poly)
    assert np.all(np.diff(s_rows) >= 0)
    seg = np.linalg.norm(np.diff(poly, axis=0), axis=1)
    total = seg.sum()
    if total < 1e-6:
        return
    assert s_rows[-1] == pytest.approx(total, abs=1e-8)  # sub-nm legs are dropped
    s = np.array(frac) * total
    # query away from the profile's vertices: at a vertical change the profile has two
    # values, and a path may merely touch a footprint's corner there (measure zero)
    s = s[np.all(np.abs(s[:, None] - s_rows[None, :]) > 1e-7, axis=1)]
    if len(s) == 0:
        return
    cum = np.concatenate([[0], np.cumsum(seg)])
    j = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1)
    ok = seg[j] > 0
    s, j = s[ok], j[ok]
    xy = poly[j] + ((s - cum[j]) / seg[j])[:, None] * (poly[j + 1] - poly[j])
    np.testing.assert_allclose(profile_height(s_rows, z_rows, s), ter.height(xy), atol=1e-9)


@FAST
@given(offset=st.floats(-0.9, 0.9), angle_off=st.floats(-1.0, 1.0))
def test_profile_locates_every_riser(offset, angle_off):
    """A straight line across a flight: each vertical change sits on the riser line."""
    flight = StairFlight((0.0, 0.0), 0.0, 2.0, 0.3, 0.17, 5)
    ter = Terrain(EXTENT, 0.0, (flight,))
    a = np.array([-2.0, offset - 2 * math.tan(angle_off) * 0.3])
    direction = np.array([math.cos(angle_off), math.sin(angle_off)])
    b = a + 6 * direction
    s_rows, z_rows = ter.profile_arrays(np.stack([a, b]))
    jump_s = s_rows[1:][np.diff(s_rows) == 0]
    jump_xy = a + jump_s[:, None] * direction
    on_flight = np.abs(jump_xy[:, 1]) < 1 - 1e-9
    u = jump_xy[on_flight, 0]
    # every vertical change on the flight lies on a riser line u = k * going (< 1 mm; exact)
    k = np.round(u / 0.3)
    np.testing.assert_allclose(u, k * 0.3, atol=1e-9)
    # and the heights agree with point queries just before/after each change
    for sj in jump_s:
        zb, za = ter.height(a + np.array([sj - 1e-4, sj + 1e-4])[:, None] * direction)
        rows = z_rows[1:][np.diff(s_rows) == 0][jump_s == sj]
        assert za == pytest.approx(rows[0], abs=1e-9)


def test_ground_profile_type_and_right_continuity():
    ter = Terrain(EXTENT, 0.0, (StairFlight((1.0, 0.0), 0.0, 2.0, 0.3, 0.17, 3),))
    prof = ter.profile([[0.0, 0.0], [3.0, 0.0]])
    assert type(prof).__name__ == "GroundProfile"
    np.testing.assert_allclose(prof.height(np.array([0.5, 1.0, 1.15, 1.3, 1.8, 2.5])),
                               [0, 0.17, 0.17, 0.34, 0.51, 0], atol=1e-12)


def test_override_order_later_feature_wins():
    platform = Block.box((0, 0), (6, 6), 1.0)
    pit_stairs = StairFlight((0, 0), 0.0, 2.0, 0.3, 0.2, 4, z0=1.0, up=False)
    ter = Terrain(EXTENT, 0.0, (platform, pit_stairs))
    assert ter.height([[0.1, 0.0]])[0] == pytest.approx(0.8)
    assert ter.height([[1.0, 0.0]])[0] == pytest.approx(0.2)
    assert ter.height([[-1.0, 0.0]])[0] == 1.0
    swapped = Terrain(EXTENT, 0.0, (pit_stairs, platform))
    assert swapped.height([[1.0, 0.0]])[0] == 1.0


def test_normals_slope_and_treads():
    grade = 0.1
    ramp = Slope.ramp((0, 0), math.pi / 2, 5, 2, 0.0, 5 * grade)
    ter = Terrain(EXTENT, 0.0, (ramp, StairFlight((5, 0), 0.0, 2, 0.3, 0.17, 3)))
    n = ter.normal([[0, 1], [5.1, 0], [-5, -5]])
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    np.testing.assert_allclose(n[0], np.array([0, -grade, 1]) / math.hypot(1, grade), atol=1e-12)
    np.testing.assert_allclose(n[1:], [[0, 0, 1], [0, 0, 1]])
    assert list(ter.kind([[0, 1], [5.1, 0], [-5, -5]])) == [TerrainKind.SLOPE,
                                                            TerrainKind.STAIRS, TerrainKind.FLAT]


def test_slope_incline_heights():
    s = Slope([(0, 0), (4, 0), (4, 4), (0, 4)], (0, 0), 0.5, 0.0, math.tan(math.radians(5)))
    ter = Terrain(EXTENT, 0.0, (s,))
    assert ter.height([[2.0, 1.0]])[0] == pytest.approx(0.5 + 2 * math.tan(math.radians(5)))


def test_heightfield_nodes_exact_and_seeded():
    h = np.array([[0.0, 0.1, 0.3], [0.2, 0.4, 0.0]])
    hf = Heightfield((1.0, 2.0), 0.5, h)
    ter = Terrain(EXTENT, 0.0, (hf,))
    jj, ii = np.meshgrid(range(2), range(3), indexing="ij")
    nodes = np.stack([1.0 + 0.5 * ii.ravel(), 2.0 + 0.5 * jj.ravel()], 1)
    np.testing.assert_allclose(ter.height(nodes), h.ravel(), atol=1e-12)
    assert ter.kind(nodes[:1])[0] == TerrainKind.ROUGH
    # each cell is two planar triangles split along the (1, 0)-(0, 1) diagonal
    n = ter.normal([[1.1, 2.1], [1.4, 2.4]])
    expect = np.array([[-0.2, -0.4, 1.0], [-0.4, -0.6, 1.0]])
    np.testing.assert_allclose(n, expect / np.linalg.norm(expect, axis=1, keepdims=True))
    np.testing.assert_allclose(ter.height([[1.1, 2.1], [1.4, 2.4]]),
                               [0.2 * 0.1 + 0.4 * 0.1, 0.4 - 0.4 * 0.1 - 0.6 * 0.1])
    a = Heightfield.noise((0, 0), (4, 4), 0.25, 0.05, 1.0, seed=7)
    b = Heightfield.noise((0, 0), (4, 4), 0.25, 0.05, 1.0, seed=7)
    c = Heightfield.noise((0, 0), (4, 4), 0.25, 0.05, 1.0, seed=8)
    assert np.array_equal(a.heights, b.heights) and not np.array_equal(a.heights, c.heights)
    assert a.heights.std() == pytest.approx(0.05, rel=1e-6)


def test_mesh_feature_from_file(tmp_path):
    box = trimesh.creation.box(extents=(2, 2, 0.5))
    box.apply_translation((3, 3, 0.25))
    path = tmp_path / "box.stl"
    box.export(path)
    feat = MeshFeature.load(path, translate=(1.0, 0.0, 0.0))
    ter = Terrain(EXTENT, 0.0, (feat,))
    z = ter.height([[4.0, 3.0], [4.0, 5.5], [4.5, 2.5]])
    np.testing.assert_allclose(z, [0.5, 0.0, 0.5], atol=1e-9)
    assert list(ter.kind([[4.0, 3.0], [0, 0]])) == [TerrainKind.MESH, TerrainKind.FLAT]
    s, zp = ter.profile_arrays([[0.0, 3.0], [8.0, 3.0]])
    jumps = s[1:][np.diff(s) == 0]
    np.testing.assert_allclose(jumps, [3.0, 5.0], atol=1e-9)
    mesh = ter.mesh()
    up = mesh.face_normals[:, 2] > 0.99
    c = mesh.triangles_center[up]
    np.testing.assert_allclose(ter.height(c[:, :2]), c[:, 2], atol=1e-9)
    assert mesh.bounds[1, 2] == pytest.approx(0.5)
    with pytest.raises(FileNotFoundError):
        MeshFeature.load(tmp_path / "missing.obj")


def test_mesh_matches_heights_and_covers_extent():
    ter = demo_terrain()
    mesh = ter.mesh()
    up = np.abs(mesh.face_normals[:, 2]) > 1e-9
    c = mesh.triangles_center[up]
    np.testing.assert_allclose(ter.height(c[:, :2]), c[:, 2], atol=1e-9)
    projected = (mesh.area_faces[up] * np.abs(mesh.face_normals[up, 2])).sum()
    x0, y0, x1, y1 = EXTENT
    assert projected == pytest.approx((x1 - x0) * (y1 - y0), rel=1e-9)
    assert (mesh.face_normals[up, 2] > 0).all()


def test_mesh_block_walls_are_vertical_and_complete():
    ter = Terrain(EXTENT, 0.0, (Block.box((0, 0), (2, 1), 0.3, heading=0.7),))
    mesh = ter.mesh()
    wall = np.abs(mesh.face_normals[:, 2]) < 1e-9
    assert mesh.area_faces[wall].sum() == pytest.approx(2 * (2 + 1) * 0.3, rel=1e-9)


def test_bad_input_messages():
    with pytest.raises(InputError, match=r"StairFlight\.rise must be > 0 \[m\]; got -0\.1"):
        StairFlight((0, 0), 0.0, 1.0, 0.3, -0.1, 3)
    with pytest.raises(InputError, match=r"StairFlight\.steps must be an integer ≥ 1"):
        StairFlight((0, 0), 0.0, 1.0, 0.3, 0.1, 0)
    with pytest.raises(InputError, match=r"Terrain\.features\[0\] must be inside the extent"):
        Terrain((0, 0, 5, 5), 0.0, (Block.box((5, 5), (1, 1), 0.2),))
    with pytest.raises(InputError, match=r"Terrain\.xy must be an \(n, 2\) array"):
        Terrain.flat((0, 0, 5, 5)).height(np.zeros((3, 3)))
    with pytest.raises(InputError, match=r"Block\.footprint must be a valid polygon"):
        Block([(0, 0), (1, 1), (1, 0), (0, 1)], 0.2)
    with pytest.raises(InputError, match=r"Terrain\.extent must be"):
        Terrain((0, 0, -1, 5))


@FAST
@given(lines=st.lists(st.lists(st.tuples(st.floats(-15, 15), st.floats(-15, 15)), min_size=2,
                               max_size=4), min_size=1, max_size=6))
def test_batched_profiles_equal_single_profiles(lines):
    ter = demo_terrain()
    batch = ter.profiles([np.array(pl) for pl in lines])
    for pl, (s, z) in zip(lines, batch, strict=True):
        s1, z1 = ter.profile_arrays(np.array(pl))
        assert s.shape == s1.shape
        np.testing.assert_allclose(s, s1, rtol=0, atol=1e-12)
        np.testing.assert_allclose(z, z1, rtol=0, atol=1e-12)


@FAST
@given(lines=st.lists(st.tuples(st.floats(-15, 15), st.floats(-15, 15), st.floats(-15, 15),
                                st.floats(-15, 15)), min_size=1, max_size=8))
def test_stacked_straight_lines_equal_the_list_of_polylines(lines):
    ter = demo_terrain()
    stacked = np.array(lines).reshape(-1, 2, 2)
    stacked[::3, 1] = stacked[::3, 0]  # some lines are a single point
    for (s, z), (s1, z1) in zip(ter.profiles(stacked), ter.profiles(list(stacked)),
                                strict=True):
        assert np.array_equal(s, s1) and np.array_equal(z, z1)


@FAST
@given(lines=st.lists(st.tuples(st.floats(-15, 15), st.floats(-15, 15), st.floats(-15, 15),
                                st.floats(-15, 15)), min_size=1, max_size=8),
       every=st.integers(1, 4))
def test_packed_profiles_are_the_profiles_concatenated(lines, every):
    ter = demo_terrain()
    stacked = np.array(lines).reshape(-1, 2, 2)
    stacked[::every, 1] = stacked[::every, 0]  # some lines are a single point
    s, z, sizes = ter.profiles_packed(stacked)
    each = ter.profiles(stacked)
    assert sizes.tolist() == [len(p[0]) for p in each]
    assert np.array_equal(s, np.concatenate([p[0] for p in each]))
    assert np.array_equal(z, np.concatenate([p[1] for p in each]))


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), n_blocks=st.integers(17, 60))
def test_many_features_grid_index_matches_plain_override(seed, n_blocks):
    """With many features a grid index picks candidates; the result must not change."""
    rng = np.random.default_rng(seed)
    feats = [Block.box(rng.uniform(-15, 15, 2), rng.uniform(0.2, 3, 2), rng.uniform(0, 1),
                       rng.uniform(-3, 3)) for _ in range(n_blocks)]
    feats.insert(int(rng.integers(0, n_blocks)), StairFlight((-5, -5), 0.3, 6, 0.3, 0.1, 20))
    ter = Terrain(EXTENT, 0.0, tuple(feats))
    xy = rng.uniform(-21, 21, (500, 2))
    plain = np.full(len(xy), -1)
    for i, f in enumerate(ter.features):
        plain[f.covers(xy)] = i
    np.testing.assert_array_equal(ter.owner(xy), plain)


@FAST
@given(pts=st.lists(st.tuples(st.floats(-15, 15), st.floats(-15, 15)), min_size=1, max_size=50))
def test_normals_match_finite_differences_of_height(pts):
    ter = demo_terrain()
    xy = np.array(pts)
    h = 1e-5
    offsets = np.array([[h, 0], [-h, 0], [0, h], [0, -h]])
    stencil = xy[:, None, :] + offsets[None]
    own = ter.owner(stencil.reshape(-1, 2)).reshape(-1, 4)
    z = ter.height(stencil.reshape(-1, 2)).reshape(-1, 4)
    # only where all four stencil points lie on the same planar piece as the centre
    centre = ter.owner(xy)
    same = (own == centre[:, None]).all(1)
    gx = (z[:, 0] - z[:, 1]) / (2 * h)
    gy = (z[:, 2] - z[:, 3]) / (2 * h)
    expect = np.column_stack([-gx, -gy, np.ones(len(xy))])
    expect /= np.linalg.norm(expect, axis=1, keepdims=True)
    n = ter.normal(xy)
    zc = ter.height(xy)
    # and where the ground has no kink there (a rough-ground grid line or diagonal)
    smooth = same & (np.abs(z - zc[:, None]).max(1) < 0.01)
    smooth &= (np.abs(z[:, 0] + z[:, 1] - 2 * zc) < 1e-11) & (np.abs(z[:, 2] + z[:, 3] - 2 * zc)
                                                              < 1e-11)
    np.testing.assert_allclose(n[smooth], expect[smooth], atol=1e-4)


def test_steps_cover_only_where_the_change_is_high_enough():
    # a slope falling to -1.4 m: its sides are walls only where they drop more than 0.5 m
    grade = -0.07
    slope = Slope([(0, 0), (10, 0), (10, 20), (0, 20)], (0, 0), 0.0, math.pi / 2, grade)
    ter = Terrain(EXTENT, 0.0, (slope, Block.box((-10, -10), (2, 2), 0.3)))
    steps = ter.steps(0.5)
    ys = steps[:, :, 1]
    start = 0.5 / -grade
    sides = np.isclose(steps[:, 0, 0], steps[:, 1, 0])  # the two sides x = 0 and x = 10
    assert sides.sum() == 2
    np.testing.assert_allclose(ys[sides].min(axis=1), start, atol=1e-9)
    np.testing.assert_allclose(ys[sides].max(axis=1), 20, atol=1e-9)
    assert len(ter.steps(0.2)) > len(steps)  # the 0.3 m block joins at a lower threshold
    assert np.abs(steps).max() <= 20


@pytest.mark.parametrize("suffix", ["obj", "ply", "glb", "stl"])
def test_mesh_formats(tmp_path, suffix):
    box = trimesh.creation.box(extents=(2, 2, 0.3))
    box.apply_translation((0, 0, 0.15))
    path = tmp_path / f"box.{suffix}"
    box.export(path)
    feat = MeshFeature.load(path, translate=(3.0, 1.0, 0.0), rotate_z=math.radians(45))
    ter = Terrain(EXTENT, 0.0, (feat,))
    # rotated by 45°: (3 + 1.3, 1) is inside the turned box's corner reach, (3 + 1.1, 2.1) not
    z = ter.height([[3.0, 1.0], [4.3, 1.0], [4.1, 2.1]])
    np.testing.assert_allclose(z, [0.3, 0.3, 0.0], atol=1e-9)


def test_mesh_y_up_and_unreadable(tmp_path):
    box = trimesh.creation.box(extents=(2, 0.4, 2))  # 0.4 m tall along y
    box.apply_translation((0, 0.2, 0))
    path = tmp_path / "y_up.glb"
    box.export(path)
    ter = Terrain(EXTENT, 0.0, (MeshFeature.load(path, up="y"),))
    assert ter.height([[0.0, 0.0]])[0] == pytest.approx(0.4)
    bad = tmp_path / "bad.obj"
    bad.write_text("this is not a mesh\n")
    with pytest.raises(InputError, match=r"MeshFeature\.path must be a"):
        MeshFeature.load(bad)
    with pytest.raises(InputError, match=r"MeshFeature\.up must be 'y' or 'z'"):
        MeshFeature.load(path, up="x")


def test_the_crossings_kernel_finds_what_the_numpy_pairs_find_bit_for_bit():
    from crowdwalk.terrain.ground import _crossings, _EdgeIndex

    rng = np.random.default_rng(4)
    edges = rng.uniform(0, 10, (120, 2, 2))
    edges[:10, 1] = edges[:10, 0]  # degenerate edges
    edges[10:20, :, 0] = 5.0  # vertical edges
    index = _EdgeIndex(edges)
    a = rng.uniform(0, 10, (3000, 2))
    b = a + rng.uniform(-1, 1, (3000, 2))
    b[:50] = a[:50]  # points
    a[50:60] = edges[20:30, 0]  # starting on an edge's end
    seg, t = _crossings(a, b, index)

    # the numpy pairs of the bounding-box test and the crossing test, as before the kernel
    e0, e = edges[:, 0], edges[:, 1] - edges[:, 0]
    near = ((np.maximum(a, b)[:, None] >= index.lo - 1e-9).all(-1)
            & (np.minimum(a, b)[:, None] <= index.hi + 1e-9).all(-1))
    i, j = np.nonzero(near)
    d, r, ej = b[i] - a[i], e0[j] - a[i], e[j]
    den = d[:, 0] * ej[:, 1] - d[:, 1] * ej[:, 0]
    ok = np.abs(den) > 1e-15
    den = np.where(ok, den, 1.0)
    tt = (r[:, 0] * ej[:, 1] - r[:, 1] * ej[:, 0]) / den
    u = (r[:, 0] * d[:, 1] - r[:, 1] * d[:, 0]) / den
    ok &= (tt >= -1e-12) & (tt <= 1 + 1e-12) & (u >= -1e-12) & (u <= 1 + 1e-12)
    assert ok.sum() > 100
    np.testing.assert_array_equal(seg, i[ok])
    assert np.array_equal(t.view(np.int64), np.clip(tt[ok], 0.0, 1.0).view(np.int64))


def test_footing_tells_obstacles_as_cutting_every_chord_does():
    ter = Terrain(EXTENT, 0.0, (
        Block.box((4.0, 3.0), (3, 2), 1.12, heading=0.4),  # wider than a stride
        Block.box((-4.0, -3.0), (0.4, 6), 0.2, heading=-0.3),  # a curb: short chords across
        Block(shapely.Polygon([(-15, 5), (-5, 5), (-5, 15), (-15, 15)],
                              [[(-11, 9), (-9, 9), (-9, 11), (-11, 11)]]), 0.3),  # a hole
        Slope.ramp((10, -10), 0.3, 8, 3, 0.0, 0.6),
    ))
    rng = np.random.default_rng(2)
    xy = np.concatenate([rng.uniform(-16, 16, (20000, 2)),
                         rng.uniform([-5.5, -6.5], [-2.5, 0.5], (5000, 2))])  # the curb
    a = rng.uniform(-np.pi, np.pi, xy.shape[0])
    direction = np.column_stack([np.cos(a), np.sin(a)])
    stride = rng.uniform(0.3, 1.5, xy.shape[0])
    kind, obstacle = ter.footing(xy, direction, stride=stride)
    # every block foothold's chord cut, as before the outline bound
    own = ter.owner(xy)
    block = np.flatnonzero(kind == TerrainKind.BLOCK)
    lines = shapely.linestrings(np.stack([xy[block] - 2.0 * direction[block],
                                          xy[block] + 2.0 * direction[block]], axis=1))
    polys = np.array([ter.features[k].footprint for k in own[block]], dtype=object)
    want = np.zeros(xy.shape[0], bool)
    want[block] = shapely.length(shapely.intersection(lines, polys)) <= stride[block]
    assert want.any() and (~want[block]).any()
    np.testing.assert_array_equal(obstacle, want)


def test_compiled_owner_of_boxes_and_stairs_is_the_feature_loop():
    """Terrain.owner's one-pass bbox tests (every feature a box Block or a StairFlight)
    and the compiled grouping of owners give what the per-feature loop gives, bit for bit:
    on the bbox edges and their nextafter neighbours, at a turned flight, in small calls."""
    from shapely.geometry import Polygon

    from crowdwalk.terrain.features import Block, StairFlight

    features = (
        Block(Polygon([(0, 10), (20, 10), (20, 20), (0, 20)]), top=1.02),
        StairFlight((5.0, 10.0), -np.pi / 2, 3.0, 0.3, 0.17, 6, z0=1.02, up=False),
        StairFlight((14.0, 8.0), 0.4, 2.5, 0.28, 0.15, 5, z0=0.0, up=True),
        Block(Polygon([(12, 12), (16, 12), (16, 15), (12, 15)]), top=1.5),
    )
    t = Terrain((0, 0, 30, 30), base=0.0, features=features)
    assert t._boxes is not None  # the compiled path
    rng = np.random.default_rng(3)
    pts = [rng.uniform(0, 30, (20000, 2))]
    for f in features:
        x0, y0, x1, y1 = f.bbox
        for bx in (x0, x1):
            ys = rng.uniform(y0, y1, 200)
            for d in (-np.inf, np.inf):
                pts.append(np.stack([np.nextafter(np.full(200, bx), d), ys], 1))
            pts.append(np.stack([np.full(200, bx), ys], 1))
        for by in (y0, y1):
            xs = rng.uniform(x0, x1, 200)
            for d in (-np.inf, np.inf):
                pts.append(np.stack([xs, np.nextafter(np.full(200, by), d)], 1))
            pts.append(np.stack([xs, np.full(200, by)], 1))
    xy = np.concatenate(pts)
    want = np.full(len(xy), -1, dtype=np.int64)
    for i, f in enumerate(features):
        want[f.covers(xy)] = i
    z = np.full(len(xy), 0.0)
    for i, f in enumerate(features):
        k = np.flatnonzero(want == i)
        if len(k):
            z[k] = f.surface(xy[k], xy[k])
    assert np.array_equal(t.owner(xy), want)
    assert t.height(xy).tobytes() == z.tobytes()
    for a in range(0, 400, 7):  # small calls: the same rows
        assert t.height(xy[a:a + 7]).tobytes() == z[a:a + 7].tobytes()
    assert len(np.unique(want)) == 5  # every feature and the base own points
