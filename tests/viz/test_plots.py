"""Report plots of the viewer part (crowdwalk.plots, issue 6)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk import plots
from crowdwalk.errors import InputError


def _png_has_content(path):
    import matplotlib.image as mpimg

    image = mpimg.imread(path)
    assert image.shape[0] > 100 and image.shape[1] > 100
    assert image[..., :3].std() > 0.05


@settings(max_examples=40, deadline=None)
@given(st.floats(0.3, 1.1), st.floats(0.1, 5.0))
def test_best_step_length_is_the_peak_of_each_curve(peak, width):
    x = np.linspace(0.2, 1.2, 501)
    eff = np.stack([1.0 - (x - peak) ** 2 / width, 0.5 - (x - 0.7) ** 2])
    best = plots.best_step_length(x, eff)
    assert best[0] == pytest.approx(peak, abs=0.002)
    assert best[1] == pytest.approx(0.7, abs=0.002)


def test_efficiency_curve_png(tmp_path):
    x = np.linspace(0.3, 1.0, 30)
    eff = np.stack([x / (20 + 30 * (x - 0.6) ** 2), x / (22 + 25 * (x - 0.7) ** 2)])
    out = plots.plot_efficiency_curve(x, eff, tmp_path / "eff.png", labels=["1.0 m/s", "1.4 m/s"])
    _png_has_content(out)
    with pytest.raises(InputError, match=r"plot_efficiency_curve\.labels must be 2 labels"):
        plots.plot_efficiency_curve(x, eff, tmp_path / "x.png", labels=["one"])
    with pytest.raises(InputError, match=r"plot_efficiency_curve\.efficiency must be shaped"):
        plots.plot_efficiency_curve(x, eff[:, :-1], tmp_path / "x.png")


def test_planner_comparison_png(tmp_path):
    rng = np.random.default_rng(0)
    metrics = {
        "energy per metre": {"best_first": rng.normal(3, 0.2, 40),
                             "fixed": rng.normal(3.4, 0.3, 40)},
        "travel time": {"best_first": rng.normal(20, 1, 40), "fixed": rng.normal(21, 1, 40)},
    }
    out = plots.plot_planner_comparison(metrics, tmp_path / "cmp.png",
                                        units={"energy per metre": "J/(kg m)", "travel time": "s"})
    _png_has_content(out)
    with pytest.raises(InputError, match=r"plot_planner_comparison\.travel time must be finite"):
        plots.plot_planner_comparison({"travel time": {"fixed": [np.nan]}}, tmp_path / "x.png")
    with pytest.raises(InputError, match=r"plot_planner_comparison\.metrics must be a non-empty"):
        plots.plot_planner_comparison({}, tmp_path / "x.png")


def test_gait_curves_png(tmp_path):
    t = np.linspace(0, 1, 101, endpoint=False)
    thigh = 0.35 * np.cos(2 * np.pi * t)
    shank = 0.5 * np.cos(2 * np.pi * t - 0.6)
    out = plots.plot_gait_curves(
        t, {"thigh": thigh, "shank": np.stack([shank, shank * 1.1])},
        {"thigh": (thigh, np.full_like(t, 0.05)), "shank": (shank, np.full_like(t, 0.06))},
        tmp_path / "gait.png",
    )
    _png_has_content(out)
    with pytest.raises(InputError, match=r"plot_gait_curves\.measured\['thigh'\] must be"):
        plots.plot_gait_curves(t, {"thigh": thigh}, {"thigh": (thigh[:50], thigh[:50])},
                               tmp_path / "x.png")


def test_footstep_map_png(tmp_path):
    import shapely

    rng = np.random.default_rng(1)
    x, y = rng.uniform(0, 10, 200), rng.uniform(0, 5, 200)
    out = plots.plot_footstep_map(x, y, x + y, tmp_path / "map.png",
                                  walkable_area=shapely.box(0, 0, 10, 5))
    _png_has_content(out)
    with pytest.raises(InputError, match=r"plot_footstep_map\.x must be 1-D"):
        plots.plot_footstep_map(x, y[:5], x, tmp_path / "x.png")
