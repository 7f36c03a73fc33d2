"""``plan_batch(diagnose=...)``: a failed plan not diagnosed skips the evaluation of its
agent's whole table and has no steps; every other plan of the batch, counters included,
is the plan the default (diagnose all) gives."""

import numpy as np
import pytest

from planners import PLANNERS, GroundProfile, Leg, plan_batch
from planners.plan import NO_FOOTHOLD, NOT_DIAGNOSED
from tests.planners.test_parallel_batch import _FIELDS, _batch


def _walls_batch():
    """The mixed batch of random terrain with two walls (1 m high, 1.0 and 1.3 m ahead)
    inserted and a box behind the stance foot at the end: several failed plans."""
    profiles, legs, speeds, trailing = _batch()
    for at, ahead in ((3, 1.0), (8, 1.3)):
        profiles.insert(at, GroundProfile(np.array([-1.0, ahead, ahead, 4.0]),
                                          np.array([0.0, 0.0, 1.0, 1.0])))
        legs.insert(at, legs[at])
        speeds, trailing = np.insert(speeds, at, 1.3), np.insert(trailing, at, -0.6)
    # and a 0.3 m box the first swing from 0.9 m behind cannot clear (steps stay legal)
    profiles.append(GroundProfile(np.array([-2.0, -0.5, -0.5, -0.2, -0.2, 4.0]),
                                  np.array([0.0, 0.0, 0.3, 0.3, 0.0, 0.0])))
    legs.append(Leg.from_body_height(1.75))
    return profiles, legs, np.append(speeds, 1.3), np.append(trailing, -0.9)


_WORK = ("lattice_steps", "key_frame_solves", "swing_curves", "swing_adjustments")


@pytest.mark.parametrize("planner", sorted(PLANNERS))
def test_undiagnosed_failures_leave_the_other_plans_alone(planner):
    profiles, legs, speeds, trailing = _walls_batch()
    full = plan_batch(profiles, legs, speeds, planner, trailing=trailing)
    failed = np.flatnonzero([not p.ok for p in full])
    diagnose = np.ones(len(full), bool)
    diagnose[failed[1:]] = False  # all but the first failed agent (a wall)
    part = plan_batch(profiles, legs, speeds, planner, trailing=trailing, diagnose=diagnose)
    stats = [k for k in full[0].stats if k != "time_s"]
    skipped = [a for a, p in enumerate(full) if not p.ok and not diagnose[a]]
    assert skipped and any(not p.ok and diagnose[a] for a, p in enumerate(full)), "mixed"
    for a, (p, q) in enumerate(zip(full, part, strict=True)):
        if a in skipped:
            assert (q.status, q.message) == (NO_FOOTHOLD, NOT_DIAGNOSED)
            assert p.message != NOT_DIAGNOSED and q.step_lengths.size == 0
            assert q.footholds_s.tobytes() == p.footholds_s[:1].tobytes()
            # the same search, less table: no counter of table work grows
            assert all(q.stats[k] <= p.stats[k] for k in _WORK)
            continue
        assert (p.status, p.message) == (q.status, q.message)
        for field in _FIELDS:
            assert getattr(p, field).tobytes() == getattr(q, field).tobytes(), field
        assert [p.stats[k] for k in stats] == [q.stats[k] for k in stats]
    if planner == "best_first":  # (lazy: the box's table is not completed)
        saved = sum(full[a].stats[k] - part[a].stats[k] for a in skipped for k in _WORK)
        assert saved > 0

def test_diagnose_false_everywhere_keeps_ok_plans():
    profiles, legs, speeds, trailing = _walls_batch()
    full = plan_batch(profiles, legs, speeds, "best_first_multistart", trailing=trailing)
    none = plan_batch(profiles, legs, speeds, "best_first_multistart", trailing=trailing,
                      diagnose=False)
    for p, q in zip(full, none, strict=True):
        assert p.ok == q.ok
        assert q.ok or q.message == NOT_DIAGNOSED
        if p.ok:
            assert p.E.tobytes() == q.E.tobytes()
