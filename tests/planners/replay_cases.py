"""The planner replay cases: profiles, walkers and explicit configurations.

Shared by ``make_replay.py`` (which stored ``data/replay.json`` once, from the planners
as they were before the search was split into ``best_first`` and
``best_first_multistart``) and ``test_replay.py`` (which replays it). Every field of
both configurations is spelled out, so a later change of a default cannot change what
is replayed.
"""

from __future__ import annotations

import numpy as np

from planners import EnergyWeights, GroundProfile, Leg, PlannerConfig

#: Every PlannerConfig field in force when the fixture was stored (radians as numbers).
_BASE = dict(n_steps=4, intervals=13, min_step_ratio=0.30, max_step_ratio=1.05,
             clearance=0.02, edge_margin=0.0, support_tolerance=0.02, max_step_rise=0.25,
             max_foot_slope=0.5, swing_lift=0.15, max_swing_lift=0.60, bezier_samples=20,
             max_adjustments=10, knee_max_flexion=2.2689280275926285,
             pelvis_height_ratio=0.96, turn_threshold=0.7853981633974483,
             search_starts=8, snap=True, terminal_cost=True, step_model="paper")
_WEIGHTS = dict(alpha=4.184, beta=0.0549, gamma=1.0, c_thigh=1.0, c_calf=0.1,
                down_ratio=1.0 / 3.0, vertical="linear")


def configs() -> dict[str, PlannerConfig]:
    """The default planner configuration and the crowd's (n = 3, shorter steps)."""
    weights = EnergyWeights(**_WEIGHTS)
    return {"default": PlannerConfig(**_BASE, weights=weights),
            "crowd": PlannerConfig(**{**_BASE, "n_steps": 3, "min_step_ratio": 0.15},
                                   weights=weights)}


def _random_profile(rng: np.random.Generator) -> GroundProfile:
    """Flat runs, stair flights, low blocks and ramps [m].

    A frozen copy of ``benchmarks/bench_planners.random_terrain`` (grades rounded to
    1e-4): the stored plans must not change when the benchmark's generator does.
    """
    s, z = [-2.0], [0.0]
    x = rng.uniform(0.25, 0.8)
    while x < 5.0:
        kind = rng.integers(4)
        h = z[-1]
        s.append(x)
        z.append(h)
        if kind == 0:
            x += rng.uniform(0.5, 1.5)
        elif kind == 1:
            rise = rng.choice([-1, 1]) * rng.uniform(0.12, 0.19)
            tread = rng.uniform(0.28, 0.35)
            for _ in range(rng.integers(2, 5)):
                s += [x]
                z += [z[-1] + rise]
                x += tread
                s += [x]
                z += [z[-1]]
        elif kind == 2:
            height, depth = rng.uniform(0.05, 0.2), rng.uniform(0.1, 0.4)
            s += [x, x + depth, x + depth]
            z += [h + height, h + height, h]
            x += depth + rng.uniform(0.3, 1.0)
        else:
            length, grade = rng.uniform(0.5, 2.0), round(rng.uniform(-0.15, 0.15), 4)
            x += length
            s.append(x)
            z.append(h + grade * length)
    s.append(12.0)
    z.append(z[-1])
    return GroundProfile(np.array(s), np.array(z))


def profiles() -> dict[str, GroundProfile]:
    """Named profiles: the standard grounds, the Fig. 11 block, a wall, random terrain."""
    named = {
        "flat": GroundProfile.flat(20.0),
        "stairs up": GroundProfile.stairs(0.17, 0.30, 8, first_edge=0.4),
        "stairs down": GroundProfile.stairs(-0.17, 0.30, 8, first_edge=0.4),
        "stairs up far": GroundProfile.stairs(0.17, 0.30, 6, first_edge=1.3),
        "curb": GroundProfile([-2, 0.9, 0.9, 20], [0, 0, 0.15, 0.15]),
        "fig 11 block": GroundProfile([-2, 1.15, 1.15, 1.5, 1.5, 8], [0, 0, 0.1, 0.1, 0, 0]),
        "low block": GroundProfile([-2, 1.2, 1.2, 1.5, 1.5, 20], [0, 0, 0.1, 0.1, 0, 0]),
        "ramp up 8 %": GroundProfile([-2, 0.5, 5.5, 20], [0, 0, 0.4, 0.4]),
        "ramp down 10 %": GroundProfile([-2, 0.3, 8.0], [0, 0, -0.77]),
        "wall": GroundProfile([-2, 1.0, 1.0, 5], [0, 0, 0.6, 0.6]),
    }
    rng = np.random.default_rng(15)
    for i in range(14):
        named[f"random {i}"] = _random_profile(rng)
    return named


def walkers(count: int) -> tuple[list[Leg], np.ndarray, np.ndarray]:
    """Legs, speeds [m/s] and trailing feet [m] (every third one the default) for
    ``count`` walkers."""
    rng = np.random.default_rng(1501)
    heights = rng.uniform(1.5, 1.95, count).round(3)
    speeds = rng.uniform(0.9, 1.7, count).round(3)
    trailing = -rng.uniform(0.3, 0.8, count).round(3)
    return [Leg.from_body_height(float(h)) for h in heights], speeds, trailing
