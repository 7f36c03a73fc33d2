"""The multi-walker glTF export, read back without the writer: trimesh loads the scene,
and the animation decoded straight from the GLB chunks (glTF 2.0 spec, numpy) puts every
joint where crowdwalk's poses say, for every walker."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from crowdwalk.body import JOINT_NAMES, PARENTS
from crowdwalk.cli import app
from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.export_bvh import BVH_AXES
from crowdwalk.record import open_run

pytest.importorskip("pygltflib")
SCENARIO = Path(__file__).parents[1] / "scenarios" / "obstacle_stride.yaml"  # 2 walkers


@pytest.fixture(scope="module")
def glb(tmp_path_factory):
    run = tmp_path_factory.mktemp("stride")
    run_scenario(SCENARIO, run, overrides=RunOverrides(duration=3.0))
    out = run / "crowd.glb"
    result = CliRunner().invoke(app, ["export-gltf", str(run), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "one animated skeleton per walker" in result.output
    return run, out


def _read_glb(path):
    data = path.read_bytes()
    magic, version, _ = struct.unpack_from("<4sII", data)
    assert magic == b"glTF" and version == 2
    n, kind = struct.unpack_from("<I4s", data, 12)
    doc = json.loads(data[20:20 + n])
    m, kind2 = struct.unpack_from("<I4s", data, 20 + n)
    assert kind == b"JSON" and kind2 == b"BIN\0"
    binary = data[28 + n:28 + n + m]
    sizes = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}
    dtypes = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}

    def accessor(i):
        a = doc["accessors"][i]
        view = doc["bufferViews"][a["bufferView"]]
        flat = np.frombuffer(binary, dtypes[a["componentType"]], a["count"] * sizes[a["type"]],
                             view.get("byteOffset", 0))
        return flat.reshape(a["count"], -1)
    return doc, accessor


def _rotate(q, v):
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4) xyzw."""
    u, w = q[..., :3], q[..., 3:]
    return v + 2 * np.cross(u, np.cross(u, v) + w * v)


def _quat_mul(a, b):
    x1, y1, z1, w1 = np.moveaxis(a, -1, 0)
    x2, y2, z2, w2 = np.moveaxis(b, -1, 0)
    return np.stack([w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2],
                    axis=-1)


def test_trimesh_reads_one_skeleton_per_walker(glb):
    import trimesh

    run, path = glb
    scene = trimesh.load(path, force="scene")
    agents = sorted(open_run(run).poses().body_heights)
    assert len(agents) == 2 and len(scene.geometry) == len(agents)
    names = set(scene.graph.nodes)
    for a in agents:
        assert {f"agent{a}/Hips", f"agent{a}/LeftToeBase", f"agent{a}/Head"} <= names


def test_animation_puts_every_joint_where_the_poses_say(glb):
    run, path = glb
    doc, accessor = _read_glb(path)
    poses = open_run(run).poses()
    channels = {(doc["nodes"][c["target"]["node"]]["name"], c["target"]["path"]):
                doc["animations"][0]["samplers"][c["sampler"]] for c in doc["animations"][0]
                ["channels"]}
    by_name = {n["name"]: n for n in doc["nodes"]}
    names = [n["name"].split("/")[1] for n in doc["nodes"][:len(JOINT_NAMES)]]
    worst = 0.0
    for a in sorted(poses.body_heights):
        track = poses.agent_track(a)
        times = accessor(channels[(f"agent{a}/Hips", "translation")]["input"])[:, 0]
        np.testing.assert_allclose(times, track["time"], atol=1e-5)
        root = accessor(channels[(f"agent{a}/Hips", "translation")]["output"])
        rot = np.stack([accessor(channels[(f"agent{a}/{n}", "rotation")]["output"])
                        for n in names], axis=1)  # (F, J, 4)
        world_q = np.empty_like(rot)
        world_p = np.empty(rot.shape[:2] + (3,))
        for j, parent in enumerate(PARENTS):
            if j == 0:
                world_q[:, 0], world_p[:, 0] = rot[:, 0], root
                continue
            offset = np.asarray(by_name[f"agent{a}/{names[j]}"]["translation"])
            world_p[:, j] = world_p[:, parent] + _rotate(world_q[:, parent], offset)
            world_q[:, j] = _quat_mul(world_q[:, parent], rot[:, j])
        ours = track["positions"] @ BVH_AXES.T
        worst = max(worst, float(np.abs(world_p - ours).max()))
    poses.close()
    assert worst < 1e-3  # < 1 mm (float32 keys)
