"""The viewer shows the walkable area current at the time shown: a door shut by a timed
event (scenarios/events.yaml) is a wall after it shuts, and open ground before."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from crowdwalk.crowd.run import RunOverrides, run_scenario
from crowdwalk.record import open_run
from crowdwalk.viz.camera import project_to_pixels
from crowdwalk.viz.headless import offscreen_plotter
from crowdwalk.viz.scene import Scene

EVENTS = Path(__file__).parents[2] / "scenarios" / "events.yaml"
DOOR = (14.75, 4.0)  # the east corridor's door (halfway from x = 12 to 17.5), 1.2 m wide


@pytest.fixture(scope="module")
def events_run(tmp_path_factory):
    if not EVENTS.exists():
        pytest.skip("scenarios/events.yaml is not in this checkout")
    out = tmp_path_factory.mktemp("events")
    summary = run_scenario(EVENTS, out, overrides=RunOverrides(duration=6.5, poses=False))
    return out, summary["events"][0]["time_s"]


def test_run_records_when_the_walkable_area_changed(events_run):
    run, shut = events_run
    areas = open_run(run).walkable_areas()
    assert len(areas.areas) == 2
    # the first frame after the door shut carries the new area
    assert areas.start[0] == 0.0 and shut <= areas.start[1] <= shut + 0.1 + 1e-9
    closed = areas.areas[0].difference(areas.areas[1])
    assert closed.area == pytest.approx(0.3 * 1.2, rel=0.05)  # the door, 0.3 m thick
    assert closed.centroid.distance(shapely.Point(DOOR)) < 0.05


def _door_pixels(scene, t):
    """Colours (k, 3) of the pixels around the door at 0.6 m height, at time ``t``."""
    with offscreen_plotter((800, 500)) as plotter:
        view = scene.attach(plotter)
        view.set_time(t)
        plotter.render()
        image = plotter.screenshot(return_img=True)
        offsets = np.array([[dx, dy, 0.6] for dx in (-0.05, 0.0, 0.05)
                            for dy in (-0.3, 0.0, 0.3)])
        px = project_to_pixels(plotter, np.array([*DOOR, 0.0]) + offsets, view.renderer)
    c = np.round(px).astype(int)
    return image[c[:, 1], c[:, 0]].astype(int)


def _red(colours):
    return (colours[:, 0] > colours[:, 1] + 60) & (colours[:, 0] > colours[:, 2] + 60)


def test_door_is_a_wall_only_while_shut(offscreen, events_run):
    run, shut = events_run
    scene = Scene.load(run)
    before, after = _door_pixels(scene, shut - 1.0), _door_pixels(scene, shut + 1.0)
    assert not _red(before).any(), before
    assert _red(after).mean() >= 0.8, after
    # and back again: the view follows time both ways
    assert not _red(_door_pixels(scene, shut - 0.5)).any()
