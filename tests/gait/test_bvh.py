"""BVH export (issue 4, item 7): bvhio writes it, readers load it back with the same
motion, from Python (PoseFrames, run folders) and from the CLI."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from crowdwalk.body import JOINT_NAMES, Body
from crowdwalk.cli import app
from crowdwalk.errors import InputError
from crowdwalk.export_bvh import BVH_AXES, JOINT_NAMINGS, export_bvh, frames_to_bvh, write_bvh
from crowdwalk.gait.animator import Animator
from crowdwalk.gait.metagait import animate_paths

FPS = 30.0


def _flat(xy):
    return np.zeros(len(xy))


@pytest.fixture(scope="module")
def walk():
    body = Body.from_heights([1.62, 1.84])
    paths = np.array([[[0.0, 0.0], [10.0, 2.0]], [[0.0, 1.0], [-5.0, 9.0]]])
    return body, animate_paths(body, paths, _flat, 1.3, 1.5, FPS)


@pytest.fixture(scope="module")
def run_dir(walk, tmp_path_factory):
    from crowdwalk.record import RunWriter

    body, frames = walk
    out = tmp_path_factory.mktemp("run")
    names, parents = Animator(body).skeleton
    with RunWriter(out, scenario_text="{}\n", walkable_wkt="POLYGON((0 0,1 0,1 1,0 0))",
                   fps=FPS, skeleton=(names, parents)) as writer:  # fmt: skip
        writer.write_agents(np.array([7, 9]), body.height, ["g", "g"], ["fixed", "fixed"])
        for i, f in enumerate(frames):
            writer.write_pose(i, f.time, np.array([7, 9]), f.root_position, f.root_quaternion,
                              f.joints, f.positions, f.contact, f.fallback)  # fmt: skip
    return out


def _bvh_world_positions(path) -> list[dict[str, np.ndarray]]:
    import bvhio

    root = bvhio.readAsHierarchy(str(path))
    frames = []
    last = root.getKeyframeRange()[1]
    for f in range(last + 1):
        root.loadPose(f)
        frames.append({j.Name: np.array(j.PositionWorld) for j, *_ in root.layout()})
    return frames


def _check_motion(path, frames, agent_row, scale=100.0):
    read = _bvh_world_positions(path)
    assert len(read) == len(frames)
    worst = 0.0
    for f, frame in enumerate(frames):
        for j, name in enumerate(JOINT_NAMINGS["common"]):
            ours = frame.positions[agent_row, j] @ BVH_AXES.T * scale
            worst = max(worst, float(np.abs(read[f][name] - ours).max()))
    assert worst < 1e-3 * scale  # < 1 mm


def test_frames_round_trip_through_bvhio(walk, tmp_path):
    body, frames = walk
    path = frames_to_bvh(frames, 1, float(body.height[1]), tmp_path / "a.bvh")
    _check_motion(path, frames, 1)


def test_the_file_is_plain_bvh(walk, tmp_path):
    """Independent of bvhio: the header declares every joint with its channels, and every
    motion line has exactly as many numbers as channels."""
    body, frames = walk
    path = frames_to_bvh(frames, 0, float(body.height[0]), tmp_path / "b.bvh")
    text = path.read_text().splitlines()
    joints = [line.split()[1] for line in text if line.strip().split()[:1] in (["ROOT"],
                                                                                ["JOINT"])]
    assert joints == list(JOINT_NAMINGS["common"])
    channels = sum(int(line.split()[1]) for line in text if line.strip().startswith("CHANNELS"))
    assert channels == 6 + 3 * (len(JOINT_NAMES) - 1)
    motion = text.index("MOTION")
    assert text[motion + 1] == f"Frames: {len(frames)}"
    assert float(text[motion + 2].split(":")[1]) == pytest.approx(1.0 / FPS)
    rows = [line.split() for line in text[motion + 3:] if line.strip()]
    assert len(rows) == len(frames) and all(len(r) == channels for r in rows)
    assert sum(line.strip() == "End Site" for line in text) == 5


def test_export_from_a_run_folder_and_the_cli(walk, run_dir, tmp_path):
    body, frames = walk
    path = export_bvh(run_dir, 9, tmp_path / "c.bvh")
    _check_motion(path, frames, 1)
    out = tmp_path / "cli.bvh"
    result = CliRunner().invoke(app, ["export-bvh", str(run_dir), "--agent", "7", "--out",
                                      str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    _check_motion(out, frames, 0)


def test_cli_errors_are_one_line_and_exit_code_2(run_dir, tmp_path):
    runner = CliRunner()
    result = runner.invoke(app, ["export-bvh", str(run_dir), "--agent", "3", "--out",
                                 str(tmp_path / "x.bvh")])  # fmt: skip
    assert result.exit_code == 2
    assert "export_bvh.agent must be an agent id of the run" in result.output
    assert "Traceback" not in result.output
    result = runner.invoke(app, ["export-bvh", str(tmp_path / "nope"), "--agent", "1",
                                 "--out", str(tmp_path / "y.bvh")])  # fmt: skip
    assert result.exit_code == 2 and "not found" in result.output


def test_bad_motion_is_rejected():
    with pytest.raises(InputError, match=r"^write_bvh\.joints must be shaped"):
        write_bvh("/tmp/never.bvh", 1.7, 0.04, np.zeros((3, 3)), np.zeros((3, 4, 4)))
    joints = np.tile([1.0, 0, 0, 0], (2, len(JOINT_NAMES), 1))
    with pytest.raises(InputError, match=r"^write_bvh\.poses must be finite"):
        write_bvh("/tmp/never.bvh", 1.7, 0.04, np.full((2, 3), np.nan), joints)
