"""Export a run's walkers as one glTF 2.0 binary (``.glb``) for DCC tools and game engines.

Every walker is one skeleton (its 20 joints as a node hierarchy, named as in
:data:`crowdwalk.export_bvh.JOINT_NAMINGS`, prefixed ``agent<ID>/``), one skin and a small
skinned mesh (a 4 cm box on every joint, so the skeleton is visible and bound); one
animation moves them all: the root's translation and every joint's rotation, one key per
pose frame of that walker, linear (rotations: spherical linear) between keys. Before its
first and after its last frame a walker holds that pose (glTF clamps). glTF is y-up in
metres: world (x, y, z up) maps to (x, z, −y), as in the BVH export. Written with
pygltflib.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from crowdwalk.body import JOINT_NAMES, PARENTS, Body
from crowdwalk.errors import invalid
from crowdwalk.export_bvh import BVH_AXES, JOINT_NAMINGS, _to_bvh_quaternion

__all__ = ["export_gltf"]

_BOX = 0.02  # half edge of the box drawn on every joint [m]
_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
_FACES = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                   [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


class _Blob:
    """One binary buffer with its buffer views and accessors (pygltflib objects)."""

    def __init__(self, gltf) -> None:
        self.gltf, self.data = gltf, bytearray()

    def add(self, array: np.ndarray, kind: str, *, bounds: bool = False) -> int:
        import pygltflib as g

        array = np.ascontiguousarray(array)
        ctype = {np.dtype(np.float32): g.FLOAT, np.dtype(np.uint16): g.UNSIGNED_SHORT,
                 np.dtype(np.uint32): g.UNSIGNED_INT}[array.dtype]
        self.data += b"\0" * (-len(self.data) % 4)
        self.gltf.bufferViews.append(g.BufferView(buffer=0, byteOffset=len(self.data),
                                                  byteLength=array.nbytes))
        self.data += array.tobytes()
        flat = array.reshape(len(array), -1)
        self.gltf.accessors.append(g.Accessor(
            bufferView=len(self.gltf.bufferViews) - 1, componentType=ctype, count=len(array),
            type=kind, min=flat.min(axis=0).tolist() if bounds else None,
            max=flat.max(axis=0).tolist() if bounds else None))
        return len(self.gltf.accessors) - 1


def export_gltf(run_dir, out, *, agents=None, naming: str = "common") -> Path:
    """Write the walkers of a run folder (``poses.sqlite``) as one ``.glb``.

    Parameters
    ----------
    run_dir : path
        Run folder written by ``crowdwalk run`` with poses.
    out : path
        The ``.glb`` file.
    agents : sequence of int or None
        Agent ids to export (default: every agent with poses).
    naming : ``"common"`` or ``"hanim"`` joint names.

    Returns
    -------
    pathlib.Path
    """
    import pygltflib as g

    from crowdwalk.record import open_run

    out = Path(out)
    if out.suffix.lower() != ".glb":
        raise invalid("export_gltf", "out", "a .glb file", str(out))
    if naming not in JOINT_NAMINGS:
        raise invalid("export_gltf", "naming", f"one of {sorted(JOINT_NAMINGS)}", naming)
    poses = open_run(run_dir).poses()
    if poses is None:
        raise FileNotFoundError(2, "the run recorded no poses", str(Path(run_dir) / "poses.sqlite"))
    try:
        ids = sorted(poses.body_heights) if agents is None else [int(a) for a in agents]
        unknown = [a for a in ids if a not in poses.body_heights]
        if unknown or not ids:
            raise invalid("export_gltf", "agents", "agent ids of the run", unknown or ids)
        tracks = [poses.agent_track(a) for a in ids]
        heights = np.array([poses.body_heights[a] for a in ids], float)
    finally:
        poses.close()

    gltf = g.GLTF2(scene=0, scenes=[g.Scene(nodes=[])], animations=[g.Animation(
        name="crowdwalk", channels=[], samplers=[])])
    blob = _Blob(gltf)
    body = Body.from_heights(heights)
    offsets = body.offsets() @ BVH_AXES.T  # (A, J, 3) [m], y up
    nj = len(JOINT_NAMES)
    anim = gltf.animations[0]
    for k, (agent, track) in enumerate(zip(ids, tracks, strict=True)):
        first = len(gltf.nodes)
        rest = np.zeros((nj, 3))  # bind pose: rest offsets, no rotation, root at the origin
        for j in range(nj):
            if j:  # the root's place is its animated translation
                rest[j] = offsets[k, j] + rest[PARENTS[j]]
            gltf.nodes.append(g.Node(name=f"agent{agent}/{JOINT_NAMINGS[naming][j]}",
                                     translation=offsets[k, j].tolist() if j else None,
                                     children=[first + c for c in range(nj) if PARENTS[c] == j
                                               and c]))
        inverse_bind = np.tile(np.eye(4), (nj, 1, 1))
        inverse_bind[:, 3, :3] = -rest  # column-major: the translation is the 4th column
        verts = (rest[:, None, :] + _BOX * _CORNERS).reshape(-1, 3).astype(np.float32)
        joints = np.zeros((nj * 8, 4), np.uint16)
        joints[:, 0] = np.repeat(np.arange(nj), 8)
        weights = np.zeros((nj * 8, 4), np.float32)
        weights[:, 0] = 1.0
        faces = (_FACES[None] + 8 * np.arange(nj)[:, None, None]).reshape(-1).astype(np.uint32)
        gltf.meshes.append(g.Mesh(name=f"agent{agent}", primitives=[g.Primitive(
            attributes=g.Attributes(POSITION=blob.add(verts, "VEC3", bounds=True),
                                    JOINTS_0=blob.add(joints, "VEC4"),
                                    WEIGHTS_0=blob.add(weights, "VEC4")),
            indices=blob.add(faces, "SCALAR"))]))
        gltf.skins.append(g.Skin(name=f"agent{agent}", skeleton=first,
                                 joints=list(range(first, first + nj)),
                                 inverseBindMatrices=blob.add(
                                     inverse_bind.astype(np.float32), "MAT4")))
        gltf.nodes.append(g.Node(name=f"agent{agent}/mesh", mesh=k, skin=k))
        gltf.scenes[0].nodes += [first, len(gltf.nodes) - 1]

        times = blob.add(track["time"].astype(np.float32)[:, None], "SCALAR", bounds=True)
        quats = track["joints"].copy()
        quats[:, 0] = track["root_quaternion"]
        quats = _to_bvh_quaternion(quats / np.linalg.norm(quats, axis=-1, keepdims=True))
        xyzw = np.concatenate([quats[..., 1:], quats[..., :1]], axis=-1).astype(np.float32)
        keys = [("translation", first, (track["root_position"] @ BVH_AXES.T), "VEC3")]
        keys += [("rotation", first + j, xyzw[:, j], "VEC4") for j in range(nj)]
        for path, node, values, kind in keys:
            anim.samplers.append(g.AnimationSampler(
                input=times, output=blob.add(values.astype(np.float32), kind),
                interpolation="LINEAR"))
            anim.channels.append(g.AnimationChannel(
                sampler=len(anim.samplers) - 1,
                target=g.AnimationChannelTarget(node=node, path=path)))
    gltf.buffers = [g.Buffer(byteLength=len(blob.data))]
    gltf.set_binary_blob(bytes(blob.data))
    out.parent.mkdir(parents=True, exist_ok=True)
    gltf.save_binary(str(out))
    return out
