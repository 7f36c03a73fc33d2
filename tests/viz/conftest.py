"""Fixtures of the viewer tests: an off-screen GL check and a small synthetic run."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="session")
def offscreen():
    """Configure off-screen rendering; skip when this machine has no GL stack at all."""
    from crowdwalk.viz.headless import configure_offscreen, gl_available

    if not gl_available():
        pytest.skip("no off-screen GL stack (install libegl1 libegl-mesa0 libgl1-mesa-dri)")
    configure_offscreen()
    return True


@pytest.fixture(scope="session")
def crowd():
    """Twelve synthetic walkers for 3 s at 10 fps in an 8 m x 6 m area."""
    from crowdwalk.viz.synthetic import synthetic_crowd

    return synthetic_crowd(12, duration=3.0, fps=10.0, area=(8.0, 6.0), seed=1)


@pytest.fixture(scope="session")
def write_run():
    """The function that writes a synthetic run folder (see :func:`_write_run`)."""
    return _write_run


def _write_run(path, poses, steps, fps=10.0):
    """Write a run folder (crowdwalk.record layout) holding the given poses and footsteps,
    without ``scenario.yaml`` so the viewer falls back to flat ground."""
    from crowdwalk.record import FOOTSTEP_COLUMNS, RunWriter

    wkt = "POLYGON ((-2 -2, 12 -2, 12 9, -2 9, -2 -2))"
    with RunWriter(path, scenario_text="", walkable_wkt=wkt, fps=fps,
                   skeleton=(poses.names, poses.parents)) as writer:
        for frame, t in enumerate(poses.times):
            ids, pos = poses.at(frame)
            k, nj = pos.shape[:2]
            root = pos[:, 0]
            writer.write_frame(frame, ids, root[:, :2], np.zeros(k), np.tile([1.0, 0.0], (k, 1)))
            quat = np.tile([1.0, 0.0, 0.0, 0.0], (k, 1))
            writer.write_pose(frame, t, ids, root, quat, np.tile(quat[:, None], (1, nj, 1)), pos,
                              np.zeros((k, 2), bool), np.zeros(k, bool))
        n = len(steps)
        rows = {c: np.zeros(n) for c in FOOTSTEP_COLUMNS}
        rows.update(agent=steps.agent, step=np.arange(n), time=steps.time, foot=np.full(n, "l"),
                    x=steps.position[:, 0], y=steps.position[:, 1], z=steps.position[:, 2],
                    energy=steps.energy, planner=steps.planner, group=np.full(n, "g"),
                    heading=steps.heading, kind=np.zeros(n, int), on_obstacle=np.zeros(n, int))
        writer.write_footsteps(rows)
    (path / "scenario.yaml").unlink()
    return path
