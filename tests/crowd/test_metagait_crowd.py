"""MetaGait in the crowd (Sun & Metaxas 2001, §6.1): every step of a ``crowdwalk run``
is oriented by it, and a planted foot turns only in a spin turn, on its ball."""

from pathlib import Path

import numpy as np
import pytest

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.gait_report import foot_points, load_tracks, stance_runs
from crowdwalk.record import open_run

SCENARIOS = Path(__file__).parents[2] / "scenarios"


@pytest.fixture(scope="module")
def corner(tmp_path_factory):
    """The corner's twenty walkers for 14 s (the first round the bend, the others queue
    into it), poses at 25 fps."""
    tmp = tmp_path_factory.mktemp("corner")
    text = (SCENARIOS / "corner.yaml").read_text()
    text = text.replace("fps: 10", "fps: 25")
    text = text.replace("dt: 0.05", "dt: 0.04").replace("poses: false", "poses: true")
    path = tmp / "corner.yaml"
    path.write_text(text)
    run_scenario(path, tmp / "run", overrides=RunOverrides(duration=14.0))
    return open_run(tmp / "run")


def test_steps_carry_metagait_orientation(corner):
    steps = corner.footsteps()
    assert np.all(np.isfinite(steps.toe_out)) and np.all(np.isfinite(steps.spin))
    # round the corner some steps turn more than T: their stance foot spins, and a spin
    # is never more than the turn beyond T of its step
    turn = np.zeros(steps.agent.size)
    for a in np.unique(steps.agent):
        rows = np.flatnonzero(steps.agent == a)
        h = steps.heading[rows]
        turn[rows[1:]] = np.angle(np.exp(1j * np.diff(h)))
    spun = np.abs(steps.spin) > 1e-9
    assert spun.sum() >= 2
    assert np.all(np.abs(steps.spin) <= np.abs(turn) + np.radians(30.0))
    assert np.all(np.sign(steps.spin[spun]) == np.sign(turn[spun]))


def test_a_planted_foot_turns_only_on_its_ball(corner):
    """Heel slide <= 10 mm per stance; while the heel is down the foot does not turn."""
    poses = corner.poses()
    tracks = load_tracks(poses)
    poses.close()
    stances = 0
    for track in tracks.values():
        for side in (0, 1):
            pts = foot_points(track, side)
            f = pts["toe"] - pts["heel"]
            yaw = np.degrees(np.unwrap(np.arctan2(f[:, 1], f[:, 0])))
            for a, b in stance_runs(track.contact[:, side]):
                heel = pts["heel"][a:b]
                down = heel[:, 2] <= heel[:, 2].min() + 0.005
                slide = np.linalg.norm(heel[down, :2] - heel[down][0, :2], axis=1).max()
                assert slide <= 0.010
                assert np.ptp(yaw[a:b][down]) <= 1.0
                stances += 1
    assert stances > 40
