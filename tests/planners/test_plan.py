"""Planner properties: optimality order, translation invariance, determinism, batches."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from planner_strategies import terrain_profiles

from planners import PLANNERS, GroundProfile, Leg, PlannerConfig, plan, plan_batch
from planners.lattice import build_tables
from planners.optimal import optimal
from planners.search import all_configs_evaluated


def test_flat_ground_gives_equal_neutral_steps(leg):
    p = plan(GroundProfile.flat(), leg, 1.34)
    assert p.ok and p.step_lengths.size == 4
    assert np.allclose(p.step_lengths, p.stats["neutral_step"])
    assert np.allclose(p.footholds_z, 0) and p.footholds_s[0] == 0
    assert p.efficiency == pytest.approx(p.distance / p.energy_total)
    assert p.phase_durations.sum(axis=1) == pytest.approx(p.step_lengths / 1.34)


def _to_reach(p):
    """Energy [J/kg] of a plan's steps plus the terminal estimate to the common reach."""
    return p.energy_total + p.stats["terminal_energy"]


@settings(max_examples=30, deadline=None)
@given(terrain_profiles())
def test_optimal_is_best_and_fixed_never_beats_it(leg, profile):
    # the searches' criterion: the least energy to the horizon's common reach
    plans = {name: plan(profile, leg, 1.34, name) for name in PLANNERS}
    best = plans["optimal"]
    for name, p in plans.items():
        if p.ok:
            assert best.ok, name
            assert p.stats["reach"] == best.stats["reach"]
            assert _to_reach(best) <= _to_reach(p) * (1 + 1e-12), name
    # the paper's criterion (Eq. 5 over the planned steps alone)
    paper = PlannerConfig(terminal_cost=False)
    plans = {name: plan(profile, leg, 1.34, name, paper) for name in PLANNERS}
    best = plans["optimal"]
    for name, p in plans.items():
        if p.ok:
            assert best.ok, name
            assert p.stats["terminal_energy"] == 0.0
            assert best.efficiency >= p.efficiency * (1 - 1e-12), name
            assert best.energy_per_metre <= p.energy_per_metre * (1 + 1e-12), name


@settings(max_examples=15, deadline=None)
@given(terrain_profiles())
def test_optimal_equals_exhaustive_enumeration(leg, profile):
    tables = build_tables([profile], [leg], np.array([1.34]), None, np.zeros(1),
                          PlannerConfig())
    legal, eff = all_configs_evaluated(tables, np.array([0]))
    result = optimal(tables)
    assert result.found[0] == legal.any()
    if legal.any():
        _, got = tables.evaluate(np.array([0]), result.configs)
        assert got[0] == pytest.approx(eff[0][legal[0]].max(), rel=1e-12)


@settings(max_examples=20, deadline=None)
@given(terrain_profiles(), st.floats(-3, 3), st.floats(-2, 2),
       st.sampled_from(sorted(PLANNERS)))
def test_translation_changes_only_offsets(leg, profile, ds, dz, planner):
    a = plan(profile, leg, 1.34, planner)
    b = plan(profile.shifted(ds, dz), leg, 1.34, planner, origin=ds)
    assert a.status == b.status
    assert np.allclose(b.footholds_s, a.footholds_s + ds, atol=1e-9)
    assert np.allclose(b.footholds_z, a.footholds_z + dz, atol=1e-9)
    assert np.allclose(b.E, a.E, rtol=1e-9, atol=1e-12)
    assert np.allclose(b.swing_controls, a.swing_controls + [ds, dz], atol=1e-9)


def test_plans_are_deterministic_and_batches_match_single_plans(leg):
    profiles = [GroundProfile.flat(), GroundProfile.stairs(0.17, 0.3, 5, first_edge=0.4),
                GroundProfile.stairs(-0.15, 0.32, 4, first_edge=0.7),
                GroundProfile([-2, 0, 3, 8], [0, 0, 0.3, 0.3])]
    legs = [leg, Leg.from_body_height(1.55), Leg.from_body_height(1.9), leg]
    speeds = [1.34, 1.0, 1.5, 1.2]
    for planner in sorted(PLANNERS):
        batch = plan_batch(profiles, legs, speeds, planner)
        again = plan_batch(profiles, legs, speeds, planner)
        for p, q, prof, lg, v in zip(batch, again, profiles, legs, speeds, strict=True):
            assert q.status == p.status  # the same call gives the same bits
            assert np.array_equal(q.footholds_s, p.footholds_s) and np.array_equal(q.E, p.E)
            single = plan(prof, lg, v, planner)  # batching only shifts s by an offset
            assert single.status == p.status
            assert np.allclose(single.footholds_s, p.footholds_s, atol=1e-9)
            assert np.allclose(single.E, p.E, rtol=1e-9)


def test_fig_11_multistart_walker_strides_over_a_low_block_the_fixed_one_steps_on(leg):
    block = GroundProfile([-2, 1.15, 1.15, 1.5, 1.5, 8], [0, 0, 0.1, 0.1, 0, 0])
    fixed = plan(block, leg, 1.34, "fixed")
    planned = plan(block, leg, 1.34, "best_first_multistart")
    assert fixed.ok and planned.ok
    assert np.any(fixed.footholds_z > 0.05)  # steps onto the block
    assert np.all(planned.footholds_z == 0)  # strides across
    assert planned.energy_per_metre < fixed.energy_per_metre


def test_trailing_foot_and_origin_are_honoured(leg):
    p = plan(GroundProfile.flat(), leg, 1.34, trailing=-0.4, origin=2.0)
    assert p.trailing_s == pytest.approx(1.6)
    assert p.swing_controls[0, 0, 0] == pytest.approx(1.6)
    assert p.footholds_s[0] == 2.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"speed": float("nan")}, "plan.speeds must be finite"),
        ({"speed": -1.0}, "plan.speed must be finite and in \\(0, 3\\] \\[m/s\\]; got -1.0"),
        ({"planner": "astar"}, "plan.planner must be one of"),
        ({"trailing": 0.3}, "plan.trailing must be in \\(-3, 0\\)"),
        ({"config": "fast"}, "plan.config must be a PlannerConfig"),
    ],
)
def test_bad_arguments_raise_value_errors(leg, kwargs, match):
    args = {"speed": 1.34, **kwargs}
    speed = args.pop("speed")
    with pytest.raises(ValueError, match=match):
        plan(GroundProfile.flat(), leg, speed, **args)


def test_negative_leg_lengths_are_rejected():
    with pytest.raises(ValueError, match="Leg.thigh must be finite and > 0 \\[m\\]; got -0.4"):
        Leg(-0.4, 0.4, 0.26, 0.06, 0.2)


def _better_neighbour(tables, config, deltas):
    """Whether a legal grid neighbour of ``config`` (n,) in ``deltas`` is more efficient."""
    row = np.array([0])
    _, eff = tables.evaluate(row, config[None])
    neighbours = config + deltas
    inside = ((neighbours >= 0) & (neighbours < tables.struct.J)).all(axis=1)
    legal, n_eff = tables.evaluate(row, np.clip(neighbours, 0, tables.struct.J - 1)[None])
    return bool(np.any(inside & legal[0] & (n_eff[0] > eff[0])))


@settings(max_examples=20, deadline=None)
@given(terrain_profiles())
def test_searches_end_in_local_optima_of_their_neighbourhoods(leg, profile):
    from planners.best_first import best_first
    from planners.multistart import best_first_multistart
    from planners.search import neighbour_deltas

    tables = build_tables([profile], [leg], np.array([1.34]), None, np.zeros(1),
                          PlannerConfig())
    paper = best_first(tables)
    single = best_first_multistart(tables, starts=1)
    multi = best_first_multistart(tables, starts=8)
    legal, _ = all_configs_evaluated(tables, np.array([0]))
    assert paper.found[0] == single.found[0] == multi.found[0] == legal.any()
    if not paper.found[0]:
        return
    n = tables.struct.n
    assert not _better_neighbour(tables, paper.configs[0], neighbour_deltas(n, shifts=False))
    assert not _better_neighbour(tables, single.configs[0], neighbour_deltas(n))
    row = np.array([0])
    _, (e1,) = tables.evaluate(row, single.configs)
    _, (e8,) = tables.evaluate(row, multi.configs)
    assert e8 >= e1


@settings(max_examples=20, deadline=None)
@given(terrain_profiles(), st.integers(1, 4))
def test_find_init_is_breadth_first_from_the_neutral_steps(leg, profile, n_steps):
    """FIND_INIT returns a legal configuration nearest (L1) to q_init, having expanded
    every configuration nearer than it and none farther."""
    from planners.best_first import find_init

    config = PlannerConfig(n_steps=n_steps)
    tables = build_tables([profile], [leg], np.array([1.34]), None, np.zeros(1), config)
    grid = tables.struct.all_configs.astype(int)
    legal, _ = all_configs_evaluated(tables, np.array([0]))
    dist = np.abs(grid - tables.neutral[0]).sum(axis=1)
    result = find_init(tables)
    assert result.found[0] == legal.any()
    if not legal.any():
        assert result.checks[0] == result.expanded[0] == grid.shape[0]
        return
    d = dist[legal[0]].min()
    code = result.configs[0] @ (tables.struct.J ** np.arange(n_steps - 1, -1, -1))
    assert legal[0, code] and dist[code] == d
    assert result.checks[0] == result.expanded[0] + 1
    assert (dist < d).sum() <= result.expanded[0] < (dist <= d).sum()


def test_batches_larger_than_a_chunk(leg):
    profiles = [GroundProfile.flat(), GroundProfile.stairs(0.17, 0.3, 4, first_edge=0.5)] * 35
    plans = plan_batch(profiles, leg, 1.34, "fixed")
    assert len(plans) == 70 and all(p.ok for p in plans)
    assert np.allclose(plans[-1].footholds_s, plans[1].footholds_s)


@settings(max_examples=10, deadline=None)
@given(terrain_profiles())
def test_pruning_does_not_change_the_optimum(leg, profile):
    import planners.lattice as lattice

    deferred, lattice.DEFER_STEPS = lattice.DEFER_STEPS, frozenset()  # every step read
    try:
        pruned = plan(profile, leg, 1.34, "optimal")
        lattice.PRUNE = False
        full = plan(profile, leg, 1.34, "optimal")
    finally:
        lattice.PRUNE = True
        lattice.DEFER_STEPS = deferred
    assert pruned.status == full.status
    assert _to_reach(pruned) == pytest.approx(_to_reach(full), rel=1e-12)
    assert pruned.stats["swing_curves"] <= full.stats["swing_curves"]
    assert pruned.stats["key_frame_solves"] <= full.stats["key_frame_solves"]
    assert pruned.stats["lattice_steps"] <= full.stats["lattice_steps"] == 1148


def _walk(profile, leg, planner, config, distance):
    """A lone walker on a profile with a receding horizon: plan, take the first step,
    plan again. Returns the energy [J/kg] to ``distance`` (the last step pro rata) and
    the step lengths [m]."""
    s, trailing, energy, lengths = 0.0, None, 0.0, []
    while s < distance:
        p = plan(profile, leg, 1.34, planner, config, trailing=trailing, origin=s)
        assert p.ok, p.message
        step, e = float(p.step_lengths[0]), float(p.E[0])
        energy += e * min(1.0, (distance - s) / step)
        lengths.append(step)
        trailing, s = -step, s + step
    return energy, np.array(lengths)


_GROUNDS = {
    "flat": GroundProfile.flat(20.0),
    "stairs up": GroundProfile.stairs(0.17, 0.30, 6, first_edge=3.0),
    "stairs down": GroundProfile.stairs(-0.17, 0.30, 6, first_edge=3.0),
    "curb": GroundProfile([-2, 2.9, 2.9, 20], [0, 0, 0.15, 0.15]),
    "low block": GroundProfile([-2, 3.2, 3.2, 3.5, 3.5, 20], [0, 0, 0.1, 0.1, 0, 0]),
    "ramp": GroundProfile([-2, 2.0, 7.0, 20], [0, 0, 0.4, 0.4]),  # 8 % up
}
_CROWD = PlannerConfig(n_steps=3, min_step_ratio=0.15)  # crowdwalk.crowd's planner config


@pytest.mark.parametrize("ground", sorted(_GROUNDS))
def test_multistart_lone_walker_never_spends_more_than_the_fixed_one(leg, ground):
    """Walked step by step over the same ground to the same point, the planned walker's
    summed energy is at most the unplanned one's (equal on level ground)."""
    profile = _GROUNDS[ground]
    planned, steps = _walk(profile, leg, "best_first_multistart", _CROWD, 6.0)
    fixed, _ = _walk(profile, leg, "fixed", _CROWD, 6.0)
    assert planned <= fixed * (1 + 1e-9)
    if ground == "flat":
        assert planned == pytest.approx(fixed, rel=1e-12)
    assert steps.min() > 0.25  # no shuffling in front of a flight or a curb


def test_without_the_terminal_cost_the_planner_shuffles_before_a_flight(leg):
    """Chen & Li's Eq. 5 over the planned steps alone: leaving the flight beyond the
    horizon looks efficient, so the walker shortens its steps before it and spends more
    than the unplanned walker (why PlannerConfig.terminal_cost exists)."""
    from dataclasses import replace

    paper = replace(_CROWD, terminal_cost=False, step_model="paper")
    profile = _GROUNDS["stairs up"]
    planned, steps = _walk(profile, leg, "best_first_multistart", paper, 6.0)
    fixed, _ = _walk(profile, leg, "fixed", paper, 6.0)
    assert steps.min() < 0.2
    assert planned > fixed


def test_plan_batch_splits_the_path_turn_over_the_steps_inside_foot_first(leg):
    """§5.4 in the plans: a 180 deg left turn is four 45 deg rotations; turning right with
    the left foot next, the left foot steps straight and the right one turns first."""
    flat = [GroundProfile.flat()] * 3
    left, right, straight = plan_batch(flat, leg, 1.34, heading_change=[np.pi, -0.6, 0.0],
                                       first_foot=["left", "left", "right"])
    assert np.degrees(left.foot_rotations) == pytest.approx([45, 45, 45, 45])
    assert left.feet == ("left", "right", "left", "right")
    assert np.degrees(right.foot_rotations) == pytest.approx([0, -34.377468, 0, 0])
    assert straight.feet[0] == "right" and not straight.foot_rotations.any()
    assert plan(flat[0], leg, 1.34).foot_rotations.tolist() == [0.0] * 4
