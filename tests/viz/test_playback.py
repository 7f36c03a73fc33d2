"""Playback state behind the viewer's keys and timer."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.errors import InputError
from crowdwalk.viz.playback import Playback


@settings(max_examples=50, deadline=None)
@given(st.floats(0, 100), st.floats(0.1, 100), st.lists(st.floats(0, 5), max_size=20),
       st.booleans())
def test_time_never_leaves_the_run(start, length, ticks, loop):
    pb = Playback(start, start + length, frame_dt=0.04, loop=loop)
    pb.toggle()
    for dt in ticks:
        t = pb.advance(dt)
        assert start - 1e-9 <= t <= start + length + 1e-9


def test_play_pause_step_and_speed():
    pb = Playback(0.0, 10.0, frame_dt=0.1)
    assert pb.advance(1.0) == 0.0  # paused: the timer does not move time
    assert pb.toggle() is True
    assert pb.advance(0.5) == pytest.approx(0.5)
    assert pb.faster() == 2.0
    assert pb.advance(0.5) == pytest.approx(1.5)
    assert pb.step(1) == pytest.approx(1.6) and not pb.playing
    assert pb.step(-3) == pytest.approx(1.3)
    for _ in range(20):
        pb.faster()
    assert pb.speed == Playback.MAX_SPEED
    for _ in range(40):
        pb.slower()
    assert pb.speed == Playback.MIN_SPEED


def test_end_of_run_loops_or_pauses():
    looping = Playback(0.0, 2.0, frame_dt=0.1, time=1.5, loop=True)
    looping.toggle()
    assert looping.advance(1.0) == pytest.approx(0.5) and looping.playing
    once = Playback(0.0, 2.0, frame_dt=0.1, time=1.5, loop=False)
    once.toggle()
    assert once.advance(1.0) == 2.0 and not once.playing
    assert once.toggle() and once.time == 0.0  # playing from the end restarts


def test_invalid_ranges_are_rejected():
    with pytest.raises(InputError, match=r"Playback\.end must be >= start"):
        Playback(2.0, 1.0, frame_dt=0.1)
    with pytest.raises(InputError, match=r"Playback\.frame_dt must be > 0"):
        Playback(0.0, 1.0, frame_dt=0.0)
