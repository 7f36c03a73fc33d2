"""The viewer on the bundled scenario's run (``crowdwalk run scenarios/quickstart.yaml --out
runs/quickstart``, which CI does before the tests)."""

from pathlib import Path

import numpy as np
import pytest

from crowdwalk.viz.camera import project_to_pixels
from crowdwalk.viz.headless import offscreen_plotter
from crowdwalk.viz.scene import Scene

RUN = Path(__file__).parents[2] / "runs" / "quickstart"


@pytest.fixture(scope="module")
def quickstart():
    if not (RUN / "poses.sqlite").exists():
        pytest.skip("runs/quickstart not simulated yet (crowdwalk run scenarios/quickstart.yaml)")
    return Scene.from_run(RUN)


def test_every_agent_head_is_drawn_where_the_run_puts_it(offscreen, quickstart):
    from crowdwalk.record import open_run

    t = 0.5 * sum(quickstart.time_range)
    with offscreen_plotter((800, 500)) as plotter:
        view = quickstart.attach(plotter)
        view.set_time(t)
        plotter.render()
        image = plotter.screenshot(return_img=True).astype(int)
        poses = open_run(RUN).poses()
        record = poses.frame(poses.frames[np.searchsorted(poses.times, t + 1e-9) - 1])
        np.testing.assert_array_equal(view.agent_ids, record.ids)
        head = poses.names.index("skullbase")
        centres = record.positions[:, head] + [0.0, 0.0, view.figures.head_radius]
        px = np.round(project_to_pixels(plotter, centres)).astype(int)
        h, w = image.shape[:2]
        inside = (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0) & (px[:, 1] < h)
        assert inside.sum() >= 0.9 * len(record.ids) > 0
        colours = image[px[inside, 1], px[inside, 0]]
        assert np.mean(colours.max(axis=1) < 110) >= 0.9  # the dark figures, not the ground
        # one metre beside each head (at ground level) there is no figure
        beside = np.round(project_to_pixels(plotter, centres - [0.0, 1.0, 1.7])).astype(int)
        ok = (beside[:, 0] >= 0) & (beside[:, 0] < w) & (beside[:, 1] >= 0) & (beside[:, 1] < h)
        colours = image[beside[ok, 1], beside[ok, 0]]
        assert np.mean(colours.max(axis=1) < 110) < 0.5
