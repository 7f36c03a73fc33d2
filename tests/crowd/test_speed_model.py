"""The speed model: lone walkers at their free speed; the time-gap model (Tordeux et al.
2016) at density, calibrated on the SFPE handbook's corridor speeds and validated here on
Weidmann's (1993) fundamental diagram."""

from dataclasses import replace

import numpy as np
import pytest

from crowdwalk.crowd.params import crowd_model
from crowdwalk.crowd.speed import contact_gap_speed, headway_speed, time_gap_speed
from crowdwalk.verify import free_speed, ring_corridor_speed, weidmann_speed


def test_time_gap_speed_from_the_nearest_walker_ahead():
    me = np.zeros((4, 2))
    ahead = np.array([[1.0, 0.0]] * 4)
    others = np.array([[[1.2, 0.0], [0.8, 0.5]],    # 1.2 m ahead; 0.8 m off the line
                       [[1.2, 0.3], [-0.5, 0.0]],   # 0.3 m off the line; one behind
                       [[-0.5, 0.0], [0.5, 0.0]],   # behind; 0.5 m ahead but not valid
                       [[0.3, 0.0], [3.0, 0.0]]])   # closer than two radii: 0
    valid = np.array([[True, True], [True, True], [True, False], [True, True]])
    v = time_gap_speed(position=me, direction=ahead, radius=np.full(4, 0.18),
                       others=others, others_radius=np.full((4, 2), 0.18), valid=valid,
                       free_speed=np.full(4, 1.34), time_gap=0.8)
    gap = np.hypot(1.2, 0.3) - 0.36
    np.testing.assert_allclose(v, [(1.2 - 0.36) / 0.8, min(1.34, gap / 0.8), 1.34, 0.0])


def test_lone_walkers_reach_their_free_speed(tmp_path):
    (check,) = free_speed(True, tmp_path)  # 6 walkers, 5 s apart, measured on 10 m
    assert check.passed, check.figure


def test_time_gap_model_follows_weidmann_at_1_5_per_m2(tmp_path):
    params = replace(crowd_model("free"), speed_model="time_gap")  # without S175's switches
    density, speed = ring_corridor_speed(1.5, tmp_path, params=params)
    assert 1.0 < density < 2.2
    assert speed == pytest.approx(float(weidmann_speed(density)), abs=0.15)


def test_contact_gap_speed_counts_the_distance_to_first_contact():
    me = np.zeros((3, 2))
    ahead = np.array([[1.0, 0.0]] * 3)
    others = np.array([[[1.2, 0.0]],     # straight ahead: Tordeux's s − ℓ
                       [[0.5, 0.3]],     # beside-ahead, 0.3 m off the line
                       [[0.5, 0.4]]])    # 0.4 m off the line: never touched
    v = contact_gap_speed(position=me, direction=ahead, radius=np.full(3, 0.18),
                          others=others, others_radius=np.full((3, 1), 0.18),
                          valid=np.ones((3, 1), bool), free_speed=np.full(3, 1.34),
                          time_gap=0.8)
    contact = 0.5 - np.sqrt(0.36**2 - 0.3**2)
    np.testing.assert_allclose(v, [(1.2 - 0.36) / 0.8, contact / 0.8, 1.34])
    # candidate directions (k, C, 2): turning away from the one ahead frees the way
    fan = np.array([[[1.0, 0.0], [0.0, 1.0]]] * 3)
    vc = contact_gap_speed(position=me, direction=fan, radius=np.full(3, 0.18),
                           others=others, others_radius=np.full((3, 1), 0.18),
                           valid=np.ones((3, 1), bool), free_speed=np.full(3, 1.34),
                           time_gap=0.8)
    assert vc.shape == (3, 2)
    np.testing.assert_allclose(vc[:, 0], v)
    assert vc[0, 1] == 1.34


def test_headway_speed_follows_only_the_walker_in_its_lane():
    # Seyfried et al. 2005: v = (s - a) / b, a = r_i + r_j, b = 1.06 s
    me = np.zeros((4, 2))
    ahead = np.array([[1.0, 0.0]] * 4)
    others = np.array([[[1.2, 0.0]],     # in line, 1.2 m ahead
                       [[0.6, 0.1]],     # 0.1 m off the line: within the lane
                       [[0.5, 0.25]],    # 0.25 m off: the next lane of a zipper
                       [[-0.5, 0.0]]])   # behind
    v = headway_speed(position=me, direction=ahead, radius=np.full(4, 0.18),
                      others=others, others_radius=np.full((4, 1), 0.18),
                      valid=np.ones((4, 1), bool), free_speed=np.full(4, 1.34),
                      time_gap=1.06, lane=np.full(4, 0.18))
    np.testing.assert_allclose(v, [(1.2 - 0.36) / 1.06, (0.6 - 0.36) / 1.06, 1.34, 1.34])


def test_headway_model_follows_weidmann_at_2_per_m2(tmp_path):
    # a and b come from Seyfried et al.'s single-file data; Weidmann is validation
    params = replace(crowd_model("free"), speed_model="headway")
    density, speed = ring_corridor_speed(2.0, tmp_path, params=params)
    assert 1.4 < density < 2.6
    assert speed == pytest.approx(float(weidmann_speed(density)), abs=0.15)


def test_verify_names_an_unknown_speed_model_in_one_line(tmp_path):
    from typer.testing import CliRunner

    from crowdwalk.cli import app

    result = CliRunner().invoke(app, ["verify", "--speed-model", "fast", "--only", "rimea1",
                                      "--out", str(tmp_path / "v.md")])
    assert result.exit_code == 2
    assert ("speed_model must be one of free, time_gap, contact_gap, headway; got 'fast'"
            in result.output)
    assert not (tmp_path / "v.md").exists()


def test_time_gap_speed_scores_candidate_directions_one_by_one():
    """(k, C, 2) directions (overtaking scores candidates) give what each direction gives
    alone: a neighbour 1.2 m ahead limits the straight step, not the one at 60°."""
    me, others = np.zeros((2, 2)), np.array([[[1.2, 0.0], [0.0, 1.0]], [[0.9, 0.1], [3.0, 0.0]]])
    a = np.deg2rad([0.0, 60.0, 90.0])
    dirs = np.broadcast_to(np.stack([np.cos(a), np.sin(a)], -1), (2, 3, 2))
    kw = dict(position=me, radius=np.full(2, 0.18), others=others,
              others_radius=np.full((2, 2), 0.18), valid=np.ones((2, 2), bool),
              free_speed=np.full(2, 1.34), time_gap=0.8)
    v = time_gap_speed(direction=dirs, **kw)
    assert v.shape == (2, 3)
    for c in range(3):
        np.testing.assert_array_equal(v[:, c], time_gap_speed(direction=dirs[:, c], **kw))
    assert v[0, 0] < 1.34 and v[0, 1] == 1.34


def test_the_headway_preset_runs_with_the_time_gap_speed_model(tmp_path):
    """``--crowd-model headway_s175 --speed-model time_gap``: S175's overtaking scores
    candidate directions with Tordeux's speed (it raised before)."""
    from crowdwalk.crowd.params import crowd_model

    params = crowd_model("headway_s175", {"speed_model": "time_gap"})
    density, speed = ring_corridor_speed(1.5, tmp_path, params=params)
    assert 1.0 < density < 2.2 and 0.0 < speed < 1.6
