"""crowdwalk gait-compare: the lone-walker scenarios it runs are valid scenarios."""

from __future__ import annotations

import pytest

from crowdwalk.gait_compare import SPEEDS, lone_walker_yaml
from crowdwalk.scenario import load_scenario


@pytest.mark.parametrize("gait", ["elevation_angles", "klaw", "ko_badler"])
def test_lone_walker_scenarios_load(tmp_path, gait):
    for speed in SPEEDS:
        path = tmp_path / f"{gait}_{speed}.yaml"
        path.write_text(lone_walker_yaml(speed=speed, gait=gait), encoding="utf-8")
        sc = load_scenario(path)
        (group,) = sc.groups
        assert group.gait == gait and group.free_speed.mean == speed
        assert sc.outputs.poses
