"""Local steering: the chosen step's swept body keeps clear of neighbours and walls."""

import numpy as np
import shapely
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.geometry import segment_distance
from crowdwalk.crowd.steering import Neighbours, choose_steps

ROOM = ClearanceField.from_area(shapely.box(-6, -6, 6, 6))
R = 0.2


def _neighbours(now, end):
    k = len(now)
    return Neighbours(valid=np.ones((1, k), bool), now=now[None], end=end[None],
                      velocity=(end - now)[None] / 0.5, radius=np.full((1, k), R))


def _choose(now, end, heading=0.0, target=(3.0, 0.0)):
    return choose_steps(
        position=np.zeros((1, 2)), stance=np.array([[0.1, 0.0]]), heading=np.array([heading]),
        radius=np.array([R]), route_direction=np.array([[1.0, 0.0]]),
        target=np.array([target]), nominal_step=np.array([0.7]),
        neighbours=_neighbours(now, end), clearance=ROOM)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.floats(-2.5, 2.5), st.floats(-2.5, 2.5), st.floats(-0.4, 0.4),
                          st.floats(-0.4, 0.4)), min_size=1, max_size=12))
def test_step_sweep_keeps_clear_of_committed_sweeps(raw):
    arr = np.array(raw)
    now, end = arr[:, :2], arr[:, :2] + arr[:, 2:]
    # a valid starting state: the agent (a point now) is clear of every sweep
    assume(np.all(segment_distance(np.zeros(2), np.zeros(2), now, end) >= 2 * R))
    choice = _choose(now, end)
    if not choice.move[0]:
        return
    for length in np.linspace(0.15, choice.free_length[0], 5):
        body_end = np.array([0.1, 0.0]) + 0.5 * length * choice.direction[0]
        gap = segment_distance(np.zeros(2), body_end, now, end)
        assert np.all(gap >= 2 * R - 1e-9)


def test_free_corridor_goes_straight_at_the_preferred_length():
    far = np.array([[0.0, 5.0]])
    choice = _choose(far, far)
    assert choice.move[0]
    np.testing.assert_allclose(choice.direction[0], [1, 0], atol=1e-9)
    assert choice.free_length[0] >= 0.7


def test_blocked_ahead_sidesteps_or_waits_but_never_walks_into_the_blocker():
    wall_of_people = np.array([[0.45, y] for y in np.linspace(-0.4, 0.4, 3)])
    choice = _choose(wall_of_people, wall_of_people)
    if choice.move[0]:
        assert choice.direction[0][0] < 0.99  # not straight ahead


def test_oncoming_walker_is_passed_on_the_right():
    oncoming = np.array([[2.0, 0.0]])
    choice = _choose(oncoming, oncoming + [-0.35, 0.0])
    assert choice.move[0]
    assert choice.direction[0][1] < 0  # to the right of +x is -y


def test_walls_are_respected():
    corridor = ClearanceField.from_area(shapely.box(-1, -0.5, 10, 0.5))
    choice = choose_steps(
        position=np.zeros((1, 2)), stance=np.zeros((1, 2)), heading=np.array([np.pi / 2]),
        radius=np.array([R]), route_direction=np.array([[0.0, 1.0]]),
        target=np.array([[0.0, 3.0]]), nominal_step=np.array([0.7]),
        neighbours=Neighbours(*(np.zeros((1, 0) + s) for s in ((), (2,), (2,), (2,), ()))),
        clearance=corridor)
    if choice.move[0]:
        end = 0.5 * choice.free_length[0] * choice.direction[0]
        assert corridor(end[None])[0] >= R - 1e-9


def test_follower_steps_into_the_room_its_leader_vacates():
    # in single file (a 0.6 m corridor) the leader is 0.5 m ahead and walking 0.6 m
    # further within 0.5 s: against its whole sweep the follower could barely step; in time
    # it follows at the same pace
    corridor = ClearanceField.from_area(shapely.box(-6, -0.3, 6, 0.3))
    now, end = np.array([[0.5, 0.0]]), np.array([[1.1, 0.0]])
    nbs = Neighbours(valid=np.ones((1, 1), bool), now=now[None], end=end[None],
                     velocity=(end - now)[None] / 0.5, radius=np.full((1, 1), R),
                     remaining=np.full((1, 1), 0.5))
    kw = dict(position=np.zeros((1, 2)), stance=np.zeros((1, 2)), heading=np.zeros(1),
              radius=np.array([R]), route_direction=np.array([[1.0, 0.0]]),
              target=np.array([[3.0, 0.0]]), nominal_step=np.array([0.7]), neighbours=nbs,
              clearance=corridor, speed=np.array([1.3]))
    whole = choose_steps(**kw)
    timed = choose_steps(**kw, step_time=np.array([0.5]))
    assert whole.free_length[0] <= 0.15
    assert timed.move[0] and timed.free_length[0] >= 0.6
    # and the body stays clear of the leader at every instant (both stand afterwards)
    L = timed.free_length[0]
    dur = max(L / 1.3, 0.5)
    vel = 0.5 * L * timed.direction[0] / dur
    t = np.linspace(0.0, 2.0, 2001)[:, None]
    me = vel * np.minimum(t, dur)
    leader = now[0] + (end[0] - now[0]) / 0.5 * np.minimum(t, 0.5)
    assert np.linalg.norm(me - leader, axis=1).min() >= 2 * R - 1e-9


@settings(max_examples=25, deadline=None)
@given(st.lists(st.lists(st.tuples(st.floats(-2.5, 2.5), st.floats(-2.5, 2.5),
                                   st.floats(-0.4, 0.4), st.floats(-0.4, 0.4)),
                         min_size=0, max_size=6), min_size=2, max_size=5))
def test_deciding_together_equals_deciding_alone(crowds):
    # agents with different numbers of neighbours, decided in one batch (the swept-body
    # test runs over the relevant (agent, neighbour) pairs only) and one at a time
    k = max(len(c) for c in crowds)
    m = len(crowds)
    now, end = np.zeros((m, max(k, 1), 2)), np.zeros((m, max(k, 1), 2))
    valid = np.zeros((m, max(k, 1)), bool)
    for i, c in enumerate(crowds):
        if c:
            arr = np.array(c)
            now[i, :len(c)], end[i, :len(c)] = arr[:, :2], arr[:, :2] + arr[:, 2:]
            valid[i, :len(c)] = True
    position = np.zeros((m, 2))
    args = dict(stance=np.tile([0.1, 0.0], (m, 1)), heading=np.zeros(m),
                radius=np.full(m, R), route_direction=np.tile([1.0, 0.0], (m, 1)),
                target=np.tile([3.0, 0.0], (m, 1)), nominal_step=np.full(m, 0.7))
    nbs = Neighbours(valid=valid, now=now, end=end, velocity=(end - now) / 0.5,
                     radius=np.full(valid.shape, R))
    together = choose_steps(position, neighbours=nbs, clearance=ROOM, **args)
    for i in range(m):
        alone = choose_steps(position[i:i + 1], neighbours=Neighbours(
            *(a[i:i + 1] for a in (nbs.valid, nbs.now, nbs.end, nbs.velocity, nbs.radius))),
            clearance=ROOM, **{key: v[i:i + 1] for key, v in args.items()})
        assert together.move[i] == alone.move[0]
        assert together.free_length[i] == alone.free_length[0]
        assert np.array_equal(together.direction[i], alone.direction[0])


def test_gap_reach_makes_a_follower_fall_in_beside_the_walker_ahead():
    # a walker 0.7 m ahead on the same line, walking on: the swept-body test lets the
    # follower close up behind it; scored at the step the contact gap allows, the
    # follower steps beside-behind it instead (the zipper)
    from crowdwalk.crowd.speed import GapSteps

    leader = np.array([[0.8, 0.0]])
    nbs = Neighbours(valid=np.ones((1, 1), bool), now=leader[None], end=leader[None] + [0.3, 0.0],
                     velocity=np.array([[[0.6, 0.0]]]), radius=np.full((1, 1), R))
    gap = GapSteps(np.zeros((1, 2)), np.array([R]), nbs.end, nbs.radius, nbs.valid, nbs.valid,
                   np.array([1.34]), np.array([0.9]), time_gap=1.0)

    args = dict(position=np.zeros((1, 2)), stance=np.array([[0.1, 0.0]]),
                heading=np.array([0.0]), radius=np.array([R]),
                route_direction=np.array([[1.0, 0.0]]), target=np.array([[3.0, 0.0]]),
                nominal_step=np.array([0.7]), neighbours=nbs, clearance=ROOM)
    behind = choose_steps(**args)
    beside = choose_steps(**args, gap=gap)
    assert behind.move[0] and beside.move[0]
    assert abs(behind.direction[0][1]) < 1e-9
    assert abs(beside.direction[0][1]) > 0.1


def test_an_oncoming_walker_behind_the_nearest_group_mates_is_avoided():
    # twelve group-mates walking the same way, all nearer than the oncoming walker: the
    # evasion must not look at the nearest neighbours only (they are the group's own)
    mates = np.array([[x, y] for x in (-0.5, -0.9, -1.3) for y in (-0.9, -0.5, 0.5, 0.9)])
    oncoming = np.array([[2.5, 0.0]])
    now = np.vstack([mates, oncoming])
    velocity = np.vstack([np.tile([1.3, 0.0], (12, 1)), [[-1.3, 0.0]]])
    nbs = Neighbours(valid=np.ones((1, 13), bool), now=now[None], end=now[None],
                     velocity=velocity[None], radius=np.full((1, 13), R))
    choice = choose_steps(
        position=np.zeros((1, 2)), stance=np.array([[0.1, 0.0]]), heading=np.array([0.0]),
        radius=np.array([R]), route_direction=np.array([[1.0, 0.0]]),
        target=np.array([[3.0, 0.0]]), nominal_step=np.array([0.7]), neighbours=nbs,
        clearance=ROOM, speed=np.array([1.3]))
    assert choice.move[0]
    assert choice.direction[0][1] < -0.1  # evades, to its right



def _turning(params, heading=0.0, stuck=0.0, nominal=0.7):
    """A walker heading +x whose route turns to +y (target 3 m to its left), open room."""
    none = Neighbours(*(np.zeros((1, 0) + s) for s in ((), (2,), (2,), (2,), ())))
    return choose_steps(
        position=np.zeros((1, 2)), stance=np.array([[0.1, 0.0]]), heading=np.array([heading]),
        radius=np.array([R]), route_direction=np.array([[0.0, 1.0]]),
        target=np.array([[0.0, 3.0]]), nominal_step=np.array([nominal]),
        neighbours=none, clearance=ROOM, params=params, stuck=np.array([stuck]))


def test_turn_limit_splits_a_sharp_turn_over_steps():
    """Chen & Li §5.4 threshold as a steering limit (``turn_limit_deg``): a walking step
    turns at most 45° from the heading; a walker that was standing, or whose step
    straight on is cut below ``turn_limit_spare`` of its nominal step, is spared."""
    from dataclasses import replace

    from crowdwalk.crowd.steering import SteeringParams

    def turn(choice):
        return np.degrees(np.arctan2(choice.direction[0, 1], choice.direction[0, 0]))

    free = _turning(SteeringParams())
    assert free.move[0] and turn(free) > 50.0  # unlimited: straight for the target
    limited = replace(SteeringParams(), turn_limit_deg=45.0)
    step = _turning(limited)
    assert step.move[0] and 0.0 < turn(step) <= 45.0 + 1e-6
    assert turn(_turning(limited, stuck=0.5)) == turn(free)  # from standing
    # with ``turn_limit_spare`` a walker whose way straight on is cut short (neighbours,
    # walls) is spared; by default (0) it is not
    from crowdwalk.crowd.steering_kernels import turn_allowed

    def ok(params, ahead):
        limit = np.radians(params.turn_limit_deg) + 1e-9
        return [[turn_allowed(np.radians(c), 0.0, ahead, 0.7, 0.0, limit,
                              params.turn_limit_spare) for c in (30.0, 60.0)]]

    spare = replace(limited, turn_limit_spare=1.0)
    assert ok(spare, 0.75) == [[True, False]] and ok(spare, 0.6) == [[True, True]]
    assert ok(limited, 0.6) == [[True, False]]
    import pytest

    from crowdwalk.errors import InputError
    with pytest.raises(InputError, match="turn_limit_deg"):
        SteeringParams(turn_limit_deg=0.0)
