"""KLAW and Ko-Badler take MetaGait's orientation (Sun & Metaxas 2001, §6.1) from the
crowd's steps, as the ElevInterp Animator does: the landing foot points the step's
toe-out from its heading, and a planted foot turns only in a spin turn, on its ball.
Measured on ``crowdwalk run`` output (poses, footsteps) and gait-report's figures."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from crowdwalk.body import JOINT, LEG_JOINTS, PARENTS, Body, quaternion_to_matrix
from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.gait.klaw import KlawEngine
from crowdwalk.gait.ko_badler.engine import KoBadlerEngine
from crowdwalk.gait_report import run_figures, stance_runs
from crowdwalk.record import open_run

SCENARIOS = Path(__file__).parents[2] / "scenarios"


def _wrap(x):
    return np.angle(np.exp(1j * np.asarray(x)))


@pytest.fixture(scope="module", params=["klaw", "ko_badler"])
def corner(request, tmp_path_factory):
    """The corner's twenty walkers for 14 s with ``gait: <engine>``, poses at 25 fps."""
    tmp = tmp_path_factory.mktemp(f"corner_{request.param}")
    text = (SCENARIOS / "corner.yaml").read_text()
    text = text.replace("fps: 10", "fps: 25")
    text = text.replace("dt: 0.05", "dt: 0.04").replace("poses: false", "poses: true")
    text = text.replace("planner: best_first_multistart",
                        f"planner: best_first_multistart\n    gait: {request.param}")
    assert f"gait: {request.param}" in text
    path = tmp / "corner.yaml"
    path.write_text(text)
    run_scenario(path, tmp / "run", overrides=RunOverrides(duration=14.0))
    return open_run(tmp / "run")


def _foot_yaw(joints: np.ndarray, side: int) -> np.ndarray:
    """Yaw (F,) [rad] of one foot from the stored joint rotations (``joints`` (F, J, 4)
    local wxyz, what ``crowdwalk export-bvh`` writes): the direction its lateral axis
    makes, whatever the foot's pitch."""
    local = quaternion_to_matrix(joints)
    chain, j = [], int(LEG_JOINTS[side, 2])
    while j > 0:
        chain.append(j)
        j = int(PARENTS[j])
    world = local[:, 0]
    for j in reversed(chain):
        world = world @ local[:, j]
    return np.unwrap(np.arctan2(-world[:, 0, 1], world[:, 1, 1]))


def _stances(run):
    """Per stance that starts at a footstep's heel strike: (landing yaw error [rad]: foot
    yaw once flat minus heading + side · toe_out; the spin of the step it then stands in
    [rad]; the foot's yaw change from then to that step's end [rad])."""
    steps = run.footsteps()
    poses = run.poses()
    out = []
    for agent in np.unique(steps.agent):  # analysis of a finished run: a pass per walker
        track = poses.agent_track(int(agent))
        mine = steps.of_agent(agent)
        for side, name, outward in ((0, "left", 1.0), (1, "right", -1.0)):
            yaw = _foot_yaw(track["joints"], side)
            rows = np.flatnonzero(mine.foot == name)
            for a, b in stance_runs(track["contact"][:, side].astype(bool)):
                if not rows.size:
                    continue
                k = rows[np.argmin(np.abs(mine.time[rows] - track["time"][a]))]
                later = np.flatnonzero(mine.time > mine.time[k] + 1e-6)
                if abs(mine.time[k] - track["time"][a]) > 0.06 or not later.size or b - a < 8:
                    continue
                flat = a + 3
                land = mine.heading[k] + outward * mine.toe_out[k]
                # the end of the step it stands in: its spin turn done
                end = min(int(np.searchsorted(track["time"], mine.time[later[0]] - 1e-6)),
                          b - 1)
                out.append((_wrap(yaw[flat] - land), mine.spin[later[0]],
                            _wrap(yaw[end] - yaw[flat])))
    poses.close()
    return np.array(out)


def test_landing_foot_points_the_steps_toe_out(corner):
    err = np.abs(_stances(corner)[:, 0])
    assert err.size > 100
    # Ko-Badler's feet pointed along the heading (7° off), KLAW's by the style's angle
    assert np.degrees(np.median(err)) <= 0.5 and np.degrees(np.percentile(err, 95)) <= 2.0


def test_a_planted_foot_turns_only_in_a_spin_turn_on_its_ball(corner):
    rows = _stances(corner)
    spin, turn = rows[:, 1], rows[:, 2]
    spun = np.abs(spin) > np.radians(10.0)
    assert spun.sum() >= 3
    # the foot turns by its spin turn (before: not at all) and otherwise not at all
    assert np.all(np.abs(turn[spun] - spin[spun]) <= 0.1 * np.abs(spin[spun]) + np.radians(1))
    assert np.all(np.abs(turn[np.abs(spin) < 1e-9]) <= np.radians(1.0))
    # gait-report's planted-foot figures: no turn with the heel down, no heel slide
    # (its "stances turning > 10°" reads the yaw from ankle -> ball with straight toes,
    # which points backwards when KLAW's foot stands steeply on its ball at push-off)
    for fig in run_figures(corner.path):
        assert fig.heel_down_turn_max <= 1.0
        assert fig.heel_slide_max <= 0.010


@pytest.mark.parametrize("engine", ["klaw", "ko_badler"])
def test_one_engine_step_lands_at_the_commanded_toe_out(engine):
    """A straight step whose toe-out (20°) differs from the walker's own angle."""
    body = Body.from_heights(np.array([1.75]))
    e = KlawEngine(body) if engine == "klaw" else KoBadlerEngine(body)
    toe = np.radians(20.0)
    for k, (foot, x0, x1) in enumerate(((1, 0.0, 0.7), (0, 0.7, 1.4))):  # right, then left
        y_st, y_sw = (0.05, -0.05) if foot == 1 else (-0.05, 0.05)
        e.command(SimpleNamespace(
            agent=np.array([0]), step=np.array([k + 1]), start_time=np.array([0.55 * k]),
            duration=np.array([0.55]), foot=np.array([foot]),
            start=np.array([[x0, y_st, 0.0]]), target=np.array([[x1, y_sw, 0.0]]),
            stance_centre=np.array([[x0, 0.0]]), heading=np.zeros(1),
            length=np.array([0.7]), rise=np.zeros(1), swing_bezier=np.full((1, 4, 3), np.nan),
            toe_out=np.array([toe]), spin=np.zeros(1)))
        p = e.pose(0.55 * (k + 1) - 1e-6, np.array([0])).positions[0]
        side = "r" if foot == 1 else "l"
        f = p[JOINT[f"{side}_metatarsal"]] - p[JOINT[f"{side}_talocrural"]]
        outward = -1.0 if foot == 1 else 1.0
        assert np.degrees(np.arctan2(f[1], f[0])) == pytest.approx(outward * 20.0, abs=1.5)
