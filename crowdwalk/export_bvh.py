"""Export one agent's motion as a BVH file (Biovision Hierarchy) with ``bvhio``.

The skeleton is :mod:`crowdwalk.body`'s (joints named as motion-capture rigs name them, or
with ``naming="hanim"`` by their H-Anim names), scaled to the agent's body
height; the root carries 6 channels, every other joint 3 rotation channels (Z X Y, the
order most importers expect). BVH is y-up: world (x east, y north, z up) maps to BVH
(X, Y, Z) = (x, z, −y), a proper rotation, so joint rotations keep their meaning.
Lengths are written in centimetres by default (``scale=100``).

Sources: a run folder (``poses.sqlite`` read through :func:`crowdwalk.record.open_run`),
or a sequence of :class:`~crowdwalk.gait.animator.PoseFrame` straight from an Animator.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from crowdwalk.body import END_SITES, JOINT_NAMES, PARENTS, Body
from crowdwalk.errors import invalid

__all__ = ["export_bvh", "frames_to_bvh", "write_bvh", "BVH_AXES", "JOINT_NAMINGS"]

#: Joint names a BVH file carries: ``"common"`` (the default), the names of motion-capture
#: rigs (Hips, Spine, Head, LeftUpLeg, LeftFoot, LeftToeBase, ...) that importers and BVH
#: libraries (e.g. pybvh) recognise to find the up axis (root to ``Head``) and the feet
#: (``*Foot``/``*ToeBase``) without hints; or ``"hanim"``, crowdwalk's own H-Anim names.
JOINT_NAMINGS = {
    "hanim": tuple(JOINT_NAMES),
    "common": tuple({
        "HumanoidRoot": "Hips", "sacroiliac": "Pelvis", "vl5": "Spine", "skullbase": "Head",
    }.get(n) or ("Left" if n.startswith("l_") else "Right") + {
        "hip": "UpLeg", "knee": "Leg", "talocrural": "Foot", "subtalar": "Subtalar",
        "metatarsal": "ToeBase", "shoulder": "Arm", "elbow": "ForeArm", "wrist": "Hand",
    }[n[2:]] for n in JOINT_NAMES),
}

BVH_AXES = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
"""Rotation taking world vectors (z up) to BVH vectors (y up): (x, y, z) → (x, z, −y)."""


def _to_bvh_quaternion(q: np.ndarray) -> np.ndarray:
    """Quaternions wxyz (..., 4) of world-frame rotations → the same rotations in BVH axes."""
    out = np.empty_like(q)
    out[..., 0] = q[..., 0]
    out[..., 1:] = q[..., 1:] @ BVH_AXES.T
    return out


def write_bvh(
    out: str | Path,
    body_height: float,
    frame_time: float,
    root_position: np.ndarray,
    joints: np.ndarray,
    scale: float = 100.0,
    naming: str = "common",
) -> Path:
    """Write a BVH file for one body and F frames.

    Parameters
    ----------
    out : path of the ``.bvh`` file.
    body_height : float [m], sets the skeleton's segment lengths.
    frame_time : float [s] between frames.
    root_position : (F, 3) ``HumanoidRoot`` world positions [m].
    joints : (F, J, 4) local joint quaternions wxyz; joint 0 is the root's world rotation.
    scale : float, BVH units per metre (100: centimetres).
    naming : ``"common"`` or ``"hanim"`` joint names (:data:`JOINT_NAMINGS`).

    Returns
    -------
    pathlib.Path
    """
    import bvhio
    from pyglm import glm
    from SpatialTransform import Pose

    root_position = np.asarray(root_position, dtype=float)
    joints = np.asarray(joints, dtype=float)
    n_frames, nj = root_position.shape[0], len(JOINT_NAMES)
    if root_position.shape != (n_frames, 3) or n_frames == 0:
        raise invalid("write_bvh", "root_position", "an (F >= 1, 3) array [m]",
                      root_position.shape)  # fmt: skip
    if joints.shape != (n_frames, nj, 4):
        raise invalid("write_bvh", "joints", f"shaped ({n_frames}, {nj}, 4)", joints.shape)
    if not (np.isfinite(frame_time) and frame_time > 0):
        raise invalid("write_bvh", "frame_time", "finite and > 0 [s]", frame_time)
    if not (np.isfinite(scale) and scale > 0):
        raise invalid("write_bvh", "scale", "finite and > 0 [units/m]", scale)
    if naming not in JOINT_NAMINGS:
        raise invalid("write_bvh", "naming", f"one of {sorted(JOINT_NAMINGS)}", naming)
    if not (np.isfinite(root_position).all() and np.isfinite(joints).all()):
        raise invalid("write_bvh", "poses", "finite", "non-finite values")
    body = Body.from_heights([body_height])
    offsets = body.offsets()[0] @ BVH_AXES.T * scale
    ends = {k: v[0] @ BVH_AXES.T * scale for k, v in body.end_site_offsets().items()}
    quats = _to_bvh_quaternion(joints / np.linalg.norm(joints, axis=-1, keepdims=True))
    positions = root_position @ BVH_AXES.T * scale

    nodes = []
    for j, name in enumerate(JOINT_NAMES):
        node = bvhio.BvhJoint(JOINT_NAMINGS[naming][j], glm.vec3(*offsets[j]))
        node.Channels = (["Xposition", "Yposition", "Zposition"] if j == 0 else []) + [
            "Zrotation", "Xrotation", "Yrotation"
        ]  # fmt: skip
        if name in END_SITES:
            node.EndSite = glm.vec3(*ends[name])
        for f in range(n_frames):
            pos = glm.vec3(*positions[f]) if j == 0 else glm.vec3(*offsets[j])
            node.Keyframes.append(Pose(pos, glm.quat(*quats[f, j])))
        nodes.append(node)
    for j in range(1, nj):
        nodes[PARENTS[j]].Children.append(nodes[j])
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    bvhio.writeBvh(str(out), bvhio.BvhContainer(nodes[0], n_frames, float(frame_time)), 6)
    return out


def frames_to_bvh(
    frames: Sequence, agent: int, body_height: float, out: str | Path, scale: float = 100.0,
    naming: str = "common",
) -> Path:
    """Write one agent's poses from a sequence of ``PoseFrame`` (uniform time steps) for a
    body ``body_height`` [m]; ``scale`` BVH units per metre; ``naming`` of the joints."""
    rows = []
    for frame in frames:
        hit = np.flatnonzero(np.asarray(frame.agents) == agent)
        if hit.size:
            rows.append((frame.time, frame.root_position[hit[0]], frame.joints[hit[0]]))
    if len(rows) < 2:
        raise invalid("frames_to_bvh", "agent", "an agent present in at least 2 frames", agent)
    times = np.array([r[0] for r in rows])
    root = np.array([r[1] for r in rows])
    joints = np.array([r[2] for r in rows])
    return write_bvh(out, body_height, float(np.median(np.diff(times))), root, joints, scale,
                     naming)


def export_bvh(run_dir: str | Path, agent: int, out: str | Path, scale: float = 100.0,
               naming: str = "common") -> Path:
    """Write the BVH file of one agent of a run folder (its ``poses.sqlite``); ``scale``
    BVH units per metre, ``naming`` of the joints (:data:`JOINT_NAMINGS`).

    Raises
    ------
    FileNotFoundError
        When the folder or its ``poses.sqlite`` does not exist.
    InputError
        When the agent has no poses or the stored skeleton is not crowdwalk's.
    """
    from crowdwalk.record import open_run

    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise FileNotFoundError(2, "run folder not found", str(run_dir))
    run = open_run(run_dir)
    poses = run.poses()
    if poses is None:
        raise FileNotFoundError(2, "the run recorded no poses", str(run_dir / "poses.sqlite"))
    try:
        if list(poses.names) != list(JOINT_NAMES):
            raise invalid("export_bvh", "skeleton", f"crowdwalk's {len(JOINT_NAMES)} joints",
                          f"{len(poses.names)} joints")  # fmt: skip
        if agent not in poses.body_heights:
            ids = sorted(poses.body_heights)[:10]
            raise invalid("export_bvh", "agent", f"an agent id of the run (e.g. {ids})", agent)
        track = poses.agent_track(agent)
        height = float(poses.body_heights[agent])
        fps = poses.fps
    finally:
        poses.close()
    times = track["time"]
    if times.size < 2:
        raise invalid("export_bvh", "agent", "an agent with at least 2 pose frames", agent)
    frame_time = 1.0 / fps if np.isfinite(fps) and fps > 0 else float(np.median(np.diff(times)))
    joints = track["joints"].copy()
    joints[:, 0] = track["root_quaternion"]
    return write_bvh(out, height, frame_time, track["root_position"], joints, scale, naming)
