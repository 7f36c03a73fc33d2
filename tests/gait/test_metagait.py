"""MetaGait (Sun & Metaxas 2001, §6): path following, toe-out and spin turns, maximum
step length, the uneven-terrain loop (Eqs. 11–12), planner step lengths."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.errors import InputError
from crowdwalk.gait.metagait import (
    MetaGait,
    MetaGaitConfig,
    closest_arc_length,
    level_step_length,
    path_point,
    preferred_step_for_slope,
)


def _flat(xy):
    return np.zeros(len(xy))


def _corner(turn_deg: float, leg: float = 0.7):
    """Path: straight for one step from the origin, then turned by ``turn_deg``."""
    turn = np.radians(turn_deg)
    return np.array([[[0.0, 0.0], [leg, 0.0], [leg + 5 * np.cos(turn), 5 * np.sin(turn)]]])


@settings(max_examples=40, deadline=None)
@given(st.floats(-np.pi, np.pi), st.floats(-20, 20), st.floats(-20, 20), st.floats(0.3, 0.9))
def test_heading_follows_a_straight_path_in_any_direction(angle, x0, y0, sl):
    d = np.array([np.cos(angle), np.sin(angle)])
    path = np.array([[[x0, y0], [x0 + 10 * d[0], y0 + 10 * d[1]]]])
    offset = np.array([[x0, y0]]) + 2.0 * d + 0.3 * np.array([-d[1], d[0]])
    psi, s0 = MetaGait(1).heading(path, offset, np.array([sl]))
    assert s0[0] == pytest.approx(2.0)
    assert np.cos(psi[0] - angle) == pytest.approx(1.0)


def test_path_point_and_closest_arc_length_agree():
    path = np.array([[[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]])
    for s in (0.0, 1.5, 3.0, 5.0, 7.0):
        p = path_point(path, np.array([s]))
        assert closest_arc_length(path, p)[0] == pytest.approx(s)
    assert np.allclose(path_point(path, np.array([9.0])), [[3.0, 6.0]])  # extended


@pytest.mark.parametrize(
    ("turn", "toe", "spin"),
    [(30, 0, 0), (60, 15, 0), (70, 25, 0), (100, 25, 30), (-100, -25, -30)],
)
def test_toe_out_and_spin_turn_thresholds(turn, toe, spin):
    """Δ > T=45° adds Δ−T of toe-out up to T2=25°; beyond, Δ−T−T2 becomes a spin."""
    mg = MetaGait(1)
    path = _corner(turn)
    yaw, sp = mg.turn(path, np.zeros(1), np.array([0.7]))
    assert np.degrees(yaw[0]) == pytest.approx(toe, abs=0.5)
    assert np.degrees(sp[0]) == pytest.approx(spin, abs=0.5)


def test_spin_turn_waits_for_the_next_step():
    mg = MetaGait(1)
    kwargs = dict(time=[0.0], stance=np.zeros((1, 3)), swing_foot=[1], path=_corner(100),
                  level_step=[0.7], speed=[1.3], body_height=[1.75], ground=_flat)  # fmt: skip
    first = mg.next_step(np.array([0]), **kwargs)
    second = mg.next_step(np.array([0]), **kwargs)
    assert first.spin[0] == 0.0
    assert np.degrees(second.spin[0]) == pytest.approx(30.0, abs=0.5)


def test_maximum_step_length_limits_the_heading_change_per_cycle():
    cfg = MetaGaitConfig()
    mg = MetaGait(2, cfg)
    straight = np.array([[0.0, 0.0], [0.7, 0.0], [10.0, 0.0]])
    sharp = np.array([[0.0, 0.0], [1.2, 0.0], [1.2, 10.0]])
    paths = np.stack([straight, sharp])
    sl = mg.max_step_length(paths, np.zeros(2), np.array([0.7, 0.7]))
    assert sl[0] == pytest.approx(0.7)
    assert cfg.min_step_length <= sl[1] < 0.7
    psi_now = np.arctan2(*path_point(paths[1:], sl[1:])[0][::-1])
    later = path_point(paths[1:], 3 * sl[1:]) - path_point(paths[1:], 2 * sl[1:])
    change = np.arctan2(later[0, 1], later[0, 0]) - psi_now
    assert abs(change) <= cfg.max_heading_change + 1e-9 or sl[1] == cfg.min_step_length


def test_equation_11_preferred_step_lengths():
    level = np.array([0.627, 0.627, 0.623])
    slope = np.radians([0.0, -10.0, 10.0])
    sl = preferred_step_for_slope(level, slope)
    assert sl[0] == pytest.approx(0.627)
    assert sl[1] == pytest.approx(0.627 - 0.075)
    assert sl[2] == pytest.approx(0.623 - 0.019)


@settings(max_examples=30, deadline=None)
@given(st.floats(-12.0, 12.0), st.floats(0.5, 0.8))
def test_uneven_terrain_loop_lands_on_the_slope_at_the_preferred_length(deg, level):
    grade = np.tan(np.radians(deg))

    def ramp(xy):
        return grade * xy[:, 0]

    mg = MetaGait(1)
    sl, sh, target = mg.terrain_step(np.zeros((1, 3)), np.zeros(1), np.zeros(1),
                                     np.array([level]), np.array([2.0]), ramp)  # fmt: skip
    assert target[0, 2] == pytest.approx(ramp(target[:, :2])[0])  # on the ground
    assert sh[0] == pytest.approx(grade * sl[0])  # Eq. 12
    pref = preferred_step_for_slope(np.array([level]), np.arctan2(sh, sl))
    assert sl[0] == pytest.approx(pref[0], rel=1e-3)  # the fixed point of the loop
    assert sl[0] <= level + 1e-12


def test_planner_step_lengths_are_used_when_given():
    mg = MetaGait(2)
    path = np.tile(np.array([[[0.0, 0.0], [10.0, 0.0]]]), (2, 1, 1))
    cmd = mg.next_step(np.arange(2), [0.0, 0.0], np.zeros((2, 3)), [1, 1], path, [0.7, 0.7],
                       [1.3, 1.3], [1.75, 1.75], _flat, planned_length=[0.45, np.nan],
                       planned_height=[0.17, np.nan])  # fmt: skip
    assert cmd.step_length[0] == pytest.approx(0.45) and cmd.step_height[0] == pytest.approx(0.17)
    assert cmd.target[0, 2] == pytest.approx(0.17)
    assert cmd.step_length[1] == pytest.approx(0.7) and cmd.step_height[1] == 0.0
    assert cmd.duration[1] == pytest.approx(0.7 / 1.3)


def test_level_step_length_grows_with_leg_length_and_speed():
    sl = level_step_length(np.array([0.8, 0.9, 0.9]), np.array([1.3, 1.3, 1.5]))
    assert sl[0] < sl[1] < sl[2]
    assert 0.6 < sl[1] < 0.8  # measured 0.65–0.78 m at 1.34 m/s


def test_bad_input_is_rejected():
    with pytest.raises(InputError, match=r"^MetaGaitConfig\.toe_out_limit must be"):
        MetaGaitConfig(toe_out_limit=-1.0)
    with pytest.raises(InputError, match=r"^MetaGait\.path must be"):
        MetaGait(1).next_step(np.array([0]), [0.0], np.zeros((1, 3)), [1],
                              np.zeros((1, 1, 2)), [0.7], [1.3], [1.75], _flat)  # fmt: skip


# --- in the crowd: MetaGait.orient / orient_steps (§6.1 with Chen & Li §5.4) ------------


@settings(max_examples=60, deadline=None)
@given(turn=st.floats(-3.0, 3.0), ahead=st.floats(-3.0, 3.0), left=st.booleans(),
       base=st.floats(0.0, 0.3))
def test_orient_spins_only_what_the_hips_cannot_take(turn, ahead, left, base):
    """After the spin the heading is at most T from the stance foot's own direction, and
    nothing is spun when it already is; toe-out beyond the walker's own is at most T2,
    toward the turn ahead and only on the inside foot (the outside foot steps straight)."""
    from crowdwalk.gait.foot import wrap_angle
    from crowdwalk.gait.metagait import orient_steps
    from planners import split_turn

    cfg = MetaGaitConfig()
    side_sw = 1.0 if left else -1.0
    stance_yaw = np.array([-side_sw * base])  # stance foot along +x with its toe-out
    r = orient_steps(heading=np.array([turn]), heading_next=np.array([turn + ahead]),
                     stance_yaw=stance_yaw, swing_left=np.array([left]),
                     base_toe_out=np.array([base]), config=cfg)
    twist = wrap_angle(turn - (stance_yaw + r.spin + side_sw * base))
    assert abs(twist[0]) <= cfg.toe_out_threshold + 1e-9
    if abs(wrap_angle(turn)) <= cfg.toe_out_threshold:
        assert r.spin[0] == 0.0
    extra = r.toe_out[0] - base
    assert 0.0 <= extra <= cfg.toe_out_limit + 1e-12
    first = split_turn(float(wrap_angle(ahead)), cfg.toe_out_threshold,
                       "left" if left else "right")[0]
    if extra > 0:  # the inside foot: §5.4 turns it with this placement
        assert first.size and first[0] != 0.0 and np.sign(first[0]) == side_sw
        assert extra == pytest.approx(min(abs(wrap_angle(ahead)) - cfg.toe_out_threshold,
                                          cfg.toe_out_limit))
    assert r.landing_yaw[0] == pytest.approx(float(wrap_angle(turn + side_sw * r.toe_out[0])))


def test_orient_remembers_each_foot():
    """A 100-degree left turn in one step: the right stance foot spins 55 degrees (its
    hip takes T = 45), the left foot lands along the new heading with its toe-out; the
    next step starts from the feet where MetaGait left them."""
    mg = MetaGait(1)
    base = np.array([np.radians(7.0)])
    first = mg.orient([0], swing_foot=np.array([0]), heading=np.array([0.0]),
                      heading_next=np.array([0.0]), base_toe_out=base)
    assert first.spin[0] == 0.0
    turn = mg.orient([0], swing_foot=np.array([1]), heading=np.array([np.radians(100.0)]),
                     heading_next=np.array([np.radians(100.0)]), base_toe_out=base)
    # the left foot (stance) pointed at +7 deg: twist 100 - 0 = 100 -> spin 55
    assert np.degrees(turn.spin[0]) == pytest.approx(55.0)
    assert np.degrees(mg.foot_yaw[0]) == pytest.approx([7.0 + 55.0, 100.0 - 7.0])
    on = mg.orient([0], swing_foot=np.array([0]), heading=np.array([np.radians(100.0)]),
                   heading_next=np.array([np.radians(100.0)]), base_toe_out=base)
    assert on.spin[0] == 0.0  # the right foot landed along the new heading
