"""Body outlines broader than deep: three discs on the shoulder line; the in-time clearance
of turning, stepping outlines; a walker turns its shoulders to slip through a gap."""

from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from crowdwalk.crowd.params import CrowdParams
from crowdwalk.crowd.shape import BodyShape, body_gaps, clear_runs, disc_centres, shape_overlap
from crowdwalk.crowd.steering import SteeringParams
from crowdwalk.sinks import OverlapMonitor, RunInfo, Snapshot
from crowdwalk.verify import _run

SHAPE = BodyShape.from_axes(np.array([0.18]), np.array([0.2215]))


def _extent(shape: BodyShape, direction: np.ndarray) -> float:
    """Half the outline's extent along unit ``direction`` (body at 0 facing +x)."""
    c = disc_centres(np.zeros(2), np.array(0.0), shape.shoulder_offset[0])
    r = np.array([shape.radius[0], shape.shoulder_radius[0], shape.shoulder_radius[0]])
    return float((c @ direction + r).max())


def test_outline_is_as_broad_and_deep_as_its_axes():
    assert _extent(SHAPE, np.array([0.0, 1.0])) == np.float64(0.2215)  # shoulder width
    assert abs(_extent(SHAPE, np.array([1.0, 0.0])) - 0.18) < 1e-12  # depth
    # turned by 60 degrees it needs less width across the walking direction
    turned = np.array([np.sin(np.pi / 3), np.cos(np.pi / 3)])
    assert _extent(SHAPE, turned) < 0.19
    assert SHAPE.bound[0] == np.float64(0.2215)


def test_two_bodies_side_by_side_overlap_where_one_behind_the_other_does_not():
    sh = np.repeat(SHAPE.packed(), 2, axis=0)
    a, b = np.zeros((2, 2)), np.array([[0.0, 0.40], [0.40, 0.0]])  # beside, behind
    over = shape_overlap(a, np.zeros(2), sh, b, np.zeros(2), sh)
    assert over[0] > 0.04 and over[1] < 0.0
    # the overlap monitor sees the same (facing from the snapshot's orientation)
    mon = OverlapMonitor()
    mon.begin(RunInfo(fps=10.0, body_height=np.full(2, 1.71),
                      shape=BodyShape.from_axes(np.full(2, 0.18), np.full(2, 0.2215)),
                      group=np.array(["g", "g"]), planner=np.array(["fixed", "fixed"])))
    behind = Snapshot(frame=0, agents=np.arange(2), xy=np.array([[0.0, 0.0], [0.4, 0.0]]),
                      z=np.zeros(2), orientation=np.array([[1.0, 0.0], [1.0, 0.0]]))
    mon.frame(0.0, behind, None)
    assert mon.max_overlap == 0.0
    beside = Snapshot(frame=1, agents=np.arange(2), xy=np.array([[0.0, 0.0], [0.0, 0.4]]),
                      z=np.zeros(2), orientation=np.array([[1.0, 0.0], [1.0, 0.0]]))
    mon.frame(0.1, beside, None)
    assert mon.max_overlap > 0.04


coord = st.floats(-0.8, 0.8)
turn = st.floats(-1.6, 1.6)


@settings(max_examples=80, deadline=None)
@given(st.tuples(coord, coord), st.tuples(st.floats(-0.4, 0.4), st.floats(-0.4, 0.4)),
       st.floats(-3.0, 3.0), turn, st.floats(0.3, 0.7), st.floats(0.0, 0.3),
       st.tuples(coord, coord), st.tuples(st.floats(-0.4, 0.4), st.floats(-0.4, 0.4)),
       st.floats(-3.0, 3.0), turn, st.one_of(st.just(0.0), st.floats(0.05, 0.6)))
def test_a_clear_gap_is_a_lower_bound_of_the_clearance_at_every_instant(a0, da, ya, ta, dur, gone,
                                                                          b0, db, yb, tb,
                                                                          rem):
    a0, b0 = np.array([a0]), np.array([b0])
    a1 = a0[:, None, :] + np.array(da)
    b1 = b0 + np.array(db) if rem > 0 else b0
    yb1 = yb + tb if rem > 0 else yb
    gap = body_gaps(np.array([0]), a_start=a0, a_yaw0=np.array([ya]), a_end=a1,
                    a_yaw1=np.array([[ya + ta]]), a_duration=np.array([[dur]]),
                    a_elapsed=np.array([gone]), a_shape=SHAPE.packed(), b_now=b0,
                    b_yaw_now=np.array([yb]), b_end=b1, b_yaw_end=np.array([yb1]),
                    b_remaining=np.array([rem]), b_shape=SHAPE.packed())[0][0, 0]
    # both move linearly (the yaw too) from now on, then stand
    t = np.linspace(0.0, 1.2, 2401)
    fa = np.clip((gone + t) / dur, 0.0, 1.0)
    fb = np.clip(t / rem, 0.0, 1.0) if rem > 0 else np.ones_like(t)
    pa = a0[0] + fa[:, None] * (a1[0, 0] - a0[0])
    pb = b0[0] + fb[:, None] * (b1[0] - b0[0])
    sh = np.repeat(SHAPE.packed(), t.size, axis=0)
    clearance = -shape_overlap(pa, ya + fa * ta, sh, pb, yb + fb * (yb1 - yb), sh).max()
    if gap >= 0.0:  # clear: by at least that much at every instant
        assert gap <= clearance + 1e-9
    else:  # overlapping (how deep is not asked for): they do, up to the turn's widening
        assert clearance < 0.03


def _slit(gap: float) -> dict:
    """One walker along a 2 m corridor through a 0.2 m thick wall with a ``gap`` wide
    slit on its centre line."""
    lo, hi = 1.0 - gap / 2, 1.0 + gap / 2
    return {"name": "slit", "terrain": {"extent": [0, -1, 9, 3]},
            "routes": {"nodes": [{"name": "a", "xy": [1.0, 1.0]},
                                 {"name": "b", "xy": [8.0, 1.0]}],
                       "edges": [{"from": "a", "to": "b", "width": 2.0}]},
            "obstacles": [
                {"name": "s", "polygon": [[4.0, -0.5], [4.2, -0.5], [4.2, lo], [4.0, lo]]},
                {"name": "n", "polygon": [[4.0, hi], [4.2, hi], [4.2, 2.5], [4.0, 2.5]]}],
            "groups": [{"name": "g", "count": 1, "spawn": "a", "destinations": ["b"],
                        "body_height": {"mean": 1.71, "sd": 0.0},
                        "free_speed": {"mean": 1.2, "sd": 0.0}}],
            "simulation": {"duration": 20.0, "seed": 1, "dt": 0.05, "fps": 10},
            "outputs": {"poses": False}}


def test_walker_turns_its_shoulders_to_slip_through_a_gap(tmp_path):
    # 0.40 m: narrower than the 0.44 m shoulders, wider than the 0.36 m depth
    broad = CrowdParams(body="three_discs")
    run = _run(_slit(0.40), tmp_path / "twist", params=broad)
    assert run.summary["agents_arrived"] == 1
    t = run.traj
    inside = (t.x > 4.0) & (t.x < 4.2)  # the body centre between the slit's faces
    facing = np.degrees(np.abs(np.arctan2(t.ori_y[inside], t.ori_x[inside])))
    assert inside.any() and facing.min() > 30.0  # shoulders turned in the slit
    assert facing.max() < 90.0  # still facing ahead, not walking sideways
    # facing where it steps, the same walker cannot pass
    still = replace(broad, steering=replace(SteeringParams(), twists_deg=(),
                                                    keep_facing=False))
    stuck = _run(_slit(0.40), tmp_path / "square", params=still)
    assert stuck.summary["agents_arrived"] == 0


def test_the_default_body_is_one_disc_as_broad_as_deep():
    axes = CrowdParams().body_axes(np.array([1.71]))
    assert axes[0] == axes[1] == np.float64(0.105 * 1.71)
    half_depth, half_width = CrowdParams(body="three_discs").body_axes(np.array([1.71]))
    assert half_width[0] > half_depth[0]




def test_gaps_stopped_at_a_runs_first_blocked_length_or_bounded_give_the_same_free_lengths():
    rng = np.random.default_rng(7)
    m, k, n_c, n_l = 40, 6, 5, 6
    shape = BodyShape.from_axes(rng.uniform(0.15, 0.2, m), rng.uniform(0.2, 0.26, m)).packed()
    start = rng.uniform(0, 3, (m, 2))
    ends = start[:, None, None, :] + (np.linspace(0.15, 0.9, n_l)[None, None, :, None]
                                      * rng.normal(size=(m, n_c, 1, 2)))
    ends = ends.reshape(m, n_c * n_l, 2)
    yaw0 = rng.uniform(-3, 3, m)
    yaw1 = yaw0[:, None] + rng.uniform(-1, 1, (m, n_c * n_l))
    dur = rng.uniform(0.3, 0.7, (m, n_c * n_l))
    pa = np.repeat(np.arange(m), k)  # agent-major, as np.nonzero gives them
    b_now = start[pa] + rng.uniform(-1, 1, (pa.size, 2))
    b_end = b_now + rng.uniform(-0.4, 0.4, (pa.size, 2))
    kw = dict(a_start=start, a_yaw0=yaw0, a_end=ends, a_yaw1=yaw1, a_duration=dur,
              a_elapsed=rng.uniform(0, 0.2, m), a_shape=shape, b_now=b_now,
              b_yaw_now=rng.uniform(-3, 3, pa.size), b_end=b_end,
              b_yaw_end=rng.uniform(-3, 3, pa.size),
              b_remaining=np.where(rng.random(pa.size) < 0.3, 0.0, rng.uniform(0, 0.5, pa.size)),
              b_shape=shape[rng.integers(0, m, pa.size)])
    wall_ok = rng.random((m, n_c * n_l)) > 0.1
    ok = wall_ok & (rng.random((m, n_c * n_l)) > 0.1)
    full, full_centre = body_gaps(pa, **kw)
    cut, cut_centre = body_gaps(pa, **kw, runs=n_l, a_ok=ok, a_centre_ok=wall_ok)

    def free(g, own):  # (m, C) clear lengths from the short end, all neighbours counted
        blocked = np.zeros((m, n_c, n_l), bool)
        np.logical_or.at(blocked, pa, g.reshape(-1, n_c, n_l) < 0.0)
        return np.cumprod(~blocked & own.reshape(m, n_c, n_l), axis=2).sum(axis=2)

    assert (free(full, ok) > 0).any() and (free(full, ok) < n_l).any()  # both kinds occur
    np.testing.assert_array_equal(free(cut, ok), free(full, ok))
    np.testing.assert_array_equal(free(cut_centre, wall_ok), free(full_centre, wall_ok))
    kept = np.isfinite(cut)
    assert (~kept).any()  # some were skipped
    # the others: evaluated, or a lower bound where the run's capsule keeps clear
    bounded = kept & (cut != full)
    assert bounded.any() and (cut[bounded] >= 0.0).all() and (cut <= full).all()
    assert (cut_centre <= full_centre).all() and (cut_centre[bounded] >= 0.0).all()


def test_clear_runs_keeps_exactly_the_signs_of_the_gaps_reduced_over_the_neighbours():
    rng = np.random.default_rng(11)
    m, k, n_c, n_l = 60, 5, 5, 6
    shape = BodyShape.from_axes(rng.uniform(0.15, 0.2, m), rng.uniform(0.2, 0.26, m)).packed()
    start = rng.uniform(0, 3, (m, 2))
    ends = start[:, None, None, :] + (np.linspace(0.15, 0.9, n_l)[None, None, :, None]
                                      * rng.normal(size=(m, n_c, 1, 2)))
    ends = ends.reshape(m, n_c * n_l, 2)
    yaw0 = rng.uniform(-3, 3, m)
    pa = np.repeat(np.arange(0, m, 2), k)  # every other agent has neighbours
    b_now = start[pa] + rng.uniform(-0.9, 0.9, (pa.size, 2))
    kw = dict(a_start=start, a_yaw0=yaw0, a_end=ends,
              a_yaw1=yaw0[:, None] + rng.uniform(-1, 1, (m, n_c * n_l)),
              a_duration=rng.uniform(0.3, 0.7, (m, n_c * n_l)),
              a_elapsed=rng.uniform(0, 0.2, m), a_shape=shape, b_now=b_now,
              b_yaw_now=rng.uniform(-3, 3, pa.size),
              b_end=b_now + rng.uniform(-0.4, 0.4, (pa.size, 2)),
              b_yaw_end=rng.uniform(-3, 3, pa.size),
              b_remaining=np.where(rng.random(pa.size) < 0.3, 0.0, rng.uniform(0, 0.5, pa.size)),
              b_shape=shape[rng.integers(0, m, pa.size)])
    wall_ok = rng.random((m, n_c * n_l)) > 0.1
    ok = wall_ok & (rng.random((m, n_c * n_l)) > 0.1)
    gaps, centre_gaps = body_gaps(pa, **kw, runs=n_l, a_ok=ok, a_centre_ok=wall_ok)

    def reduced(g, own):
        blocked = np.zeros((m, n_c * n_l), bool)
        np.logical_or.at(blocked, pa, g < 0.0)
        return own & ~blocked

    got_ok, got_centre = ok.copy(), wall_ok.copy()
    clear_runs(pa, **kw, runs=n_l, ok=got_ok, centre_ok=got_centre)
    want_ok, want_centre = reduced(gaps, ok), reduced(centre_gaps, wall_ok)
    np.testing.assert_array_equal(got_ok[pa], want_ok[pa])
    np.testing.assert_array_equal(got_centre[pa], want_centre[pa])
    alone = np.setdiff1d(np.arange(m), pa)
    np.testing.assert_array_equal(got_ok[alone], ok[alone])  # no neighbours: untouched
    assert want_ok[pa].any() and (~want_ok[pa] & wall_ok[pa]).any()  # both kinds occur


def test_clashes_with_neighbours_are_the_steps_with_a_negative_gap_to_a_valid_neighbour():
    from crowdwalk.crowd.conflicts import clashes_with_neighbours
    from crowdwalk.crowd.steering import Neighbours

    rng = np.random.default_rng(5)
    m, k = 40, 7
    shape = BodyShape.from_axes(rng.uniform(0.15, 0.2, (m, k)).ravel(),
                                rng.uniform(0.2, 0.26, (m, k)).ravel()).packed().reshape(m, k, 3)
    start = rng.uniform(0, 3, (m, 2))
    now = start[:, None] + rng.normal(0, 0.5, (m, k, 2))
    nbs = Neighbours(valid=rng.random((m, k)) < 0.7, now=now,
                     end=now + rng.normal(0, 0.2, (m, k, 2)), velocity=np.zeros((m, k, 2)),
                     radius=shape[..., 0], remaining=rng.uniform(0, 0.5, (m, k)),
                     yaw_now=rng.uniform(-3, 3, (m, k)), yaw_end=rng.uniform(-3, 3, (m, k)),
                     shape=shape)
    rows = np.flatnonzero(rng.random(m) < 0.8)
    own = shape[rows, 0]
    kw = dict(start=start[rows], end=start[rows] + rng.normal(0, 0.3, (rows.size, 2)),
              duration=rng.uniform(0.3, 0.6, rows.size), elapsed=rng.uniform(0, 0.1, rows.size),
              yaw=rng.uniform(-3, 3, rows.size), yaw_end=rng.uniform(-3, 3, rows.size),
              shape=np.column_stack([own, 0.8 * own, np.full(rows.size, 0.05)]))
    got = clashes_with_neighbours(nbs, rows, **kw)
    pa, pk = np.nonzero(nbs.valid[rows])  # every (decider, valid neighbour) pair at once
    nb = rows[pa]
    gaps = body_gaps(pa, a_start=kw["start"], a_yaw0=kw["yaw"], a_end=kw["end"][:, None],
                     a_yaw1=kw["yaw_end"][:, None], a_duration=kw["duration"][:, None],
                     a_elapsed=kw["elapsed"], a_shape=kw["shape"], b_now=nbs.now[nb, pk],
                     b_yaw_now=nbs.yaw_now[nb, pk], b_end=nbs.end[nb, pk],
                     b_yaw_end=nbs.yaw_end[nb, pk], b_remaining=nbs.remaining[nb, pk],
                     b_shape=shape[nb, pk])[0][:, 0]
    want = np.zeros(rows.size, bool)
    np.logical_or.at(want, pa, gaps < 0.0)
    np.testing.assert_array_equal(got, want)
    assert want.any() and not want.all()


def test_clear_runs_decides_touching_bodies_as_the_exact_gaps_do():
    # neighbours within a few ulp of touching (where the quick norms of clear_runs could
    # round to the other side): its signs are still body_gaps' (the exact norms')
    rng = np.random.default_rng(8)
    m = 4000
    shape = BodyShape.from_axes(np.full(m, 0.18), np.where(np.arange(m) % 2, 0.22, 0.18))
    packed = shape.packed()
    angle = rng.uniform(-np.pi, np.pi, m)
    along = np.column_stack([np.cos(angle), np.sin(angle)])
    start = rng.uniform(-50, 50, (m, 2))
    end = start + 0.3 * along
    # centre discs a few ulp from touching (about 1 in 200 is decided the other way by
    # sqrt(x x + y y) than by hypot)
    touch = packed[:, 0] * 2 + rng.uniform(-3e-16, 3e-16, m)
    b_now = end + touch[:, None] * np.column_stack([-along[:, 1], along[:, 0]])
    kw = dict(a_start=start, a_yaw0=angle, a_end=end[:, None], a_yaw1=angle[:, None],
              a_duration=np.full((m, 1), 0.5), a_elapsed=np.zeros(m), a_shape=packed,
              b_now=b_now, b_yaw_now=angle, b_end=b_now, b_yaw_end=angle,
              b_remaining=np.zeros(m), b_shape=packed)
    pa = np.arange(m)
    gaps, centre_gaps = body_gaps(pa, **kw)
    ok, centre_ok = np.ones((m, 1), bool), np.ones((m, 1), bool)
    clear_runs(pa, **kw, runs=1, ok=ok, centre_ok=centre_ok)
    np.testing.assert_array_equal(ok[:, 0], gaps[:, 0] >= 0.0)
    np.testing.assert_array_equal(centre_ok[:, 0], centre_gaps[:, 0] >= 0.0)
    assert ok.any() and not ok.all()  # both sides of touching occur
