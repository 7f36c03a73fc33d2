"""The crowd's footstep planner: cache keys relative to the stance foot, served plans."""

import numpy as np
import shapely

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.footsteps import FootstepPlanner
from crowdwalk.terrain import StairFlight, Terrain
from planners import GroundProfile, Leg, PlannerConfig, plan

CONFIG = PlannerConfig(n_steps=3, min_step_ratio=0.15)
LEGS = [Leg.from_body_height(1.70), Leg.from_body_height(1.80)]


def _planner(terrain, area=None):
    clearance = None if area is None else ClearanceField.from_area(area)
    return FootstepPlanner(terrain, LEGS, config=CONFIG, horizon=3, clearance=clearance)


def _plan(fp, stance, stance_z, direction, leg, speed, trailing):
    m = len(stance)
    return fp.plan(np.asarray(stance, float), np.full(m, stance_z),
                   direction=np.tile(np.asarray(direction, float), (m, 1)),
                   leg=np.full(m, leg), speed=np.full(m, speed),
                   planner=np.full(m, "best_first"), trailing=np.full(m, trailing))


def test_level_ground_of_any_extent_is_planned_once_per_leg_and_speed():
    # agents at different distances from a wall: their local paths (and profiles) end at
    # different lengths, but level ground is the same problem for all of them
    area = shapely.box(0, -5, 20, 5)
    fp = _planner(Terrain((0, -5, 20, 5), 0.3), area)
    stance = [[x, 0.0] for x in (2.0, 17.0, 18.0, 18.5, 19.0)]
    first = _plan(fp, stance, 0.3, [1.0, 0.0], 0, 1.3, -0.6)
    assert fp.calls - fp.hits == len(stance)  # all new in this tick (one planner run)
    assert first.ok.all()
    again = _plan(fp, [[x + 0.5, 1.0] for x, _ in stance], 0.3, [1.0, 0.0], 0, 1.3, -0.4)
    assert again.from_cache.all()  # other extents and trailing feet: still level ground
    assert np.array_equal(again.step_length, first.step_length)
    other = _plan(fp, stance[:1], 0.3, [1.0, 0.0], 1, 1.3, -0.6)
    assert not other.from_cache.any()  # another leg class is another problem


def test_served_plan_is_the_planners_plan_for_the_agents_own_ground():
    # down a flight: the cache must tell apart stance feet at different places on a tread
    flight = StairFlight((0.0, 0.0), 0.0, 3.0, 0.30, 0.17, 10, z0=1.7, up=False)
    terrain = Terrain((-5, -5, 10, 5), 0.0, (flight,))
    fp = _planner(terrain)
    xs = np.array([0.42, 0.47, 0.72])  # the last one on the next tread, 0.30 further
    z = terrain.height(np.column_stack([xs, np.zeros(3)]))
    got = [_plan(fp, [[x, 0.0]], zi, [1.0, 0.0], 0, 1.3, -0.3) for x, zi in zip(
        xs, z, strict=True)]
    assert not got[1].from_cache[0]  # 5 cm further along: a different problem
    for x, zi, g in zip(xs, z, got, strict=True):
        s, zz = terrain.profile_arrays(np.array([[x - 1.0, 0.0], [x + 3.0, 0.0]]))
        want = plan(GroundProfile(s - 1.0, zz - zi), LEGS[0], 1.3, config=CONFIG,
                    trailing=-0.3)
        assert g.ok[0] and want.ok
        np.testing.assert_allclose(g.step_length[0], want.step_lengths, atol=1e-9)
        np.testing.assert_allclose(g.step_height[0], np.diff(want.footholds_z), atol=1e-9)


def test_profiles_found_in_threads_give_the_same_plans(monkeypatch):
    # walkers spread over a flight and the ground around it, some near the area's edge
    # (their local paths end early): the profiles are found for parts of them at once
    import crowdwalk.workers as W

    monkeypatch.setattr(W, "MIN_THREAD_ROWS", 1)
    flight = StairFlight((0.0, 0.0), 0.0, 3.0, 0.30, 0.17, 10, z0=1.7, up=False)
    terrain = Terrain((-5, -5, 10, 5), 0.0, (flight,))
    area = shapely.box(-5, -5, 4.0, 5)
    rng = np.random.default_rng(3)
    stance = np.column_stack([rng.uniform(-2.0, 3.9, 40), rng.uniform(-1.0, 1.0, 40)])
    z = terrain.height(stance)
    angle = rng.uniform(-0.5, 0.5, 40)
    direction = np.column_stack([np.cos(angle), np.sin(angle)])
    runs = []
    for threads in (None, W.RowThreads(3)):
        fp = _planner(terrain, area)
        runs.append(fp.plan(stance, z, direction=direction, leg=np.zeros(40, int),
                            speed=np.full(40, 1.3), planner=np.full(40, "best_first"),
                            trailing=np.full(40, -0.4), threads=threads))
        assert len(fp._cache) > 1  # the walkers' grounds differ
    one, split = runs
    for name in ("ok", "step_length", "step_height", "swing", "energy", "from_cache"):
        np.testing.assert_array_equal(getattr(one, name), getattr(split, name))


def test_plans_stored_as_whole_arrays_equal_the_plans_stored_one_by_one():
    from crowdwalk.crowd.footsteps import _PlanStore, _steps_of
    from planners import plan_batch

    grounds = [GroundProfile.flat(6.0, 0.0, -1.0),
               GroundProfile.stairs(0.17, 0.3, 4, first_edge=0.8),
               GroundProfile(np.array([-1.0, 0.5, 0.5, 3.0]), np.array([0.0, 0.0, 0.12, 0.12])),
               GroundProfile(np.array([-1.0, 0.4, 0.4, 9.0]), np.array([0.0, 0.0, 2.0, 2.0]))]
    legs = [LEGS[0], LEGS[1], LEGS[0], LEGS[1]]
    for config in (CONFIG, PlannerConfig(n_steps=2, min_step_ratio=0.15)):
        plans = plan_batch(grounds * 30, legs * 30, [1.3, 1.1, 1.4, 1.2] * 30,
                           planner="best_first", config=config, trailing=[-0.6] * 120)
        assert not all(p.ok for p in plans)  # the 2 m wall
        one, many = _PlanStore(3), _PlanStore(3)
        many.add_plans(plans[:5])
        rows = [one.add(_steps_of(p, 3)) for p in plans[:5] + plans]
        assert many.add_plans(plans).tolist() == rows[5:]
        assert one.size == many.size == 125
        for a, b in zip(one.take(np.arange(125)), many.take(np.arange(125)), strict=True):
            assert a.tobytes() == b.tobytes()
