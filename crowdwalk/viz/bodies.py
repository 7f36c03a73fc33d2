"""Every walker as a shaded solid body, all walkers in one mesh.

A body is limb capsules (thighs, shanks, feet, upper arms, forearms, neck: tapered
cylinders closed by half-spheres) and three ellipsoid volumes (pelvis, chest, head),
placed from the joint world positions of one frame and scaled by the walker's own segment
lengths (the body height is read off the thigh, Winter's 0.245 H; radii are fractions of
it). Skeletons without the H-Anim joint names (e.g. trajectory poles) get a capsule per
bone and a head on the topmost joint.

All geometry is written with numpy into one :class:`pyvista.PolyData`; its topology
depends only on the number of walkers, so a frame with as many walkers as the last one
only overwrites point coordinates and normals in place. Normals are analytic.
Colours are direct RGB point scalars (``"rgb"``), one colour per walker.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid

__all__ = ["Detail", "SolidBodies", "bone_pairs", "detail_for"]

THIGH_FRACTION = 0.245  # thigh length / body height (Winter 2009, Fig. 4.1)
REFERENCE_HEIGHT = 1.75  # [m] the radii below are for this height

# Capsules of the H-Anim skeleton: (proximal joint, distal joint, radius there, radius
# here) [m] at REFERENCE_HEIGHT; feet and neck are placed by _hanim_parts.
_LIMBS = (
    ("l_hip", "l_knee", 0.078, 0.056), ("r_hip", "r_knee", 0.078, 0.056),
    ("l_knee", "l_talocrural", 0.054, 0.038), ("r_knee", "r_talocrural", 0.054, 0.038),
    ("l_shoulder", "l_elbow", 0.047, 0.039), ("r_shoulder", "r_elbow", 0.047, 0.039),
    ("l_elbow", "l_wrist", 0.038, 0.031), ("r_elbow", "r_wrist", 0.038, 0.031),
)  # fmt: skip
_HANIM = ("HumanoidRoot", "l_hip", "r_hip", "l_talocrural", "l_metatarsal", "r_talocrural",
          "r_metatarsal", "vl5", "skullbase", "l_shoulder", "r_shoulder", "l_elbow",
          "r_elbow", "l_wrist", "r_wrist", "l_knee", "r_knee")
_FOOT_RADIUS = 0.034
_HEEL_BEHIND, _ANKLE_HEIGHT, _TOE_AHEAD = 0.038, 0.039, 0.035  # [H] heel, ankle, toe tip
_REST_FOOT_PITCH = np.arctan2(0.039, 0.073)  # ankle→ball below the sole line [rad]


def bone_pairs(parents: np.ndarray) -> np.ndarray:
    """Joint index pairs (child, parent) of every bone, (B, 2) int, from parents (J,)
    (-1 for the root)."""
    parents = np.asarray(parents, dtype=np.int64)
    if parents.ndim != 1 or parents.size == 0:
        raise invalid("SolidBodies", "parents", "a non-empty (J,) integer array", parents.shape)
    if np.any(parents >= parents.size) or np.any(parents < -1):
        raise invalid("SolidBodies", "parents", f"indices in [-1, {parents.size})", parents)
    child = np.flatnonzero(parents >= 0)
    return np.column_stack([child, parents[child]])


@dataclass(frozen=True)
class Detail:
    """Tessellation of one body: ``sides`` facets around a capsule, ``caps`` rings per
    half-sphere cap (0: open tube), ``sphere`` icosphere subdivisions of the volumes."""

    sides: int
    caps: int
    sphere: int


def detail_for(n_agents: int) -> Detail:
    """Level of detail for a crowd of ``n_agents``: software rendering cost grows with the
    triangle count, and a large crowd is seen from afar (``benchmarks/bench_render.py``)."""
    if n_agents <= 100:
        return Detail(sides=8, caps=2, sphere=2)
    if n_agents <= 300:
        return Detail(sides=6, caps=1, sphere=1)
    return Detail(sides=4, caps=0, sphere=0)


def _unit(v: np.ndarray, fallback=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Unit vectors (..., 3); vectors shorter than 1 µm become ``fallback``."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 1e-6, v / np.maximum(n, 1e-12), np.asarray(fallback, dtype=float))


def _frame(left: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3), columns forward, left, up, from a left (lateral)
    direction and an approximate up direction (..., 3)."""
    up = _unit(up)
    left = _unit(left - np.sum(left * up, axis=-1, keepdims=True) * up, (0.0, 1.0, 0.0))
    forward = np.cross(left, up)
    return np.stack([forward, left, up], axis=-1)


def _perpendicular(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (..., 3) perpendicular to each unit ``axis`` and to each other."""
    helper = np.zeros_like(axis)
    use_z = np.abs(axis[..., 2]) < 0.9
    helper[..., 2] = use_z
    helper[..., 0] = ~use_z
    u = _unit(np.cross(axis, helper))
    return u, np.cross(axis, u)


@dataclass
class SolidBodies:
    """One mesh of solid bodies for all walkers, updated in place frame by frame.

    Parameters
    ----------
    names : sequence of str
        Joint names (J,); the H-Anim names of :mod:`crowdwalk.body` give full bodies.
    parents : (J,) int
        Parent joint of each joint (-1 for the root).
    detail : Detail
        Tessellation (see :func:`detail_for`).
    pole_radius : float
        Capsule radius [m] of skeletons without H-Anim names.
    """

    names: tuple[str, ...]
    parents: np.ndarray
    detail: Detail = field(default_factory=lambda: Detail(8, 2, 2))
    pole_radius: float = 0.035
    mesh: pv.PolyData = field(init=False, repr=False)
    n_agents: int = field(init=False, default=-1)

    def __post_init__(self) -> None:
        self.names = tuple(self.names)
        self.parents = np.asarray(self.parents, dtype=int)
        self.bones = bone_pairs(self.parents)
        if len(self.names) != len(self.parents):
            raise invalid("SolidBodies", "names", f"one per joint ({len(self.parents)})",
                          len(self.names))
        d = self.detail
        if d.sides < 3 or d.caps < 0 or d.sphere < 0:
            raise invalid("SolidBodies", "detail", "sides >= 3, caps >= 0, sphere >= 0", d)
        self.hanim = all(n in self.names for n in _HANIM)
        self._j = {n: i for i, n in enumerate(self.names)}
        self.n_capsules = len(_LIMBS) + 3 if self.hanim else len(self.bones)
        self.n_volumes = 3 if self.hanim else 1
        self._capsule_template()
        sphere = pv.Icosphere(radius=1.0, nsub=d.sphere)
        self._sphere32 = np.asarray(sphere.points, dtype=np.float32)
        sphere_faces = sphere.regular_faces
        self.capsule_points = len(self._ring_axial) * d.sides
        n_caps = self.n_capsules * self.capsule_points
        tris = [self._capsule_tris[None] + (self.capsule_points * np.arange(self.n_capsules))
                [:, None, None]]
        tris.append(sphere_faces[None] + n_caps + len(self._sphere32) * np.arange(self.n_volumes)
                    [:, None, None])
        self._agent_tris = np.concatenate([t.reshape(-1, 3) for t in tris])
        self.points_per_agent = n_caps + self.n_volumes * len(self._sphere32)
        self.triangles_per_agent = len(self._agent_tris)
        self.mesh = pv.PolyData()
        self._colors: np.ndarray | None = None

    def _capsule_template(self) -> None:
        """Ring profile of a capsule from the proximal pole to the distal one: per ring the
        end it belongs to (0 proximal, 1 distal), its offset along the axis and its radius,
        both in units of that end's radius (no caps: one ring per end, an open tube)."""
        caps, s = self.detail.caps, self.detail.sides
        phi = np.linspace(-np.pi / 2, 0.0, caps + 1) if caps else np.zeros(1)
        self._ring_end = np.r_[np.zeros(len(phi)), np.ones(len(phi))].astype(int)
        self._ring_axial = np.r_[np.sin(phi), -np.sin(phi[::-1])]
        self._ring_radial = np.r_[np.cos(phi), np.cos(phi[::-1])]
        angles = np.linspace(0.0, 2 * np.pi, s, endpoint=False)
        self._cos32, self._sin32 = np.cos(angles).astype(np.float32), np.sin(angles).astype(
            np.float32)
        k = np.arange(s)
        kn = (k + 1) % s
        band = np.concatenate([np.column_stack([k, kn, s + k]),
                               np.column_stack([kn, s + kn, s + k])])
        rings = len(self._ring_axial)
        self._capsule_tris = np.concatenate([band + s * r for r in range(rings - 1)])

    # --- public -------------------------------------------------------------------------

    def update(self, positions: np.ndarray, colors: np.ndarray | None = None) -> pv.PolyData:
        """Move the bodies to one frame's poses.

        Parameters
        ----------
        positions : (k, J, 3) float
            Joint world positions [m] of the k walkers present in the frame.
        colors : (k, 3) uint8, optional
            One RGB colour per walker (point scalars ``"rgb"``); kept when omitted.

        Returns
        -------
        pyvista.PolyData
            The same mesh object every call.
        """
        positions = np.asarray(positions, dtype=np.float64)
        n_joints = len(self.parents)
        if positions.ndim != 3 or positions.shape[1:] != (n_joints, 3):
            raise invalid("SolidBodies", "positions", f"shaped (k, {n_joints}, 3) [m]",
                          positions.shape)
        k = positions.shape[0]
        if k != self.n_agents:
            self._rebuild(k)
        if k:
            self._write(positions)
            self.mesh.GetPoints().Modified()
            self.mesh.point_data["Normals"].Modified()
            if colors is not None:
                colors = np.asarray(colors, dtype=np.uint8).reshape(k, 3)
                if self._colors is None or not np.array_equal(colors, self._colors):
                    rgb = self.mesh.point_data["rgb"].reshape(k, self.points_per_agent, 3)
                    rgb[:] = colors[:, None]
                    self.mesh.point_data["rgb"].Modified()
                    self._colors = colors.copy()
        self.mesh.Modified()
        return self.mesh

    def heights(self, positions: np.ndarray) -> np.ndarray:
        """Body height (k,) [m] of each walker from its thigh length (the reference height
        for skeletons without H-Anim names)."""
        if not self.hanim:
            return np.full(len(positions), REFERENCE_HEIGHT)
        j = self._j
        thigh = np.linalg.norm(positions[:, j["l_knee"]] - positions[:, j["l_hip"]], axis=-1)
        return np.where(thigh > 0.1, thigh / THIGH_FRACTION, REFERENCE_HEIGHT)

    def parts(self, positions: np.ndarray):
        """Capsules and volumes of every walker.

        Returns
        -------
        a, b : (k, C, 3) float
            Capsule end centres [m].
        ra, rb : (k, C) float
            Capsule radii at a and b [m].
        centre : (k, E, 3) float
            Volume centres [m].
        rotation : (k, E, 3, 3) float
            Volume axes (columns forward, left, up).
        axes : (k, E, 3) float
            Volume semi-axes [m].
        """
        if self.hanim:
            return self._hanim_parts(positions)
        k = len(positions)
        a, b = positions[:, self.bones[:, 1]], positions[:, self.bones[:, 0]]
        r = np.full(a.shape[:2], self.pole_radius)
        top = positions[:, [int(np.argmax(positions[0, :, 2]) if k else 0)]]
        head = 0.11 * np.ones((k, 1, 3))
        centre = top + head * [0.0, 0.0, 1.0]
        return a, b, r, r, centre, np.broadcast_to(np.eye(3), (k, 1, 3, 3)), head

    # --- geometry -----------------------------------------------------------------------

    def _hanim_parts(self, p: np.ndarray):
        j = self._j
        k = len(p)
        s = (self.heights(p) / REFERENCE_HEIGHT)[:, None]  # (k, 1) size factor
        h = s * REFERENCE_HEIGHT
        a = [p[:, j[x]] for x, _, _, _ in _LIMBS]
        b = [p[:, j[y]] for _, y, _, _ in _LIMBS]
        ra = [np.full(k, r0) for *_, r0, _ in _LIMBS]
        rb = [np.full(k, r1) for *_, r1 in _LIMBS]
        up_world = np.array([0.0, 0.0, 1.0])
        hips_left = p[:, j["l_hip"]] - p[:, j["r_hip"]]
        for side in ("l", "r"):  # feet: heel to toe along the hindfoot, on the sole
            ankle, ball = p[:, j[f"{side}_talocrural"]], p[:, j[f"{side}_metatarsal"]]
            g = _unit(ball - ankle, (1.0, 0.0, 0.0))
            left = _unit(np.cross(up_world, g) + 1e-9 * hips_left, (0.0, 1.0, 0.0))
            n = np.cross(g, left)
            c, si = np.cos(_REST_FOOT_PITCH), np.sin(_REST_FOOT_PITCH)
            forward, up = c * g + si * n, c * n - si * g
            r = _FOOT_RADIUS * s
            a.append(ankle - _HEEL_BEHIND * h * forward - (_ANKLE_HEIGHT * h - r) * up)
            b.append(ball + (_TOE_AHEAD * h - r) * forward + r * up)
            ra.append(np.full(k, _FOOT_RADIUS))
            rb.append(np.full(k, 0.9 * _FOOT_RADIUS))
        shoulders = 0.5 * (p[:, j["l_shoulder"]] + p[:, j["r_shoulder"]])
        skull = p[:, j["skullbase"]]
        a.append(shoulders)
        b.append(skull)
        ra.append(np.full(k, 0.048))
        rb.append(np.full(k, 0.045))
        a, b = np.stack(a, 1), np.stack(b, 1)
        ra, rb = np.stack(ra, 1) * s, np.stack(rb, 1) * s
        # volumes: pelvis, chest, head
        root, vl5 = p[:, j["HumanoidRoot"]], p[:, j["vl5"]]
        shoulders_left = p[:, j["l_shoulder"]] - p[:, j["r_shoulder"]]
        pelvis_r = _frame(hips_left, vl5 - root)
        chest_r = _frame(shoulders_left, shoulders - vl5)
        head_r = _frame(shoulders_left, skull - shoulders)
        trunk = np.linalg.norm(shoulders - vl5, axis=-1)[:, None]
        centre = np.stack([
            root + 0.03 * h * pelvis_r[..., 2],
            vl5 + 0.55 * (shoulders - vl5),
            skull + 0.055 * h * head_r[..., 2] + 0.008 * h * head_r[..., 0],
        ], 1)  # fmt: skip
        axes = np.stack([
            s * [0.09, 0.15, 0.11],
            np.column_stack([0.10 * s[:, 0], 0.16 * s[:, 0], 0.6 * trunk[:, 0]]),
            s * [0.10, 0.082, 0.115],
        ], 1)  # fmt: skip
        rotation = np.stack([pelvis_r, chest_r, head_r], 1)
        return a, b, ra, rb, centre, rotation, axes

    def _rebuild(self, k: int) -> None:
        """New topology and point buffers for ``k`` walkers."""
        self.n_agents = k
        self._colors = None
        if k == 0:
            self.mesh.copy_from(pv.PolyData())
            return
        tris = (self._agent_tris[None] + (self.points_per_agent * np.arange(k))[:, None, None])
        faces = np.column_stack([np.full(k * len(self._agent_tris), 3), tris.reshape(-1, 3)])
        n = k * self.points_per_agent
        self.mesh.copy_from(pv.PolyData(np.zeros((n, 3), np.float32), faces=faces.ravel()))
        self.mesh.point_data["Normals"] = np.zeros((n, 3), np.float32)
        self.mesh.point_data.active_normals_name = "Normals"
        self.mesh.point_data["rgb"] = np.full((n, 3), 90, np.uint8)

    def _write(self, positions: np.ndarray) -> None:
        """Write points and normals of all walkers straight into the mesh buffers
        (float32 arithmetic: the buffers' precision)."""
        k = len(positions)
        a, b, ra, rb, centre, rotation, axes = (
            np.asarray(x, dtype=np.float32) for x in self.parts(positions))
        points = np.asarray(self.mesh.points).reshape(k, self.points_per_agent, 3)
        normals = np.asarray(self.mesh.point_data["Normals"]).reshape(k, self.points_per_agent, 3)
        n_caps = self.n_capsules * self.capsule_points
        rings, sides = len(self._ring_end), self.detail.sides
        # capsules: rings around the axis, each at its end's centre and radius
        axis = _unit(b - a).astype(np.float32)  # (k, C, 3)
        u, v = _perpendicular(axis)
        radial = (u[..., None, :] * self._cos32[:, None] + v[..., None, :] * self._sin32[:, None])
        cap_pts = points[:, :n_caps].reshape(k, self.n_capsules, rings, sides, 3)
        cap_n = normals[:, :n_caps].reshape(k, self.n_capsules, rings, sides, 3)
        for r, (end, axial, rad) in enumerate(zip(self._ring_end, self._ring_axial,
                                                  self._ring_radial, strict=True)):
            radius = (ra if end == 0 else rb)[..., None]  # (k, C, 1)
            centre_r = (a if end == 0 else b) + (axial * radius) * axis  # (k, C, 3)
            np.multiply(radial, (rad * radius)[..., None], out=cap_pts[:, :, r])
            cap_pts[:, :, r] += centre_r[:, :, None, :]
            np.multiply(radial, np.float32(rad), out=cap_n[:, :, r])
            cap_n[:, :, r] += (np.float32(axial) * axis)[:, :, None, :]
        # volumes: unit sphere scaled by the semi-axes and turned by the rotation
        sphere = self._sphere32[None, None]  # (1, 1, V, 3)
        turn = rotation.swapaxes(-1, -2)  # row vectors times R^T
        vol = np.matmul(sphere * axes[:, :, None, :], turn)
        vol += centre[:, :, None, :]
        points[:, n_caps:] = vol.reshape(k, -1, 3)
        vol_n = np.matmul(sphere / axes[:, :, None, :], turn)
        vol_n /= np.linalg.norm(vol_n, axis=-1, keepdims=True)
        normals[:, n_caps:] = vol_n.reshape(k, -1, 3)
