"""A second BVH library (pybvh) reads `crowdwalk export-bvh` output without hints: it
infers the up axis and the feet, and its foot contacts agree with crowdwalk's stance."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.export_bvh import export_bvh
from crowdwalk.record import open_run

pybvh = pytest.importorskip("pybvh")
from pybvh import analysis  # noqa: E402

SCENARIO = Path(__file__).parents[1] / "scenarios" / "lone_walker.yaml"


@pytest.fixture(scope="module")
def walker(tmp_path_factory):
    out = tmp_path_factory.mktemp("lone")
    run_scenario(SCENARIO, out, overrides=RunOverrides(duration=6.0))
    return out


def test_pybvh_infers_up_axis_and_feet(walker, tmp_path):
    path = export_bvh(walker, 0, tmp_path / "w.bvh")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "ambiguous up axis" or "no feet" warnings
        bvh = pybvh.read_bvh_file(path)
        assert bvh.world_up == "+y"
        assert analysis.auto_detect_foot_joints(bvh) == ["LeftToeBase", "RightToeBase"]
        planted = analysis.foot_contacts(bvh).astype(bool)  # (F, 2): left, right
    poses = open_run(walker).poses()
    stance = poses.agent_track(0)["contact"].astype(bool)  # crowdwalk's own (F, 2)
    poses.close()
    assert planted.shape == stance.shape
    assert (planted == stance).mean() > 0.7
    # where pybvh sees a planted foot, crowdwalk has that foot in stance
    assert (stance[planted]).mean() > 0.9
    # and the H-Anim names are what a library cannot guess from
    hanim = pybvh.read_bvh_file(export_bvh(walker, 0, tmp_path / "h.bvh", naming="hanim"))
    assert analysis.auto_detect_foot_joints(hanim) == []
