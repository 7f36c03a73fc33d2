"""Every agent as a full-body stick figure, all agents in one mesh.

Bones are tubes (open prisms) around each joint→parent segment and heads are small
spheres; both are built with numpy from the joint world positions of one frame. The
mesh topology depends only on the number of agents, so a frame with the same number of
agents as the last one only overwrites the point coordinates in place (no new actor,
no new cells). Normals are analytic (radial), so the tubes shade smoothly without a
normals filter.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid

__all__ = ["StickFigures", "bone_pairs"]


def bone_pairs(parents: np.ndarray) -> np.ndarray:
    """Joint index pairs (child, parent) of every bone.

    Parameters
    ----------
    parents : (J,) int
        Parent joint index of each joint, -1 for the root.

    Returns
    -------
    (B, 2) int
        One row per joint that has a parent.
    """
    parents = np.asarray(parents, dtype=np.int64)
    if parents.ndim != 1 or parents.size == 0:
        raise invalid("StickFigures", "parents", "a non-empty (J,) integer array", parents.shape)
    if np.any(parents >= parents.size) or np.any(parents < -1):
        raise invalid("StickFigures", "parents", f"indices in [-1, {parents.size})", parents)
    child = np.flatnonzero(parents >= 0)
    return np.column_stack([child, parents[child]])


def _unit_sphere(subdivisions: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V,3) and triangles (F,3) of a unit icosphere."""
    sphere = pv.Icosphere(radius=1.0, nsub=subdivisions)
    return np.asarray(sphere.points, dtype=np.float64), sphere.regular_faces


def _perpendicular_frames(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (n,3) perpendicular to each unit ``axis`` (n,3) and each other."""
    helper = np.zeros_like(axis)
    use_z = np.abs(axis[:, 2]) < 0.9
    helper[use_z, 2] = 1.0
    helper[~use_z, 0] = 1.0
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(axis, u)
    return u, v


@dataclass
class StickFigures:
    """One tube-and-sphere mesh for all agents, updated in place frame by frame.

    Parameters
    ----------
    parents : (J,) int
        Parent joint of each joint (-1 for the root), as in the run's skeleton table.
    head_joint : int
        Joint that carries the head sphere (the topmost joint of the skeleton).
    radius : float
        Bone tube radius [m].
    head_radius : float
        Head sphere radius [m].
    sides : int
        Facets around each tube.
    head_detail : int
        Subdivisions of the head icosphere (0: 20 triangles, 1: 80).
    """

    parents: np.ndarray
    head_joint: int
    radius: float = 0.035
    head_radius: float = 0.11
    sides: int = 6
    head_detail: int = 1
    mesh: pv.PolyData = field(init=False, repr=False)
    n_agents: int = field(init=False, default=-1)
    _values: np.ndarray | None = field(init=False, default=None, repr=False)

    def __post_init__(self) -> None:
        self.bones = bone_pairs(self.parents)
        n_joints = len(self.parents)
        if not 0 <= self.head_joint < n_joints:
            raise invalid("StickFigures", "head_joint", f"in [0, {n_joints})", self.head_joint)
        if not self.radius > 0 or not self.head_radius > 0:
            raise invalid("StickFigures", "radius", "> 0 [m]", (self.radius, self.head_radius))
        if self.sides < 3:
            raise invalid("StickFigures", "sides", ">= 3", self.sides)
        angles = np.linspace(0.0, 2 * np.pi, self.sides, endpoint=False)
        self._cos = np.cos(angles).astype(np.float32)
        self._sin = np.sin(angles).astype(np.float32)
        sphere_points, sphere_faces = _unit_sphere(self.head_detail)
        self._sphere_points = sphere_points.astype(np.float32)
        s, b = self.sides, len(self.bones)
        # One bone: ring 0 (child end) points 0..s-1, ring 1 (parent end) s..2s-1; 2 triangles
        # per side.
        k = np.arange(s)
        kn = (k + 1) % s
        bone_tris = np.concatenate(
            [np.column_stack([k, kn, s + k]), np.column_stack([kn, s + kn, s + k])]
        )
        tris = [bone_tris[None] + (2 * s * np.arange(b))[:, None, None]]
        tris.append(sphere_faces[None] + 2 * s * b)
        self._agent_tris = np.concatenate([t.reshape(-1, 3) for t in tris])
        self.points_per_agent = 2 * s * b + len(self._sphere_points)
        self.mesh = pv.PolyData()

    def update(self, positions: np.ndarray, values: np.ndarray | None = None) -> pv.PolyData:
        """Move the figures to one frame's poses.

        Parameters
        ----------
        positions : (k, J, 3) float
            Joint world positions [m] of the k agents present in the frame.
        values : (k,) float, optional
            One colour value per agent (e.g. an id or a planner code), stored as the
            point scalar ``"value"``; kept from the last call when omitted.

        Returns
        -------
        pyvista.PolyData
            The same mesh object every call.
        """
        positions = np.asarray(positions, dtype=np.float64)
        n_joints = len(self.parents)
        if positions.ndim != 3 or positions.shape[1:] != (n_joints, 3):
            raise invalid(
                "StickFigures", "positions", f"shaped (k, {n_joints}, 3) [m]", positions.shape
            )
        k = positions.shape[0]
        if k != self.n_agents:
            self._rebuild(k)
        if k:
            self._write_geometry(positions)
            self.mesh.GetPoints().Modified()
            self.mesh.point_data["Normals"].Modified()
            new = None if values is None else np.asarray(values, dtype=np.float32)
            if new is not None and not np.array_equal(new, self._values, equal_nan=True):
                value = self.mesh.point_data["value"].reshape(k, -1)
                value[:] = new[:, None]
                self.mesh.point_data["value"].Modified()  # re-uploaded only when changed
                self._values = new
        self.mesh.Modified()
        return self.mesh

    def _rebuild(self, k: int) -> None:
        """New topology and point buffers for ``k`` agents."""
        if k == 0:
            self.mesh.copy_from(pv.PolyData())
            self.n_agents = 0
            return
        offsets = (self.points_per_agent * np.arange(k))[:, None, None]
        tris = (self._agent_tris[None] + offsets).reshape(-1, 3)
        faces = np.column_stack([np.full(len(tris), 3), tris]).ravel()
        n_points = k * self.points_per_agent
        self.mesh.copy_from(pv.PolyData(np.zeros((n_points, 3), np.float32), faces=faces))
        normals = np.zeros((k, self.points_per_agent, 3), np.float32)
        normals[:, 2 * self.sides * len(self.bones):] = self._sphere_points  # heads: radial
        self.mesh.point_data["Normals"] = normals.reshape(-1, 3)
        self.mesh.point_data.active_normals_name = "Normals"
        self.mesh.point_data["value"] = np.zeros(n_points, np.float32)
        self._values = None
        self.n_agents = k

    def _write_geometry(self, positions: np.ndarray) -> None:
        """Write points and normals of all agents straight into the mesh buffers."""
        k, s, b = positions.shape[0], self.sides, len(self.bones)
        n_bone = 2 * s * b
        points = np.asarray(self.mesh.points).reshape(k, self.points_per_agent, 3)
        normals = np.asarray(self.mesh.point_data["Normals"]).reshape(k, self.points_per_agent, 3)
        child = positions[:, self.bones[:, 0]]  # (k, B, 3)
        parent = positions[:, self.bones[:, 1]]
        axis = (parent - child).reshape(-1, 3)
        length = np.linalg.norm(axis, axis=1, keepdims=True)
        # bones shorter than 1 µm (coincident joints) get a vertical axis
        axis = np.divide(axis, length, out=np.tile([0.0, 0.0, 1.0], (len(axis), 1)),
                         where=length > 1e-6)
        u, v = (w.astype(np.float32) for w in _perpendicular_frames(axis))
        ring = (u[:, None, :] * self._cos[None, :, None]
                + v[:, None, :] * self._sin[None, :, None]).reshape(k, b, s, 3)
        normals[:, :n_bone].reshape(k, b, 2, s, 3)[:] = ring[:, :, None]
        ring *= self.radius
        bone = np.empty((k, b, 2, s, 3), dtype=np.float32)
        np.add(ring, child[:, :, None, :], out=bone[:, :, 0], casting="unsafe")
        np.add(ring, parent[:, :, None, :], out=bone[:, :, 1], casting="unsafe")
        points[:, :n_bone] = bone.reshape(k, n_bone, 3)
        head_centre = positions[:, self.head_joint] + [0.0, 0.0, self.head_radius]
        points[:, n_bone:] = head_centre[:, None, :] + self._sphere_points[None] * self.head_radius
