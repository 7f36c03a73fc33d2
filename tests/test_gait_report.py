"""crowdwalk.gait_report: figures measured from short ``crowdwalk run`` outputs."""

from pathlib import Path

import numpy as np
import pytest

from crowdwalk.body import (
    JOINT,
    JOINT_NAMES,
    Body,
    forward_kinematics,
    matrix_to_quaternion,
    rotation_y,
    rotation_z,
)
from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.gait_report import (
    WalkerTrack,
    edge_clearance,
    heel_slides,
    load_tracks,
    report_table,
    run_figures,
    second_differences,
    winter_at,
)

SCENARIOS = Path(__file__).parents[1] / "scenarios"


def lone_walker(tmp_path: Path, speed: float, height: float = 1.75, duration: float = 7.0):
    text = (SCENARIOS / "lone_walker.yaml").read_text()
    text = text.replace("free_speed: {mean: 1.33", f"free_speed: {{mean: {speed}")
    text = text.replace("body_height: {mean: 1.75", f"body_height: {{mean: {height}")
    path = tmp_path / f"lone_{speed}_{height}.yaml"
    path.write_text(text)
    out = tmp_path / f"run_{speed}_{height}"
    run_scenario(path, out, overrides=RunOverrides(duration=duration))
    return run_figures(out)[0]


@pytest.fixture(scope="module")
def natural(tmp_path_factory):
    return lone_walker(tmp_path_factory.mktemp("gait"), 1.33)


def test_lone_walker_at_natural_speed(natural):
    f = natural
    assert abs(f.speed / f.free_speed - 1) <= 0.05
    assert abs(f.step_length_z) <= 2 and abs(f.cadence_z) <= 2
    assert f.joint_r[0] >= 0.95 and f.joint_r[1] >= 0.95
    assert f.heel_slide_max <= 0.010 and f.stances_turning_over_10deg == 0
    assert f.pelvis_d2_max <= 0.02
    assert f.toe_drag_fraction == 0.0
    assert "agent 0" in report_table([f])
    # Winter 1991 is validation only (the curves are Bovi's): issue 11's joint targets
    assert np.all(f.joint_rms[:2] <= 5.0)
    assert f.toe_off_plantarflexion >= 15.0  # Winter: 18-20 deg (was 11 before the heel rise)


def test_pelvis_lists_and_rotates_as_measured(natural):
    """The §4.3 hip complex's list L(t) and the pelvis's rotation follow Bovi 2011's adult
    curves (docs/architecture.md "Pelvis from data"), measured on the run's hip joints:
    the list is greatest in loading response and the pelvis level again in late stance
    (the sine list peaked at 24 % and was still 3.6 deg at 30-45 %); the stance side is
    ahead at heel strike. The landing reach includes the swing hip's rise under the
    list, so the knee lands straighter (9.8-10 deg before; Bovi's own curve 8 deg)."""
    f = natural
    assert 0.06 <= f.pelvic_list_peak_phase <= 0.2 and f.pelvic_list_peak >= 2.0
    assert f.pelvic_list_mid_stance <= 0.3 * f.pelvic_list_peak
    assert f.pelvic_rotation_at_strike >= 2.0
    assert f.knee_at_strike <= 8.5
    # the trunk counter-rotates (Schwartz 2008): the shoulder line turns against the hips
    assert f.trunk_rotation_at_strike <= -2.0


@pytest.mark.parametrize(("speed", "height"), [(1.0, 1.75), (1.7, 1.75), (1.33, 1.50)])
def test_lone_walker_steps_follow_speed_and_size(tmp_path, speed, height):
    """Issue 11 targets met at slow and fast free speeds and for a short body: speed within
    5 %, step length and cadence within 2 SD of WBDS at the achieved speed."""
    f = lone_walker(tmp_path, speed, height)
    assert abs(f.speed / f.free_speed - 1) <= 0.05
    assert abs(f.step_length_z) <= 2 and abs(f.cadence_z) <= 2
    assert f.heel_slide_max <= 0.010 and f.pelvis_d2_max <= 0.02
    # level steps from level data (docs/architecture.md "Level steps"): hip and knee
    # within issue 11's RMS against Winter, and no toe grazing the floor (short slow
    # steps used to blend the stair datasets, then to graze at 0-1 mm)
    assert np.all(f.joint_rms[:2] <= 5.0) and np.all(f.joint_r[:2] >= 0.95)
    assert f.toe_drag_fraction == 0.0


def test_winter_reference_interpolates_by_cadence():
    slow, _ = winter_at(87.0)
    fast, _ = winter_at(123.0)
    mid, _ = winter_at(105.0)
    assert mid.shape == (3, 51)
    assert not np.allclose(slow, fast)
    np.testing.assert_allclose(winter_at(60.0)[0], slow)  # clamped


def test_heel_slide_and_jumps_are_detected():
    """A planted foot dragged 3 cm shows as a 3 cm slide; a 10 cm jump as a d2 spike."""
    f, j = 40, 20
    pos = np.zeros((f, j, 3))
    pos[:, 2, :] = [0.0, 0.1, 0.9]   # l_hip
    pos[:, 7, :] = [0.0, -0.1, 0.9]  # r_hip
    for ankle, ball, y in ((4, 6, 0.1), (9, 11, -0.1)):
        pos[:, ankle] = [0.0, y, 0.068]
        pos[:, ball] = [0.128, y, 0.0]
    pos[:, 4, 0] += np.linspace(0, 0.03, f)  # the left foot slides 3 cm while planted
    pos[:, 6, 0] += np.linspace(0, 0.03, f)
    track = WalkerTrack(agent=0, body_height=1.75, time=np.arange(f) / 25,
                        positions=pos, contact=np.ones((f, 2), bool), fps=25.0)
    slides, turns, heel_turns = heel_slides(track, 0)
    assert slides[0] == pytest.approx(0.03, abs=1e-6) and turns[0] == pytest.approx(0.0)
    assert heel_turns[0] == pytest.approx(0.0)
    assert heel_slides(track, 1)[0][0] == pytest.approx(0.0, abs=1e-9)
    jump = pos[:, 4].copy()
    jump[20] += [0.0, 0.0, 0.10]
    assert second_differences(jump, 25.0).max() == pytest.approx(0.20, abs=1e-6)


def test_a_foot_turning_on_its_heel_is_reported():
    """A planted foot whose toes swing 20 degrees round the heel: a turn with the heel
    down (not a spin on the ball) and a ball that slides."""
    f = 30
    pos = np.zeros((f, 20, 3))
    pos[:, 2, :] = [0.0, 0.1, 0.9]
    pos[:, 7, :] = [0.0, -0.1, 0.9]
    yaw = np.deg2rad(np.linspace(0.0, 20.0, f))
    heel = np.array([-0.05, 0.1])
    for i, y in enumerate(yaw):
        d = np.array([np.cos(y), np.sin(y)])
        pos[i, 4] = [*(heel + 0.05 * d), 0.068]
        pos[i, 6] = [*(heel + 0.178 * d), 0.0]
    pos[:, 9] = [0.0, -0.1, 0.068]
    pos[:, 11] = [0.128, -0.1, 0.0]
    track = WalkerTrack(agent=0, body_height=1.75, time=np.arange(f) / 25,
                        positions=pos, contact=np.ones((f, 2), bool), fps=25.0)
    slides, turns, heel_turns = heel_slides(track, 0)
    assert heel_turns[0] == pytest.approx(20.0, abs=0.5)
    assert slides[0] > 0.03  # the ball swings round the heel


class _Poses(list):
    """A :class:`crowdwalk.record.Poses` stand-in: the frames of one agent."""

    body_heights = {0: 1.75}
    fps = 25.0


def _pushing_off(pitch: np.ndarray, yaw: np.ndarray) -> _Poses:
    """One walker standing on its left ball: per frame the whole body turned by ``yaw``
    [rad] and the left foot plantarflexed by ``pitch`` [rad] at the talocrural joint,
    posed by forward kinematics and moved so that the left ball stays put; written as
    :class:`crowdwalk.record.PoseRecord` rows (local quaternions and world positions)."""
    from crowdwalk.record import PoseRecord

    f, nj = pitch.size, len(JOINT_NAMES)
    body = Body.from_heights(np.full(f, 1.75))
    local = np.tile(np.eye(3), (f, nj, 1, 1))
    local[:, JOINT["l_talocrural"]] = rotation_y(pitch)
    local[:, JOINT["l_metatarsal"]] = rotation_y(-pitch)  # toes stay on the floor
    root = rotation_z(yaw)
    pos, _ = forward_kinematics(body, np.zeros((f, 3)), root, local)
    pos -= pos[:, [JOINT["l_metatarsal"]]]  # the ball planted at the origin
    quat = matrix_to_quaternion(local)
    root_q = matrix_to_quaternion(root)
    return _Poses(PoseRecord(frame=i, time=i / 25.0, ids=np.array([0]),
                             root_position=pos[i:i + 1, 0], root_quaternion=root_q[i:i + 1],
                             joints=quat[i:i + 1], positions=pos[i:i + 1],
                             contact=np.ones((1, 2), bool), fallback=np.zeros(1, bool))
                  for i in range(f))


def test_a_foot_pushing_off_past_vertical_does_not_count_as_a_turn():
    """The planted foot's yaw is read from the written joint rotations: a foot that rises
    on its ball until the ankle -> ball line points past straight down (80 deg of
    plantarflexion at push-off, as KLAW's does) has not turned; read from the ankle and
    ball positions its heading flipped by 180 deg (a KLAW lone walker counted 18 of 29
    straight-line stances as turns). A real turn on the ball still counts."""
    f = 30
    pitch = np.deg2rad(np.linspace(0.0, 80.0, f))
    (track,) = load_tracks(_pushing_off(pitch, np.zeros(f))).values()
    slides, turns, heel_turns = heel_slides(track, 0)
    assert turns[0] == pytest.approx(0.0, abs=1e-3)
    yaw = np.deg2rad(np.linspace(0.0, 20.0, f))
    (track,) = load_tracks(_pushing_off(np.zeros(f), yaw)).values()
    assert heel_slides(track, 0)[1][0] == pytest.approx(20.0, abs=1e-3)
    assert heel_slides(track, 1)[1][0] == pytest.approx(20.0, abs=1e-3)


def test_clearance_over_an_edge_and_a_foot_across_one():
    """A swing foot carried flat 3 cm above a 17 cm step edge clears it by 3 cm (the
    samples beyond the edge see the tread top); a planted foot overhanging the edge
    rests across it; a foot on one tread does not."""
    f = 30
    step = 0.5  # edge at x = 0.5: ground 0 before, 0.17 after

    def ground(xy):
        return np.where(xy[:, 0] >= step, 0.17, 0.0)

    pos = np.zeros((f, 20, 3))
    pos[:, 2] = [0.0, 0.1, 1.1]
    pos[:, 7] = [0.0, -0.1, 1.1]
    x = np.linspace(-0.2, 1.2, f)
    pos[:, 4] = np.column_stack([x, np.full(f, 0.1), np.full(f, 0.20 + 0.06825)])
    pos[:, 6] = pos[:, 4] + [0.12775, 0.0, -0.06825]
    pos[:, 9] = [0.55 - 0.12775, -0.1, 0.17 + 0.06825]  # right ball on the upper tread,
    pos[:, 11] = [0.55, -0.1, 0.17]                    # its heel over the drop
    contact = np.ones((f, 2), bool)
    contact[3:f - 3, 0] = False
    track = WalkerTrack(agent=0, body_height=1.75, time=np.arange(f) / 25, positions=pos,
                        contact=contact, fps=25.0)
    over, across = edge_clearance(track, 0, ground)
    assert over.shape == (1,) and over[0] == pytest.approx(0.03, abs=1e-6)
    assert edge_clearance(track, 1, ground)[1].tolist() == [True]
    lower = pos.copy()
    lower[:, 4, 2] -= 0.05  # now 2 cm into the tread
    lower[:, 6, 2] -= 0.05
    track = WalkerTrack(agent=0, body_height=1.75, time=track.time, positions=lower,
                        contact=contact, fps=25.0)
    assert edge_clearance(track, 0, ground)[0][0] == pytest.approx(-0.02, abs=1e-6)
    assert edge_clearance(track, 0, ground)[1].tolist() == [False, False]


@pytest.fixture(scope="module")
def stairs(tmp_path_factory):
    out = tmp_path_factory.mktemp("gait") / "stairs"
    run_scenario(SCENARIOS / "stairs_up_down.yaml", out, overrides=RunOverrides(duration=16.0))
    (f,) = run_figures(out)
    return f


def test_stair_pelvis_joins_steps_without_a_velocity_jump(stairs):
    """Issue 11 item 5 (stairs, 25 fps): the root joins each stair step C¹, so the pelvis's
    second difference stays under 4 cm per frame (5.0 cm with a C⁰ join: the pelvis
    falling at 1.2 m/s at the last step down met data starting at rest). Level walking
    keeps the C⁰ join (its ordinary 0.28 m/s kink)."""
    assert stairs.pelvis_d2_max <= 0.04


def test_stair_ascent_knee_follows_bovi_in_stance(stairs):
    """Issue 11 item 5 (knee flexion on stairs within 10° of Bovi's curves): over the
    stance (0–60 % of the cycle, where a step-over-step cycle can follow Bovi's, which
    ends off the flight) the ascending knee is within 10° RMS of Bovi's, and the swing
    knee peaks under 100°. Main before gait11: 20.2° and 119° (the stair datasets'
    linear closure and the planner's Bezier swing); measured now 8.8° and 93°."""
    assert stairs.stairs_up_knee_stance_rms <= 10.0
    assert stairs.stairs_up_knee_peak < 100.0
