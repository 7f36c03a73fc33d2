"""The steering's compiled kernels (:func:`crowdwalk.crowd.steering.choose_steps`).

Two kernels over the deciding walkers' rows, each a loop over rows that holds no GIL
(``nogil``), so the crowd's row threads (:class:`crowdwalk.workers.RowThreads`) steer on
every core at once:

- :func:`step_limits`: the candidate directions and, for each, the longest step clear of
  the walls and the neighbours (and the torso facing that allows it);
- :func:`step_utility`: the utility of each candidate and of waiting, and the choice.

They compute what the array formulation they replace computed, bit for bit: the same
operations in the same order (numpy's ``sum`` over a last axis of K <= 128 items is
``0 + pairwise``: eight partial sums, see :func:`_sum`), libm's transcendentals (numpy
calls the same ones on this machine's SIMD level), no fused multiply-adds (numba does not
contract without ``fastmath``). ``scripts/check_identical_runs.py``: identical runs.

Shapes: m rows (walkers), C candidate directions (the fixed offsets and the current
heading, last), L step lengths, J = C L candidate steps, K neighbours per walker.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from crowdwalk.crowd.clearance import _bilinear, _walls_of
from crowdwalk.crowd.shape import _clear_of_a

__all__ = ["step_limits", "step_utility", "turn_allowed"]

_TAU = 2 * np.pi


@nb.njit(cache=True, nogil=True, inline="always")
def _wrap(x):
    """``(x + pi) % (2 pi) - pi`` as numpy computes it (Python's float modulo)."""
    return (x + np.pi) % _TAU - np.pi


@nb.njit(cache=True, nogil=True, inline="always")
def _facing(yaw, heading, turned):
    """The torso's facing [rad] at the end of a step along ``heading`` [rad] turned by
    ``turned`` [rad] from it, unwrapped against its facing ``yaw`` now [rad]."""
    turn = heading + turned - yaw
    return yaw + (turn + np.pi) % _TAU - np.pi


@nb.njit(cache=True, nogil=True, inline="always")
def _hypot2(dx, dy):
    """``sqrt(dx dx + dy dy)`` (:func:`crowdwalk.crowd.geometry.distance`'s order)."""
    return np.sqrt(dx * dx + dy * dy)


@nb.njit(cache=True, nogil=True)
def _sum(v, n):
    """``v[:n].sum()`` in numpy's order for n <= 128: 0 plus the pairwise sum (items one
    by one below 8, else eight partial sums over strides of 8, combined as a tree, then
    the rest one by one)."""
    if n < 8:
        s = 0.0
        for i in range(n):
            s += v[i]
        return 0.0 + s
    r0, r1, r2, r3 = v[0], v[1], v[2], v[3]
    r4, r5, r6, r7 = v[4], v[5], v[6], v[7]
    i = 8
    while i < n - n % 8:
        r0 += v[i]
        r1 += v[i + 1]
        r2 += v[i + 2]
        r3 += v[i + 3]
        r4 += v[i + 4]
        r5 += v[i + 5]
        r6 += v[i + 6]
        r7 += v[i + 7]
        i += 8
    s = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        s += v[i]
        i += 1
    return 0.0 + s


@nb.njit(cache=True, nogil=True, inline="always")
def _point_segment(px, py, ax, ay, bx, by):
    """Distance [m] from p to the segment ab (geometry.point_segment_distance's order)."""
    apx, apy = px - ax, py - ay
    abx, aby = bx - ax, by - ay
    denom = abx * abx + aby * aby
    t = apx * abx
    t += apy * aby
    t /= denom if denom > 0 else 1.0
    t = min(max(t, 0.0), 1.0)
    dx = apx - t * abx
    dy = apy - t * aby
    return np.sqrt(dx * dx + dy * dy)


@nb.njit(cache=True, nogil=True)
def _segments(p0x, p0y, p1x, p1y, q0x, q0y, q1x, q1y):
    """Least distance [m] between segments p0p1 and q0q1
    (geometry.segment_distance's order)."""
    rx, ry = p1x - p0x, p1y - p0y
    sx, sy = q1x - q0x, q1y - q0y
    ax, ay = q0x - p0x, q0y - p0y
    d = min(_point_segment(p0x, p0y, q0x, q0y, q1x, q1y),
            _point_segment(p1x, p1y, q0x, q0y, q1x, q1y))
    d = min(d, _point_segment(q0x, q0y, p0x, p0y, p1x, p1y))
    d = min(d, _point_segment(q1x, q1y, p0x, p0y, p1x, p1y))
    denom = rx * sy - ry * sx
    if abs(denom) > 1e-15:
        t = (ax * sy - ay * sx) / denom
        u = (ax * ry - ay * rx) / denom
        if t >= 0 and t <= 1 and u >= 0 and u <= 1:
            return 0.0
    return d


@nb.njit(cache=True, nogil=True)
def _shoulders(a, yaw_end, position, ends, yaw, shape, dist, ox, oy, cell, near, wall_ok,
               ok):
    """Row ``a``'s candidate steps (J,) bool into ``ok``: ``wall_ok`` and the shoulder
    discs keep their radius (widened for the turn to ``yaw_end`` (C,) [rad]) from the
    walls at the step's end and halfway, or do not come closer than they are now; tested
    only where the centre's clearance ``near`` (C, L) [m] is within the outline's reach
    (clearance grows by at most the distance moved)."""
    n_c, n_l = near.shape
    offset = shape[a, 2]
    reach = shape[a, 1] + 2 * offset
    for c in range(n_c):
        y0, y1 = yaw[a], yaw_end[c]
        bend = offset * (1.0 - np.cos(0.5 * (y1 - y0)))
        s0, c0, s1, c1 = -np.sin(y0) * offset, np.cos(y0) * offset, -np.sin(y1) * offset, \
            np.cos(y1) * offset
        for l in range(n_l):
            j = c * n_l + l
            ok[j] = wall_ok[c, l]
            if not (ok[j] and near[c, l] < reach and offset > 0):
                continue
            px, py = position[a, 0], position[a, 1]
            ex, ey = ends[a, c, l, 0], ends[a, c, l, 1]
            for k in (1.0, -1.0):  # left, right
                nx, ny = px + k * s0, py + k * c0
                mx, my = ex + k * s1, ey + k * c1
                r = min(shape[a, 1] + bend, _bilinear(dist, ox, oy, cell, nx, ny) - 1e-6)
                if not (_bilinear(dist, ox, oy, cell, mx, my) >= r and _bilinear(
                        dist, ox, oy, cell, 0.5 * (nx + mx), 0.5 * (ny + my)) >= r):
                    ok[j] = False


@nb.njit(cache=True, nogil=True)
def _free(ok, c, lengths):
    """The longest length [m] of run ``c`` of ``ok`` (J,) clear from the short end (0:
    none)."""
    n_l = lengths.shape[0]
    n = 0
    while n < n_l and ok[c * n_l + n]:
        n += 1
    return lengths[n - 1] if n > 0 else 0.0


@nb.njit(cache=True, nogil=True)
def _blocked(a, yaw_end, pairs, timed, position, yaw, ends, shape, need, dist, ox, oy, cell,
             near, wall_ok, a_ends, a_yaw1, a_dur, lag, nb_now, nb_yaw_now, nb_end,
             nb_yaw_end, nb_remaining, nb_shape, ok, centre_ok):
    """Row ``a``'s candidate steps clear of the walls and its ``pairs`` neighbours, the
    torso turning to ``yaw_end`` (C,): its rows of ``ok`` and ``centre_ok`` (m, J) (the
    centre discs alone, which no facing can beat)."""
    n_c, n_l = near.shape[1], near.shape[2]
    _shoulders(a, yaw_end, position, ends, yaw, shape, dist, ox, oy, cell, near[a],
               wall_ok[a], ok[a])
    for c in range(n_c):
        for l in range(n_l):
            centre_ok[a, c * n_l + l] = wall_ok[a, c, l]
    if pairs.size == 0:
        return
    if timed:
        for c in range(n_c):
            for l in range(n_l):
                a_yaw1[a, c * n_l + l] = yaw_end[c]
        _clear_of_a(a, pairs, position, yaw, a_ends, a_yaw1, a_dur, lag, shape, nb_now[a],
                    nb_yaw_now[a], nb_end[a], nb_yaw_end[a], nb_remaining[a], nb_shape[a],
                    n_l, ok, centre_ok)
        return
    for k in pairs:
        for c in range(n_c):
            for l in range(n_l):
                if _segments(position[a, 0], position[a, 1], ends[a, c, l, 0],
                             ends[a, c, l, 1], nb_now[a, k, 0], nb_now[a, k, 1],
                             nb_end[a, k, 0], nb_end[a, k, 1]) < need[k]:
                    ok[a, c * n_l + l] = centre_ok[a, c * n_l + l] = False


@nb.njit(cache=True, nogil=True)
def step_limits(position, stance, heading, route_direction, yaw, radius, shape, speed,
                step_time, lag, nominal_step, timed, nb_valid, nb_now, nb_end, nb_radius,
                nb_yaw_now, nb_yaw_end, nb_remaining, nb_shape, dist, least, ox, oy, cell,
                offsets_fixed, lengths, foot_clearance, ahead_limit, keep_facing, twists):
    """The candidate steps of m walkers and how far each may go.

    Parameters
    ----------
    position, stance : (m, 2)
        Body and stance-foot centre-line point [m].
    heading, yaw, radius : (m,)
        Walking direction [rad], torso facing [rad], body radius [m].
    route_direction : (m, 2)
        Unit direction of the route ahead.
    shape : (m, 3)
        Outlines (``BodyShape.packed`` rows).
    speed, step_time, lag, nominal_step : (m,)
        Speed [m/s], shortest step duration [s], time since the heel strike [s],
        preferred step [m].
    timed : bool
        The neighbour test in time (``nb_remaining``, ``step_time``), else against the
        neighbours' whole remaining sweeps (discs of ``radius``).
    nb_valid, nb_now, nb_end, nb_radius : (m, K), (m, K, 2), (m, K, 2), (m, K)
        The neighbours: real ones, position now and at their committed step's end [m],
        radius [m].
    nb_yaw_now, nb_yaw_end, nb_remaining, nb_shape : (m, K), (m, K), (m, K), (m, K, 3)
        Their facing now and at the end [rad], time to the end [s], outlines.
    dist, least, ox, oy, cell
        The clearance field (``ClearanceField``: distance, block_least, origin, cell).
    offsets_fixed : (C - 1,)
        Candidate offsets from the route direction [rad].
    lengths : (L,)
        Step lengths tested [m], increasing.
    foot_clearance, ahead_limit : float
        [m]; the largest offset [rad] that counts as a step ahead.
    keep_facing : bool
    twists : (T,)
        Shoulder twists [rad] tried after keeping the facing.

    Returns
    -------
    offsets, cand_heading : (m, C), (m, C)
        Each candidate's offset from the route direction and direction [rad].
    dirs : (m, C, 2)
        Unit candidate directions.
    free : (m, C)
        The longest clear step along each [m] (0: none).
    yaw_end : (m, C)
        The torso's facing at the step's end [rad] (unwrapped against ``yaw``).
    """
    m = position.shape[0]
    n_c, n_l, n_k = offsets_fixed.shape[0] + 1, lengths.shape[0], nb_valid.shape[1]
    n_j = n_c * n_l
    offsets = np.empty((m, n_c))
    dirs = np.empty((m, n_c, 2))
    cand_heading = np.empty((m, n_c))
    ends = np.empty((m, n_c, n_l, 2))
    a_ends = ends.reshape(m, n_j, 2)
    free = np.empty((m, n_c))
    yaw_end = np.empty((m, n_c))
    wall_ok = np.empty((m, n_c, n_l), np.bool_)
    near = np.empty((m, n_c, n_l))
    ok = np.empty((m, n_j), np.bool_)
    centre_ok = np.empty((m, n_j), np.bool_)
    a_yaw1 = np.empty((m, n_j))
    a_dur = np.empty((m, n_j))
    reach_w = np.empty(m)
    need = np.empty(n_k)
    pairs = np.empty(n_k, np.int64)
    twisted = np.empty(n_c)
    reach_t = np.empty(n_c)
    for a in range(m):
        reach_w[a] = shape[a, 1] + 2 * shape[a, 2]
    for a in range(m):
        # candidates: the fixed offsets from the route direction, and the current heading
        vx, vy = route_direction[a, 0], route_direction[a, 1]
        keep = _wrap(heading[a] - np.arctan2(vy, vx))
        for c in range(n_c):
            off = offsets_fixed[c] if c < n_c - 1 else keep
            offsets[a, c] = off
            co, si = np.cos(off), np.sin(off)
            dx, dy = co * vx - si * vy, si * vx + co * vy
            dirs[a, c, 0], dirs[a, c, 1] = dx, dy
            cand_heading[a, c] = np.arctan2(dy, dx)
            yaw_end[a, c] = _facing(yaw[a], cand_heading[a, c], 0.0)
            for l in range(n_l):
                h = 0.5 * lengths[l]
                ends[a, c, l, 0] = stance[a, 0] + h * dx
                ends[a, c, l, 1] = stance[a, 1] + h * dy
            if timed:
                for l in range(n_l):
                    a_dur[a, c * n_l + l] = max(lengths[l] / speed[a], step_time[a])
        _walls_of(a, dist, least, ox, oy, cell, position, stance, ends, dirs, lengths, radius,
                  reach_w, foot_clearance, wall_ok, near)
        # the neighbours a step could reach, in order
        n_p = 0
        if n_k:
            reach = 0.0
            for c in range(n_c):
                for l in range(n_l):
                    reach = max(reach, _hypot2(ends[a, c, l, 0] - position[a, 0],
                                               ends[a, c, l, 1] - position[a, 1]))
            for k in range(n_k):
                if timed:  # the outlines' holding discs
                    need[k] = (max(shape[a, 0], shape[a, 1] + shape[a, 2])
                               + max(nb_shape[a, k, 0], nb_shape[a, k, 1] + nb_shape[a, k, 2]))
                else:
                    need[k] = radius[a] + nb_radius[a, k]
                gap0 = _point_segment(position[a, 0], position[a, 1], nb_now[a, k, 0],
                                      nb_now[a, k, 1], nb_end[a, k, 0], nb_end[a, k, 1])
                if nb_valid[a, k] and gap0 - need[k] < reach + 1e-9:
                    pairs[n_p] = k
                    n_p += 1
        mine = pairs[:n_p]
        _blocked(a, yaw_end[a], mine, timed, position, yaw, ends, shape, need, dist, ox, oy,
                 cell, near, wall_ok, a_ends, a_yaw1, a_dur, lag, nb_now, nb_yaw_now, nb_end,
                 nb_yaw_end, nb_remaining, nb_shape, ok, centre_ok)
        for c in range(n_c):
            free[a, c] = _free(ok[a], c, lengths)
        if not timed:
            continue
        # a walker that cannot take its preferred step ahead facing forward, where a body
        # as narrow as it is deep could, tries keeping its facing, then each twist of its
        # shoulders (the way it is turned already, else to the left); a candidate takes
        # the first facing that lets it step strictly further
        best_ahead = 0.0
        wider = False
        for c in range(n_c):
            if abs(offsets[a, c]) <= ahead_limit:
                best_ahead = max(best_ahead, free[a, c])
            wider = wider or _free(centre_ok[a], c, lengths) > free[a, c] + 1e-9
        if not (best_ahead < min(nominal_step[a], lengths[n_l - 1]) - 1e-9 and wider):
            continue
        side = -1.0 if _wrap(yaw[a] - heading[a]) < -1e-3 else 1.0
        for o in range(twists.shape[0] + 1):
            if o == 0 and not keep_facing:
                continue
            for c in range(n_c):
                twisted[c] = yaw[a] if o == 0 else _facing(yaw[a], cand_heading[a, c],
                                                           side * twists[o - 1])
            _blocked(a, twisted, mine, timed, position, yaw, ends, shape, need, dist, ox, oy,
                     cell, near, wall_ok, a_ends, a_yaw1, a_dur, lag, nb_now, nb_yaw_now,
                     nb_end, nb_yaw_end, nb_remaining, nb_shape, ok, centre_ok)
            for c in range(n_c):
                reach_t[c] = _free(ok[a], c, lengths)
            for c in range(n_c):
                if reach_t[c] > free[a, c] + 1e-9:
                    free[a, c] = reach_t[c]
                    yaw_end[a, c] = twisted[c]
    return offsets, cand_heading, dirs, free, yaw_end


@nb.njit(cache=True, nogil=True)
def turn_allowed(cand_heading, heading, ahead, nominal_step, stuck, limit, spare):
    """The turn limit (``SteeringParams.turn_limit_deg``): whether a candidate along
    ``cand_heading`` [rad] is within ``limit`` [rad] (with 1e-9 added) of the ``heading``
    [rad], or the walker is spared: its step straight on, ``ahead`` [m], is shorter than
    ``spare`` × ``nominal_step`` [m], or it was standing (``stuck`` [s] > 0)."""
    return (abs(_wrap(cand_heading - heading)) <= limit
            or ahead < spare * nominal_step - 1e-9 or stuck > 0.0)


@nb.njit(cache=True, nogil=True)
def step_utility(position, stance, target, heading, yaw, radius, speed, nominal_step, stuck,
                 offsets, cand_heading, dirs, free, yaw_end, cap, nb_valid,
                 nb_now, nb_end, nb_velocity, nb_radius, nb_heading, has_heading,
                 personal_scale, wall_scale, dist, ox, oy, cell, weights, turn_limit):
    """The utility [m] (lower is better) of m walkers' candidates and of waiting, and the
    choice (steering.choose_steps' soft terms).

    Parameters
    ----------
    position, stance, target : (m, 2)
        Body, stance-foot centre-line point, route target [m].
    heading, yaw, radius, speed, nominal_step : (m,)
        [rad], [rad], [m], [m/s], [m].
    stuck : (m,)
        Standing time [s] (0 for none: the give-way and clog terms then add 0).
    offsets, cand_heading, dirs, free, yaw_end
        :func:`step_limits`' results.
    cap : (m, C)
        The longest step the speed model allows along each candidate [m] (inf: none).
    nb_valid, nb_now, nb_end, nb_velocity, nb_radius, nb_heading
        The K neighbours (sorted nearest first): (m, K) bool, (m, K, 2) [m], (m, K, 2)
        [m], (m, K, 2) [m/s], (m, K) [m], (m, K) [rad] (read where ``has_heading``).
    personal_scale, wall_scale : (m,)
        Factors on the neighbour repulsion and the wall term [-].
    dist, ox, oy, cell
        The clearance field.
    weights : (16,) float
        ``SteeringParams``' personal_weight, personal_range, soft_neighbours,
        anticipation, oncoming_neighbours, wall_weight, wall_range, turn_weight,
        right_bias, wait_cost, give_way_after, give_way_weight, clog_after, twist_weight,
        min_step, and the largest offset of a candidate (pi / 2 + 1e-9) [rad].
    turn_limit : (2,) float
        Turn limit [rad] (+1e-9; NaN: none) and ``turn_limit_spare`` [-].

    Returns
    -------
    direction : (m, 2), free_length : (m,) [m], move : (m,) bool, yaw_end : (m,) [rad],
    utility : (m,) [m]
    """
    m, n_c = free.shape
    n_k = nb_valid.shape[1]
    w_personal, r_personal, soft, anticipation = weights[0], weights[1], weights[2], weights[3]
    oncoming_n, w_wall, r_wall, w_turn = weights[4], weights[5], weights[6], weights[7]
    w_right, wait_cost, give_way_after, w_give_way = weights[8], weights[9], weights[10], \
        weights[11]
    clog_after, w_twist, min_step, forward = weights[12], weights[13], weights[14], weights[15]
    n_soft = min(int(soft), n_k)
    n_on = min(int(oncoming_n), n_k)
    direction = np.empty((m, 2))
    free_length = np.empty(m)
    move = np.empty(m, np.bool_)
    chosen_yaw = np.empty(m)
    best_u = np.empty(m)
    cand = np.empty((n_c + 1, 2))
    u = np.empty(n_c + 1)
    terms = np.empty(max(n_k, 1))
    pick = np.empty(max(n_k, 1), np.int64)
    for a in range(m):
        px, py = position[a, 0], position[a, 1]
        for c in range(n_c):
            use = min(min(free[a, c], nominal_step[a]), cap[a, c])
            h = 0.5 * use
            cand[c, 0] = stance[a, 0] + h * dirs[a, c, 0]
            cand[c, 1] = stance[a, 1] + h * dirs[a, c, 1]
        cand[n_c, 0], cand[n_c, 1] = px, py  # waiting
        for c in range(n_c + 1):
            u[c] = _hypot2(target[a, 0] - cand[c, 0], target[a, 1] - cand[c, 1])
        if n_k:
            # repulsion from the nearest ``soft_neighbours`` at their committed step ends
            for c in range(n_c + 1):
                for k in range(n_soft):
                    terms[k] = 0.0
                    if nb_valid[a, k]:
                        gap_end = _hypot2(cand[c, 0] - nb_end[a, k, 0],
                                          cand[c, 1] - nb_end[a, k, 1])
                        rr = radius[a] + nb_radius[a, k]
                        terms[k] = w_personal * np.exp(-(gap_end - rr) / r_personal) \
                            * personal_scale[a]
                u[c] += _sum(terms, n_soft)
            # anticipation: the nearest ``oncoming_neighbours`` oncoming walkers (the
            # sum runs over that many terms, the oncoming ones first, then zeros)
            odx, ody = np.cos(heading[a]), np.sin(heading[a])
            n_p = 0
            for k in range(n_k):
                if nb_valid[a, k] and (nb_velocity[a, k, 0] * odx
                                       + nb_velocity[a, k, 1] * ody) < -0.1:
                    pick[n_p] = k
                    n_p += 1
            n_oncoming = n_p
            for c in range(n_c + 1):
                mx = speed[a] * dirs[a, c, 0] if c < n_c else 0.0
                my = speed[a] * dirs[a, c, 1] if c < n_c else 0.0
                for q in range(n_on):
                    terms[q] = 0.0
                    if q >= n_oncoming:
                        continue
                    k = pick[q]
                    rpx, rpy = nb_now[a, k, 0] - px, nb_now[a, k, 1] - py
                    rvx, rvy = nb_velocity[a, k, 0] - mx, nb_velocity[a, k, 1] - my
                    vv = rvx * rvx + rvy * rvy
                    t = min(max(-(rpx * rvx + rpy * rvy) / max(vv, 1e-12), 0.0), anticipation)
                    closest = _hypot2(rpx - -t * rvx, rpy - -t * rvy)
                    ra = radius[a] + nb_radius[a, k]
                    terms[q] = w_personal * np.exp(-(closest - ra) / r_personal)
                u[c] += _sum(terms, n_on)
        for c in range(n_c + 1):
            wall_gap = _bilinear(dist, ox, oy, cell, cand[c, 0], cand[c, 1]) - radius[a]
            u[c] += w_wall * wall_scale[a] * np.exp(-max(wall_gap, 0.0) / r_wall)
        for c in range(n_c):
            turned = _wrap(yaw_end[a, c] - cand_heading[a, c])
            u[c] += w_twist * (1.0 - np.cos(turned))
            u[c] += w_turn * (1.0 - np.cos(cand_heading[a, c] - heading[a]))
            u[c] += w_right * max(np.sin(offsets[a, c]), 0.0)
            if not abs(offsets[a, c]) <= forward:
                u[c] = np.inf
        u[n_c] += wait_cost
        if has_heading and n_k:
            # two walkers standing face to face: waiting gets dearer every second
            odx, ody = np.cos(heading[a]), np.sin(heading[a])
            face = False
            for k in range(n_k):
                dx, dy = nb_now[a, k, 0] - px, nb_now[a, k, 1] - py
                if (np.cos(nb_heading[a, k] - heading[a]) < -0.5 and _hypot2(dx, dy) < 1.2
                        and dx * odx + dy * ody > 0 and nb_valid[a, k]):
                    face = True
                    break
            late = max(stuck[a] - give_way_after, 0.0)
            u[n_c] += w_give_way * late if face else 0.0
        # a clog: every standing walker grows impatient
        u[n_c] += w_give_way * max(stuck[a] - clog_after, 0.0)
        for c in range(n_c):
            if not free[a, c] >= min_step:
                u[c] = np.inf
        if not np.isnan(turn_limit[0]):
            # the last candidate keeps the current heading: how far the walker can go on
            for c in range(n_c):
                if not turn_allowed(cand_heading[a, c], heading[a], free[a, n_c - 1],
                                    nominal_step[a], stuck[a], turn_limit[0],
                                    turn_limit[1]):
                    u[c] = np.inf
        best = 0  # numpy's argmin: the first least (or the first NaN)
        for c in range(n_c + 1):
            if np.isnan(u[c]):
                best = c
                break
            if u[c] < u[best]:
                best = c
        pick_c = min(best, n_c - 1)
        move[a] = best < n_c
        direction[a, 0], direction[a, 1] = dirs[a, pick_c, 0], dirs[a, pick_c, 1]
        free_length[a] = free[a, pick_c] if move[a] else 0.0
        chosen_yaw[a] = yaw_end[a, pick_c] if move[a] else yaw[a]
        best_u[a] = u[best]
    return direction, free_length, move, chosen_yaw, best_u
