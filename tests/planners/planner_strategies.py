"""Hypothesis strategies for the planner tests."""

import numpy as np
from hypothesis import strategies as st

from planners import GroundProfile


@st.composite
def terrain_profiles(draw):
    """Random walkable terrain: flat runs, stair flights, low blocks and ramps [m]."""
    s, z = [-2.0], [0.0]
    x = draw(st.floats(0.25, 0.8))  # the stance foot (ankle at s = 0) stands on flat ground
    while x < 5.0:
        kind = draw(st.integers(0, 3))
        h = z[-1]
        s.append(x)
        z.append(h)
        if kind == 0:
            x += draw(st.floats(0.5, 1.5))
        elif kind == 1:
            rise = draw(st.sampled_from([-1, 1])) * draw(st.floats(0.12, 0.19))
            tread = draw(st.floats(0.28, 0.35))
            for _ in range(draw(st.integers(2, 4))):
                s.append(x)
                z.append(z[-1] + rise)
                x += tread
                s.append(x)
                z.append(z[-1])
        elif kind == 2:
            height, depth = draw(st.floats(0.05, 0.2)), draw(st.floats(0.1, 0.4))
            s += [x, x + depth, x + depth]
            z += [h + height, h + height, h]
            x += depth + draw(st.floats(0.3, 1.0))
        else:
            # grades to 0.01 %: a grade of 1e-128 is flat ground in every practical sense, but
            # translating it by dz rounds it to exactly flat and flips slope-dependent choices
            length = draw(st.floats(0.5, 2.0))
            grade = draw(st.floats(-0.15, 0.15).map(lambda g: round(g, 4)))
            x += length
            s.append(x)
            z.append(h + grade * length)
    s.append(12.0)
    z.append(z[-1])
    return GroundProfile(np.array(s), np.array(z))
