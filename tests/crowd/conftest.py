"""Shared, session-cached runs of the small scenarios (each simulated once)."""

from pathlib import Path

import pytest

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.record import open_run

SCENARIOS = Path(__file__).parents[2] / "scenarios"


@pytest.fixture(scope="session")
def run_of(tmp_path_factory):
    """``run_of(name, **overrides) -> (summary, Run)``, each combination run once."""
    cache = {}

    def get(name: str, **kw):
        kw.setdefault("poses", False)  # poses are the gait's business; keep these fast
        key = (name, tuple(sorted(kw.items())))
        if key not in cache:
            out = tmp_path_factory.mktemp(name)
            summary = run_scenario(SCENARIOS / f"{name}.yaml", out,
                                   overrides=RunOverrides(**kw))
            cache[key] = (summary, open_run(out))
        return cache[key]

    return get
