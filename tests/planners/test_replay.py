"""Replay the stored plans (``data/replay.json``): every planner gives the same footholds
(to 1e-9 m), statuses and energies as when the fixture was stored."""

import json
from pathlib import Path

import numpy as np
import pytest
from replay_cases import configs, profiles, walkers

from planners import plan_batch

FIXTURE = json.loads((Path(__file__).parent / "data" / "replay.json").read_text())


@pytest.mark.parametrize("key", sorted(FIXTURE["plans"]))
def test_replay_gives_the_stored_plans(key):
    cname, planner = key.split("/")  # stored under the name that must reproduce it
    grounds = profiles()
    assert list(grounds) == FIXTURE["profiles"]
    legs, speeds, trailing = walkers(len(grounds))
    got = []
    for tr in (trailing, None):
        got += plan_batch(list(grounds.values()), legs, speeds, planner,
                          configs()[cname], trailing=tr)
    for i, (p, want) in enumerate(zip(got, FIXTURE["plans"][key], strict=True)):
        where = f"{key} {FIXTURE['profiles'][i % len(grounds)]} #{i}"
        assert p.status == want["status"], where
        assert p.footholds_s.size == len(want["footholds_s"]), where
        assert np.allclose(p.footholds_s, want["footholds_s"], rtol=0, atol=1e-9), where
        assert np.allclose(p.footholds_z, want["footholds_z"], rtol=0, atol=1e-9), where
        assert np.allclose(p.E, want["E"], rtol=1e-9, atol=1e-12), where
