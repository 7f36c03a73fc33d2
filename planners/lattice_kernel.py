"""The compiled lattice: each agent's nodes, steps and swings, evaluated when first read.

An agent's nodes (footholds, snapping, support) and terminal energies are computed first,
for every agent of a batch (:func:`prepare_agents`); a step's legality and energy
(:func:`eval_step`) and a swing curve (:func:`eval_swing`) when a search first reads them
(:func:`step_legal`, :func:`swing_legal`, :func:`config_efficiency`), once each: the
searches' kernels take the :data:`Lattice` and read it through these. :func:`complete`
evaluates everything a search may read (the eager tables). Each agent is evaluated on its
own ground profile (shifted so that its stance foot lies on a raster cell boundary), with
the same arithmetic, in the same order, as the vectorised definitions it replaces
(:meth:`~planners.profile.GroundProfile.height` and ``span_heights``,
:func:`~planners.legality.foot_support`, :func:`~planners.legality.snap_to_support`,
:func:`~planners.energy.step_energy`, :func:`~planners.energy.terminal_energy`,
:meth:`~planners.profile.GroundProfile.raster`, :func:`~planners.swing.adjust_swings`),
so a value does not depend on when, or whether, the other entries were evaluated.
"""

from __future__ import annotations

from collections import namedtuple

import numba as nb
import numpy as np

from planners.energy import EV_PEAK_CM
from planners.kinematics import key_frame, key_frame_from, leg_constants, next_swing_leg, stance_leg
from planners.swing import _cell, adjust_one

__all__ = ["Lattice", "STEP_CONTEXT", "SWING_CONTEXT", "build_agents", "build_pending",
           "build_pending_steps", "build_swing", "eval_pending_step", "step_at",
           "complete", "complete_agents",
           "config_efficiency", "config_legal", "efficiency_one", "eval_step", "eval_swing",
           "inline", "prepare",
           "prepare_agents", "probe", "probe_efficiency", "step_legal", "swing_at",
           "swing_legal"]

_EV_PEAK = -0.18 * EV_PEAK_CM**2 + 7.14 * EV_PEAK_CM
_VERTICAL = 1e-12
# Reason flags (planners.legality.Reason)
_EDGE, _SLOPE, _STEP_HEIGHT, _KNEE_REACH, _UNREACHED = 1, 2, 4, 8, 32
_jit = nb.njit(cache=True, nogil=True)
#: Kernels that allocate nothing: compiled without numba's runtime (their array
#: arguments are not reference-counted at every call).
_leaf = nb.njit(cache=True, nogil=True, _nrt=False)
#: Functions that take the Lattice: inlined into the kernels (a call passes every array
#: of the tuple, several microseconds).
inline = nb.njit(cache=True, nogil=True, inline="always")
_inline = inline
# One exit: the functions that take the Lattice have no early ``return``. Numba keeps a
# reference to each of the Lattice's 65 arrays for a function taking it; where that
# function (inlined or not) has several exits, every call takes and releases all 65
# references (measured 0.3-4 us per call of an evaluation that found its entry done,
# against ~1 ns with one exit), and a search reads entries thousands of times.


@_leaf
def _right(s, x):
    """``np.searchsorted(s, x, side="right")`` of a float."""
    lo, hi = 0, s.size
    while lo < hi:
        mid = (lo + hi) >> 1
        if s[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@_leaf
def _left(s, x):
    """``np.searchsorted(s, x, side="left")`` of a float."""
    lo, hi = 0, s.size
    while lo < hi:
        mid = (lo + hi) >> 1
        if s[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@_leaf
def _height(s, z, slope, x):
    """GroundProfile.height at ``x`` [m]."""
    q = max(x, s[0])
    i = _right(s, q) - 1
    return z[i] + slope[i] * (q - s[i])


@_leaf
def _span(s, z, slope, a, b):
    """GroundProfile.span_heights over [a, b]: (highest, height(a), height(b)) [m]."""
    qa = max(a, s[0])
    ia = _right(s, qa) - 1
    ha = z[ia] + slope[ia] * (qa - s[ia])
    qb = max(b, s[0])
    ib = _right(s, qb) - 1
    hb = z[ib] + slope[ib] * (qb - s[ib])
    empty = b < a
    best = max(ha, ha if empty else hb)
    lo = _left(s, a)
    hi = 0 if max(a, b) < s[0] else (ia if empty else ib) + 1
    for i in range(lo, hi):
        best = max(best, z[i])
    return best, ha, hb


@_leaf
def _span_from(s, z, slope, a, ia, lo, b, ib):
    """:func:`_span` given ``ia = _right(s, max(a, s[0])) - 1``, ``lo = _left(s, a)``
    and ``ib = _right(s, max(b, s[0])) - 1`` (look-ups shared by the steps of a node)."""
    qa = max(a, s[0])
    ha = z[ia] + slope[ia] * (qa - s[ia])
    qb = max(b, s[0])
    hb = z[ib] + slope[ib] * (qb - s[ib])
    empty = b < a
    best = max(ha, ha if empty else hb)
    hi = 0 if max(a, b) < s[0] else (ia if empty else ib) + 1
    for i in range(lo, hi):
        best = max(best, z[i])
    return best, ha, hb


@_leaf
def _support(x, heel_off, toe_off, s, z, slope, edges, margin, tolerance, max_slope):
    """foot_support of an ankle at ``x`` [m]: 0 or EDGE | SLOPE flags."""
    heel = x - heel_off
    toe = x + toe_off
    count = _left(edges, toe + margin) - _right(edges, heel - margin)
    highest, z_heel, z_toe = _span(s, z, slope, heel + 1e-9, toe - 1e-9)
    bump = highest - max(z_heel, z_toe)
    grade = abs(z_toe - z_heel) / (toe - heel)
    reason = _EDGE if count > 0 else 0
    if bump > tolerance or grade > max_slope:
        reason |= _SLOPE
    return reason


@_leaf
def _snap(x, window, heel_off, toe_off, s, z, slope, edges, margin, tolerance, max_slope):
    """snap_to_support of one foothold [m] (3 edges on each side), and the
    :func:`_support` flags of the foothold returned (-1 where there is no edge: not
    computed)."""
    E = edges.size
    if E == 0:
        return x, -1
    flags = _support(x, heel_off, toe_off, s, z, slope, edges, margin, tolerance, max_slope)
    if flags == 0:
        return x, 0
    m = margin + 1e-9
    i = _left(edges, x)
    best, best_cost = x, np.inf
    for side in range(2):
        for d in range(-3, 3):
            e = edges[min(max(i + d, 0), E - 1)]
            c = e + heel_off + m if side == 0 else e - toe_off - m
            shift = abs(c - x)
            if shift <= window and shift < best_cost and _support(
                    c, heel_off, toe_off, s, z, slope, edges, margin, tolerance,
                    max_slope) == 0:
                best, best_cost = c, shift
                flags = 0
    return best, flags


@_leaf
def _energy(length, rise, Ej, speed, normal, p):
    """Eqs. 1, 2 and 4 of one step (+ the step-frequency term where ``normal`` > 0):
    (En, Ev, E). ``p``: alpha, beta, gamma, down_ratio, linear (1/0), frequency*alpha."""
    v = 60.0 * speed
    En = (32.0 + 0.005 * (v * v)) * length / v
    h = 100.0 * rise
    a = abs(h)
    if p[4] > 0:
        up = 7.14 * a
    elif a <= EV_PEAK_CM:
        up = -0.18 * (a * a) + 7.14 * a
    else:
        up = _EV_PEAK + 7.14 * (a - EV_PEAK_CM)
    Ev = up if h >= 0 else p[3] * up
    E = p[0] * En + p[1] * Ev + p[2] * Ej
    if normal > 0:
        x = normal / max(length, 1e-6) - 1.0
        E = E + p[5] * En * (x * x)
    return En, Ev, E


@_jit
def _step_E(length, rise, summit_z, leg, speed, normal, p, c_thigh, c_calf, constants,
            lift, s1):
    """step_energy(0, 0, length, rise, summit_z, ...)[3]: Eq. 4 of one step [J/kg];
    ``s1`` the stance leg at K1 of a foothold at (0, 0) (:func:`stance_leg`, the same
    for every such step: :func:`key_frame` is this with it)."""
    ankle = leg[5]
    s4 = next_swing_leg(length, rise + ankle, max(rise + ankle, 0.0 + ankle), leg[0], leg[1],
                        ankle + lift, constants)
    thigh, calf, _ = key_frame_from(0.0, 0.0, length, rise, 0.0, summit_z, leg[0], leg[1],
                                    leg[4], ankle, constants, s1, s4)
    Ej = c_thigh * thigh + c_calf * calf
    return _energy(length, rise, Ej, speed, normal, p)[2]


@_jit
def _terminal(s, z, lo_i, hi_i, starts, stop, out, leg, speed, normal, per_metre, L0,
              p, c_thigh, c_calf, constants, lift, max_slope, min_ratio, max_ratio):
    """terminal_energy of the footholds ``starts`` (K,) to ``stop`` [m] over the profile
    vertices lo_i..hi_i; fills ``out`` (K,) [J/kg]."""
    s = s[lo_i:hi_i + 1]
    z = z[lo_i:hi_i + 1]
    nseg = s.size - 1
    if nseg < 1:
        for k in range(starts.size):
            out[k] = per_metre * (stop - starts[k])
        return
    ds = np.empty(nseg)
    dz = np.empty(nseg)
    steep = np.empty(nseg, dtype=np.bool_)
    nsteep = 0
    for i in range(nseg):
        ds[i] = s[i + 1] - s[i]
        dz[i] = z[i + 1] - z[i]
        steep[i] = abs(dz[i]) > max_slope * ds[i]
        nsteep += steep[i]
    where = np.empty(nsteep, dtype=np.int64)
    w = 0
    for i in range(nseg):
        if steep[i]:
            where[w] = i
            w += 1
    length = leg[0] + leg[1]
    lo = min_ratio * length
    longest = max_ratio * length
    s1 = stance_leg(0.0, 0.0, leg[0], leg[1], leg[5], constants)
    E0 = _step_E(L0, 0.0, 0.0 + (leg[5] + lift), leg, speed, normal, p, c_thigh, c_calf,
                 constants, lift, s1)
    cost = np.empty(nseg)
    gap = np.empty(nseg)
    nxt = np.empty(nseg, dtype=np.int64)
    w = 0
    for i in range(nseg):
        while w < nsteep and where[w] <= i:
            w += 1
        nxt[i] = w  # the first steep segment after i
        gap[i] = s[where[w]] - s[i + 1] if w < nsteep else np.inf
        if steep[i]:
            g = min(max(gap[i], lo), L0)
            rise = dz[i]
        else:
            g = L0
            rise = dz[i] / max(ds[i], 1e-12) * L0
        if dz[i] == 0.0:  # a level segment: E0's step (the same length, rise and summit)
            E = E0
        else:
            E = _step_E(g, rise, max(rise, 0.0) + (leg[5] + lift), leg, speed, normal, p,
                        c_thigh, c_calf, constants, lift, s1)
        cost[i] = E - per_metre * g if steep[i] else (E - E0) / L0 * ds[i]
    if nsteep > 1:  # a low obstacle may be stridden over (see terminal_energy)
        for i in range(nseg):
            j = where[min(nxt[i], nsteep - 1)]
            if not (steep[i] and dz[i] > 0 and nxt[i] < nsteep and dz[j] < 0
                    and gap[i] + leg[2] <= longest):
                continue
            stride = max(L0, min(gap[i] + leg[2], longest))
            top = max(z[i + 1], z[j]) - z[i]
            Es = _step_E(stride, 0.0, max(top, 0.0) + (leg[5] + lift), leg, speed, normal,
                         p, c_thigh, c_calf, constants, lift, s1)
            both, jump = cost[i] + cost[j], Es - per_metre * stride
            cost[j] = cost[j] if both <= jump else 0.0
            cost[i] = min(both, jump) - cost[j]
    cum = np.empty(nseg + 1)
    cum[0] = 0.0
    for i in range(nseg):
        if not np.isfinite(cost[i]):
            cost[i] = 0.0
        cum[i + 1] = cum[i] + cost[i]
    f_stop = _cumulative(s, ds, cost, cum, stop)
    for k in range(starts.size):
        out[k] = per_metre * (stop - starts[k]) + f_stop - _cumulative(s, ds, cost, cum,
                                                                        starts[k])
    return


@_leaf
def _cumulative(s, ds, cost, cum, x):
    """terminal_energy's F: the cost from the first vertex to ``x`` [J/kg]."""
    k = min(max(_right(s, x) - 1, 0), s.size - 1)
    seg = min(k, ds.size - 1)
    frac = 0.0
    if k < s.size - 1 and ds[seg] > 0:
        frac = min(max((x - s[k]) / ds[seg], 0.0), 1.0)
    return cum[k] + cost[seg] * frac


@_leaf
def _raster(s, z, slope, start, cell, count, levels, table, vertex_cum):
    """GroundProfile.raster(start, start + count*cell) cells: fills their range-maximum
    table ``table`` (levels, count) and the cumulative vertex count per cell
    ``vertex_cum`` (count + 1,). Cell edge k is ``start + cell * k`` (as numpy's
    ``start + cell * np.arange(count + 1)``); nothing is allocated."""
    # _height at each edge, its vertex found by one sweep (the edges increase)
    cells = table[0]
    i = _right(s, max(start, s[0])) - 1
    previous = 0.0
    for k in range(count + 1):
        q = max(start + cell * k, s[0])
        while i + 1 < s.size and s[i + 1] <= q:
            i += 1
        at = z[i] + slope[i] * (q - s[i])
        if k > 0:
            cells[k - 1] = max(previous, at)
        previous = at
    scale = 1.0 / cell
    vertex_cum[:] = 0
    last = start + cell * count
    for v in range(s.size):
        sv = s[v]
        vertex_cum[_cell(sv, start, cell, scale, count) + 1] += 1
        if sv < start or sv > last:
            continue
        k = min(max(int(np.floor((sv - start) * scale)), 0), count)
        while k > 0 and start + cell * k > sv:
            k -= 1
        while k < count and start + cell * (k + 1) <= sv:
            k += 1
        if k == count:
            cells[count - 1] = max(cells[count - 1], z[v])
            continue
        cells[k] = max(cells[k], z[v])
        if start + cell * k == sv and k > 0:
            cells[k - 1] = max(cells[k - 1], z[v])
    for k in range(count):
        vertex_cum[k + 1] += vertex_cum[k]
    width = 1
    for k in range(1, levels):  # (rows and a shifted view: the loop is vectorised)
        prev, row = table[k - 1], table[k]
        split = count - 2 * width + 1
        ahead = prev[width:width + split]
        for i in range(split):
            row[i] = max(prev[i], ahead[i])
        for i in range(split, count):
            row[i] = prev[i]
        width *= 2


#: The arrays of a batch's lattice (:func:`planners.lattice.build_tables` fills the
#: inputs; the kernels below fill the rest, an agent's nodes when it is first touched,
#: a step or a swing when it is first read). Shapes: A agents, Nn nodes, Ns steps,
#: Np swings, J step lengths, S = 2J - 1 strides, V profile vertices of the batch.
Lattice = namedtuple("Lattice", [
    # structure (planners.lattice.Structure)
    "node_depth", "node_m", "step_stance", "step_front", "step_j", "step_depth",
    "step_offset", "swing_back", "swing_front", "swing_stride", "swing_offset",
    "swing_strides", "pair_first", "pair_second", "pair_valid",
    # profiles (V,), bounds (A + 1,), the stance foot's shifted arc length (A,) [m]
    "prof_s", "prof_z", "bounds", "base",
    # per agent: grid, trailing foot, speed, normal step, energy per metre, neutral
    # step (A,); legs (A, 6); flat-ground caches (A, J), (A, 2, S, ...)
    "lo", "delta", "trailing", "speeds", "normal", "per_metre", "neutral_len", "legs",
    "flat_Ej", "flat_reach", "flat_ctrl", "flat_ok", "flat_slack", "basis", "influence",
    "fparams", "iparams", "weights",
    # filled when an agent is first touched: slopes (V,), edges (V,) and their count
    # (A,), leg constants (A, 7), support flags (A, Nn), the swing raster's start,
    # cell count and levels (A,), its table (A, levels * cells) and vertex counts
    # (A, cells + 1), whether built (A,)
    "ready", "slope", "edges", "edge_count", "consts", "support", "r_start", "r_count",
    "r_levels", "r_table", "r_vcum", "r_built",
    # tables (planners.lattice.StepTables) and what is evaluated
    "node_s", "node_z", "terminal", "far", "length", "rise", "En", "Ev", "Ej", "E",
    "reason", "cost", "progress", "step_done", "swing_ok", "controls", "rounds",
    "swing_done", "work",
    # per agent scratch of the §5.2 adjustment (A, 3, T), (A, 2)
    "scratch", "summit"])


@_jit
def prepare_agents(L, part, parts):
    """:func:`prepare` of every ``parts``-th agent from ``part``
    (:func:`planners.lattice.run_parts`)."""
    for a in range(part, L.base.size, parts):
        prepare(L, a)


@_inline
def prepare(L, a):
    """Agent ``a``'s slopes, edges, nodes (snapping and support), terminal energies and
    raster extent (before any entry of its lattice is evaluated)."""
    L.ready[a] = True
    fparams, iparams = L.fparams, L.iparams
    max_slope, tolerance, margin, lift = fparams[1], fparams[2], fparams[3], 0.75 * fparams[4]
    min_ratio, max_ratio, cell = fparams[7], fparams[8], fparams[12]
    snap, terminal_cost, levels = iparams[0] > 0, iparams[1] > 0, iparams[4]
    J = L.flat_Ej.shape[1]
    n = L.step_offset.size
    Nn = L.node_depth.size
    last0 = Nn - ((J - 1) * n + 1)  # first node of depth n
    b, e_ = L.bounds[a], L.bounds[a + 1]
    s, z = L.prof_s[b:e_], L.prof_z[b:e_]
    slope = L.slope[b:e_]
    m_v = s.size
    n_edges = 0
    for i in range(m_v - 1):
        d = s[i + 1] - s[i]
        slope[i] = 0.0
        if d > _VERTICAL:
            slope[i] = (z[i + 1] - z[i]) / d
        elif abs(z[i + 1] - z[i]) > tolerance:
            L.edges[b + n_edges] = s[i]
            n_edges += 1
    slope[m_v - 1] = 0.0
    L.edge_count[a] = n_edges
    edges = L.edges[b:b + n_edges]
    leg = L.legs[a]
    heel_off, toe_off, ankle = leg[3], leg[4], leg[5]
    constants = leg_constants(leg[0], leg[1], toe_off, ankle, fparams[5], fparams[6])
    for i in range(7):
        L.consts[a, i] = constants[i]
    b0 = L.base[a]
    lo_a, delta_a = L.lo[a], L.delta[a]
    lowest, highest = np.inf, -np.inf
    for v in range(Nn):
        depth = L.node_depth[v]
        x = L.trailing[a] if depth == -1 else max(depth, 0) * lo_a + L.node_m[v] * delta_a
        snapped, flags = 0.0, -1
        if snap and v >= 2:
            snapped, flags = _snap(b0 + x, 0.5 * delta_a, heel_off, toe_off, s, z, slope,
                                   edges, margin, tolerance, max_slope)
            x = snapped - b0
        L.node_s[a, v] = x
        L.node_z[a, v] = _height(s, z, slope, b0 + x)
        L.support[a, v] = 0
        if v >= 2:  # (_snap's flags where they are of this very foothold)
            L.support[a, v] = flags if flags >= 0 and b0 + x == snapped else _support(
                b0 + x, heel_off, toe_off, s, z, slope, edges, margin, tolerance, max_slope)
        lowest = min(lowest, b0 + x)
        highest = max(highest, b0 + x)
    far_a = -np.inf
    for v in range(last0, Nn):
        far_a = max(far_a, L.node_s[a, v])
    L.far[a] = far_a
    L.terminal[a, :] = 0.0
    if terminal_cost:
        lo_i = max(_right(s, b0 + L.trailing[a] - 2.0) - 1, 0)
        hi_i = min(_left(s, b0 + far_a + 2.0), m_v - 1)
        starts = np.empty(Nn - last0)
        for v in range(last0, Nn):
            starts[v - last0] = b0 + L.node_s[a, v]
        _terminal(s, z, lo_i, hi_i, starts, b0 + far_a, L.terminal[a, last0:], leg,
                  L.speeds[a], L.normal[a], L.per_metre[a], L.neutral_len[a], L.weights,
                  L.weights[6], L.weights[7], constants, lift, max_slope, min_ratio,
                  max_ratio)
    # the swing raster covers every curve of the lattice (built when a curve needs it)
    span = 2 * leg[2]
    start = np.floor((lowest - span) / cell) * cell
    count = max(1, int(np.ceil((highest + span - start) / cell)))
    L.r_start[a] = start
    L.r_count[a] = count
    L.r_levels[a] = min(levels, _bit_length(count))
    L.r_built[a] = False


@_inline
def eval_step(L, a, t):
    """Legality and energy of step ``t`` of agent ``a`` (once; the agent must be
    ready)."""
    _eval_step_arrays(a, t, L.E, L.Ej, L.En, L.Ev, L.base, L.bounds, L.consts, L.cost, L.delta,
                      L.far, L.flat_Ej, L.flat_reach, L.fparams, L.iparams, L.legs,
                      L.length, L.lo, L.node_s, L.node_z, L.normal, L.prof_s, L.prof_z,
                      L.progress, L.reason, L.rise, L.slope, L.speeds, L.step_depth,
                      L.step_done, L.step_front, L.step_j, L.step_offset, L.step_stance,
                      L.support, L.terminal, L.weights, L.work)


@_leaf
def _eval_step_arrays(a, t, L_E, L_Ej, L_En, L_Ev, L_base, L_bounds, L_consts, L_cost, L_delta,
                      L_far, L_flat_Ej, L_flat_reach, L_fparams, L_iparams, L_legs, L_length,
                      L_lo, L_node_s, L_node_z, L_normal, L_prof_s, L_prof_z, L_progress,
                      L_reason, L_rise, L_slope, L_speeds, L_step_depth, L_step_done,
                      L_step_front, L_step_j, L_step_offset, L_step_stance, L_support,
                      L_terminal, L_weights, L_work):
    """:func:`eval_step` on the Lattice's arrays (``L_<field>``: see the note at
    :data:`inline`)."""
    if not L_step_done[a, t]:  # one exit (see the note at inline)
        L_step_done[a, t] = True
        fparams = L_fparams
        max_rise = fparams[0]
        lift = 0.75 * fparams[4]
        n = L_step_offset.size
        b, e_ = L_bounds[a], L_bounds[a + 1]
        s, z, slope = L_prof_s[b:e_], L_prof_z[b:e_], L_slope[b:e_]
        b0 = L_base[a]
        leg = L_legs[a]
        ankle = leg[5]
        st_v, fr_v = L_step_stance[t], L_step_front[t]
        ss, fs = L_node_s[a, st_v], L_node_s[a, fr_v]
        zs, zf = L_node_z[a, st_v], L_node_z[a, fr_v]
        r = zf - zs
        length = fs - ss
        L_length[a, t], L_rise[a, t] = length, r
        final = L_iparams[1] > 0 and L_step_depth[t] == n
        L_progress[a, t] = L_far[a] - ss if final else length
        j = L_step_j[t]
        ej = L_flat_Ej[a, j]
        highest = _span(s, z, slope, b0 + ss, b0 + fs)[0]
        nominal = L_lo[a] + L_delta[a] * j
        level = r == 0 and highest == zs and abs(length - nominal) <= 1e-12
        support = L_support[a, fr_v]
        hopeless = support != 0 or abs(r) > max_rise
        reachable = L_flat_reach[a, j]
        if not level and not hopeless:
            c = L_consts[a]
            constants = (c[0], c[1], c[2], c[3], c[4], c[5], c[6])
            th, ca, reachable = key_frame(ss, zs, fs, zf, ss, highest + ankle + lift, leg[0],
                                          leg[1], leg[4], ankle, ankle + lift, constants)
            ej = L_weights[6] * th + L_weights[7] * ca
            L_work[a, 0] += 1
        en, ev, et = _energy(length, r, ej, L_speeds[a], L_normal[a], L_weights)
        if hopeless and not level:
            et = np.inf
        L_En[a, t], L_Ev[a, t], L_Ej[a, t], L_E[a, t] = en, ev, ej, et
        flags = support
        if abs(r) > max_rise:
            flags |= _STEP_HEIGHT
        if not reachable:
            flags |= _KNEE_REACH
        L_reason[a, t] = flags
        L_cost[a, t] = et + L_terminal[a, fr_v] if final else et
        L_work[a, 4] += 1


@_inline
def eval_swing(L, a, q):
    """Swing curve ``q`` of agent ``a``: taken from the flat-ground cache where it
    applies, else built by the §5.2 adjustment (once; the agent is prepared)."""
    _eval_swing_arrays(a, q, L.base, L.basis, L.bounds, L.controls, L.delta, L.flat_ctrl,
                       L.flat_ok, L.flat_slack, L.fparams, L.influence, L.iparams, L.legs,
                       L.lo, L.node_m, L.node_s, L.node_z, L.prof_s, L.prof_z, L.r_built,
                       L.r_count, L.r_levels, L.r_start, L.r_table, L.r_vcum, L.rounds,
                       L.slope, L.swing_back, L.swing_done, L.swing_front, L.swing_ok,
                       L.swing_stride, L.trailing, L.work, L.scratch, L.summit)


@_leaf
def _eval_swing_arrays(a, q, L_base, L_basis, L_bounds, L_controls, L_delta, L_flat_ctrl,
                       L_flat_ok, L_flat_slack, L_fparams, L_influence, L_iparams, L_legs, L_lo,
                       L_node_m, L_node_s, L_node_z, L_prof_s, L_prof_z, L_r_built, L_r_count,
                       L_r_levels, L_r_start, L_r_table, L_r_vcum, L_rounds, L_slope,
                       L_swing_back, L_swing_done, L_swing_front, L_swing_ok, L_swing_stride,
                       L_trailing, L_work, L_scratch, L_summit):
    """:func:`eval_swing` on the Lattice's arrays (``L_<field>``: see the note at
    :data:`inline`)."""
    if not L_swing_done[a, q]:  # one exit (see the note at inline)
        L_swing_done[a, q] = True
        fparams = L_fparams
        max_slope, cell = fparams[1], fparams[12]
        b, e_ = L_bounds[a], L_bounds[a + 1]
        s, z, slope = L_prof_s[b:e_], L_prof_z[b:e_], L_slope[b:e_]
        b0 = L_base[a]
        leg = L_legs[a]
        heel_off, toe_off, ankle = leg[3], leg[4], leg[5]
        lo_a, delta_a = L_lo[a], L_delta[a]
        bk, fr = L_swing_back[q], L_swing_front[q]
        start, end = b0 + L_node_s[a, bk], b0 + L_node_s[a, fr]
        z0, z1 = L_node_z[a, bk], L_node_z[a, fr]
        stride = L_swing_stride[q]
        if stride < 0:
            behind = (-L_trailing[a] - lo_a) / delta_a
            if (abs(behind - np.rint(behind)) < 1e-9 and behind > -0.5
                    and behind < fparams[9] + 0.5):
                stride = np.int64(np.rint(behind)) + L_node_m[fr]
        vertices = _left(s, end + toe_off) - _right(s, start - heel_off)
        grade = (z1 - z0) / (end - start)
        nominal = 2 * lo_a + max(stride, 0) * delta_a
        reused = False
        if (stride >= 0 and vertices == 0 and abs(grade) <= max_slope
                and abs(end - start - nominal) <= 1e-9):
            c = 0 if grade == 0 else 1
            if L_flat_ok[a, c, stride] and (abs(grade) * max(heel_off, toe_off)
                                            <= L_flat_slack[a, c, stride]):
                for i in range(4):
                    c0 = L_flat_ctrl[a, c, stride, i, 0]
                    L_controls[a, q, i, 1] = L_flat_ctrl[a, c, stride, i, 1] + (z0 + grade * c0)
                    L_controls[a, q, i, 0] = c0 + L_node_s[a, bk]
                L_rounds[a, q] = 0
                L_swing_ok[a, q] = True
                L_work[a, 2] += 1
                reused = True
        if not reused:
            count, levels = L_r_count[a], L_r_levels[a]
            table = L_r_table[a, :levels * count].reshape((levels, count))
            vertex_cum = L_r_vcum[a, :count + 1]
            if not L_r_built[a]:
                _raster(s, z, slope, L_r_start[a], cell, count, levels, table, vertex_cum)
                L_r_built[a] = True
            ctrl = L_controls[a, q]
            ok, used = adjust_one(start, z0, end, z1, heel_off, toe_off, ankle, leg[2],
                                  L_r_start[a], cell, table, vertex_cum, L_basis,
                                  L_influence, fparams[10], fparams[4], fparams[11],
                                  max_slope, L_iparams[3], ctrl, L_summit[a], L_scratch[a])
            for i in range(4):
                ctrl[i, 0] -= b0
            L_swing_ok[a, q] = ok
            L_rounds[a, q] = used
            L_work[a, 1] += 1
            L_work[a, 3] += used


@_inline
def step_legal(L, a, t):
    """Whether step ``t`` of agent ``a`` is legal (evaluated on first read)."""
    if not L.step_done[a, t]:
        eval_step(L, a, t)
    return L.reason[a, t] == 0


@_inline
def swing_legal(L, a, q):
    """Whether swing ``q`` of agent ``a`` clears the ground (built on first read)."""
    if not L.swing_done[a, q]:
        eval_swing(L, a, q)
    return L.swing_ok[a, q]


@_inline
def complete(L, a):
    """Every table entry of agent ``a`` a search or a diagnosis may read: with
    ``prune`` (iparams[2]) the steps whose stance foothold a legal sequence of steps
    reaches and the swings of pairs a legal sequence can use (the others stay
    unevaluated: illegal, E = +inf, ``Reason.UNREACHED``), else every step and the
    swings between supported footholds."""
    prune = L.iparams[2] > 0
    Nn = L.node_depth.size
    J = L.flat_Ej.shape[1]
    reach = np.zeros(Nn, dtype=np.bool_)
    reach[0] = True
    reach[1] = True
    for t in range(L.step_stance.size):  # steps are ordered by depth
        if prune and not reach[L.step_stance[t]]:
            continue
        if step_legal(L, a, t):
            reach[L.step_front[t]] = True
    for q in range(L.swing_back.size):
        bk, fr = L.swing_back[q], L.swing_front[q]
        if prune:
            through = False
            for jp in range(J):
                if (L.pair_valid[q, jp] and L.step_done[a, L.pair_first[q, jp]]
                        and L.reason[a, L.pair_first[q, jp]] == 0
                        and L.step_done[a, L.pair_second[q, jp]]
                        and L.reason[a, L.pair_second[q, jp]] == 0):
                    through = True
                    break
            if not (through and reach[bk]):
                continue
        elif L.support[a, fr] != 0 or L.support[a, bk] != 0:
            continue
        eval_swing(L, a, q)


@_jit
def complete_agents(L, agents, part, parts):
    """:func:`complete` of every ``parts``-th agent in ``agents`` from ``part``
    (:func:`planners.lattice.run_parts`)."""
    for i in range(part, agents.size, parts):
        complete(L, agents[i])


@_jit
def probe(step_done, reason, swing_done, swing_ok, step_off, swing_off, strides, J, a, q):
    """Legality of configuration ``q`` (n,) of agent ``a`` from what is evaluated: 1
    legal, 0 illegal, -1 an entry before the first illegal one is not evaluated yet
    (then :func:`config_legal`). Plain arrays: the searches' hot path."""
    m_prev = 0
    m_prev2 = 0
    j_prev = 0
    for k in range(q.size):
        step = step_off[k] + m_prev * J + q[k]
        if not step_done[a, step]:
            return -1
        if reason[a, step] != 0:
            return 0
        swing = swing_off[k] + m_prev2 * strides[k] + q[k] + (j_prev if k > 0 else 0)
        if not swing_done[a, swing]:
            return -1
        if not swing_ok[a, swing]:
            return 0
        if k > 0:
            m_prev2 += j_prev
        m_prev += q[k]
        j_prev = q[k]
    return 1


@nb.njit(cache=True, nogil=True, _nrt=False)
def efficiency_one(a, q, cost, progress, J, step_off):
    """The efficiency of configuration ``q`` (n,) for table row ``a`` (progress / energy,
    rounded to 1e-12), as :func:`planners.search.evaluate_one` gives it; no swing is read
    (it does not depend on them)."""
    m_prev = 0
    energy = 0.0
    length = 0.0
    for k in range(q.size):
        step = step_off[k] + m_prev * J + q[k]
        energy += cost[a, step]
        length += progress[a, step]
        m_prev += q[k]
    return np.rint(length / energy * 1e12) / 1e12


@_jit
def probe_efficiency(step_done, reason, swing_done, swing_ok, cost, progress, step_off,
                     swing_off, strides, J, a, q):
    """:func:`probe` and, where legal, the efficiency of :func:`config_efficiency`:
    (1 legal, 0 illegal, -1 not evaluated yet; efficiency)."""
    legal = probe(step_done, reason, swing_done, swing_ok, step_off, swing_off, strides, J,
                  a, q)
    if legal != 1:
        return legal, 0.0
    return 1, efficiency_one(a, q, cost, progress, J, step_off)


@_inline
def config_legal(L, a, q):
    """Legality of configuration ``q`` (n,) of agent ``a``, evaluating its steps and
    swings in order up to the first illegal one."""
    J = L.flat_Ej.shape[1]
    step_off, swing_off, strides = L.step_offset, L.swing_offset, L.swing_strides
    step_done, reason = L.step_done, L.reason
    swing_done, swing_ok = L.swing_done, L.swing_ok
    m_prev = 0
    m_prev2 = 0
    j_prev = 0
    legal = True
    for k in range(q.size):
        step = step_off[k] + m_prev * J + q[k]
        if not step_done[a, step]:
            eval_step(L, a, step)
        if reason[a, step] != 0:
            legal = False
            break
        swing = swing_off[k] + m_prev2 * strides[k] + q[k] + (j_prev if k > 0 else 0)
        if not swing_done[a, swing]:
            eval_swing(L, a, swing)
        if not swing_ok[a, swing]:
            legal = False
            break
        if k > 0:
            m_prev2 += j_prev
        m_prev += q[k]
        j_prev = q[k]
    return legal


@_inline
def config_efficiency(L, a, q):
    """Legality and efficiency of configuration ``q`` (n,) of agent ``a``: sum of
    ``progress`` over sum of ``cost``, rounded to 1e-12 as
    :meth:`~planners.lattice.StepTables.evaluate`; 0 where illegal (evaluated up to
    the first illegal step or swing)."""
    J = L.flat_Ej.shape[1]
    legal, eff = probe_efficiency(L.step_done, L.reason, L.swing_done, L.swing_ok, L.cost,
                                  L.progress, L.step_offset, L.swing_offset,
                                  L.swing_strides, J, a, q)
    if legal < 0:
        if config_legal(L, a, q):
            legal, eff = probe_efficiency(L.step_done, L.reason, L.swing_done, L.swing_ok,
                                          L.cost, L.progress, L.step_offset, L.swing_offset,
                                          L.swing_strides, J, a, q)
        else:
            legal, eff = 0, 0.0
    return legal == 1, eff


# The tables evaluated up front in one pass per agent (agents on every core): the searches
# that read most of the lattice (the DP of optimal and best_first_multistart's starts)
# spend less on this loop than on evaluating entry by entry (planners.lattice.EAGER).


@_jit
def build_agents(prof_s, prof_z, bounds, base, lo, delta, trailing, speeds, normal,
                 per_metre, neutral_len, legs, flat_Ej, flat_reach, flat_ctrl, flat_ok,
                 flat_slack, node_depth, node_m, step_stance, step_front, step_j,
                 step_depth, step_offset, swing_back, swing_front, swing_stride,
                 pair_first, pair_second, pair_valid, basis, influence, fparams, iparams,
                 weights, node_s, node_z, length, rise, En, Ev, Ej, E, reason, cost,
                 progress, terminal, far, swing_ok, controls, rounds, work, defer, pending,
                 r_start, r_count, r_levels, r_table, r_vcum, defer_steps, step_pending,
                 legal, cost_lb, slope_out, consts_out, part, parts):
    """Fill every table of every ``parts``-th agent from ``part`` (see
    :func:`planners.lattice.build_tables`, which runs it on every core through
    :func:`planners.lattice.run_parts`).

    Per agent a: its profile ``prof_s/prof_z[bounds[a]:bounds[a+1]]`` [m] (shifted:
    the stance foot at ``base[a]``), grid ``lo, delta`` [m], ``trailing`` [m], speed
    [m/s], normal-mode step [m] (0 without the term), neutral energy per metre and step
    [J/(kg m)], [m]; ``legs`` (A, 6): thigh, shank, foot_length, heel, toe, ankle [m];
    the per-leg flat caches (J,), (S, ...) for the two clearances (index 0 level,
    1 sloped). ``fparams``: max_step_rise, max_foot_slope, support_tolerance,
    edge_margin, swing_lift, pelvis_height_ratio, cos(pi - knee_max_flexion),
    min_step_ratio, max_step_ratio, intervals, clearance, max_swing_lift, cell.
    ``iparams``: snap, terminal_cost, prune, max_adjustments, table levels.
    ``weights``: alpha, beta, gamma, down_ratio, linear, frequency*alpha, c_thigh,
    c_calf. ``work`` (A, 5): key-frame solves, curves built, reused, adjustment rounds,
    steps evaluated. With ``defer`` (deferred swings) the curves that need the §5.2
    adjustment are left unbuilt and marked in ``pending`` (A, Np), and the agent's raster
    is stored (``r_start``, ``r_count``, ``r_levels`` (A,), ``r_table`` (A, levels *
    cells), ``r_vcum`` (A, cells + 1)) for :func:`build_swing` to build them where a
    search reads them (:func:`swing_at`).
    """
    for a in range(part, base.size, parts):
        _agent(a, prof_s, prof_z, bounds, base, lo, delta, trailing, speeds, normal, per_metre,
               neutral_len, legs, flat_Ej, flat_reach, flat_ctrl, flat_ok, flat_slack, node_depth,
               node_m, step_stance, step_front, step_j, step_depth, step_offset, swing_back,
               swing_front, swing_stride, pair_first, pair_second, pair_valid, basis, influence,
               fparams, iparams, weights, node_s, node_z, length, rise, En, Ev, Ej, E, reason, cost,
               progress, terminal, far, swing_ok, controls, rounds, work, defer, pending,
               r_start, r_count, r_levels, r_table, r_vcum, defer_steps, step_pending, legal,
               cost_lb, slope_out, consts_out)


@_jit
def _agent(a, prof_s, prof_z, bounds, base, lo, delta, trailing, speeds, normal,
                 per_metre, neutral_len, legs, flat_Ej, flat_reach, flat_ctrl, flat_ok,
                 flat_slack, node_depth, node_m, step_stance, step_front, step_j,
                 step_depth, step_offset, swing_back, swing_front, swing_stride,
                 pair_first, pair_second, pair_valid, basis, influence, fparams, iparams,
                 weights, node_s, node_z, length, rise, En, Ev, Ej, E, reason, cost,
                 progress, terminal, far, swing_ok, controls, rounds, work, defer, pending,
                 r_start_out, r_count_out, r_levels_out, r_table_out, r_vcum_out,
                 defer_steps, step_pending, legal, cost_lb, slope_out, consts_out):
    """Every table of agent ``a`` (see :func:`build_agents`)."""
    Nn = node_depth.size
    Ns = step_stance.size
    Np = swing_back.size
    n = step_offset.size
    J = flat_Ej.shape[1]
    max_rise, max_slope, tolerance, margin, lift = (fparams[0], fparams[1], fparams[2],
                                                   fparams[3], 0.75 * fparams[4])
    pelvis, cos_knee, min_ratio, max_ratio = fparams[5], fparams[6], fparams[7], fparams[8]
    intervals, clearance, max_lift, cell = fparams[9], fparams[10], fparams[11], fparams[12]
    snap, terminal_cost, prune = iparams[0] > 0, iparams[1] > 0, iparams[2] > 0
    max_adjustments, levels = iparams[3], iparams[4]
    c_thigh, c_calf = weights[6], weights[7]
    T = basis.shape[1]
    last0 = Nn - ((J - 1) * n + 1)  # first node of depth n
    s = prof_s[bounds[a]:bounds[a + 1]]
    z = prof_z[bounds[a]:bounds[a + 1]]
    m_v = s.size
    slope = np.zeros(m_v)
    n_edges = 0
    for i in range(m_v - 1):
        d = s[i + 1] - s[i]
        if d > _VERTICAL:
            slope[i] = (z[i + 1] - z[i]) / d
        elif abs(z[i + 1] - z[i]) > tolerance:
            n_edges += 1
    edges = np.empty(n_edges)
    e = 0
    for i in range(m_v - 1):
        if s[i + 1] - s[i] <= _VERTICAL and abs(z[i + 1] - z[i]) > tolerance:
            edges[e] = s[i]
            e += 1
    leg = legs[a]
    heel_off, toe_off, ankle = leg[3], leg[4], leg[5]
    constants = leg_constants(leg[0], leg[1], toe_off, ankle, pelvis, cos_knee)
    if defer_steps:  # what step_at needs to evaluate a deferred step
        slope_out[bounds[a]:bounds[a + 1]] = slope
        for i in range(7):
            consts_out[a, i] = constants[i]
    b0 = base[a]
    # nodes: footholds relative to the stance foot, heights, support
    support = np.zeros(Nn, dtype=np.int64)
    for v in range(Nn):
        depth = node_depth[v]
        x = trailing[a] if depth == -1 else max(depth, 0) * lo[a] + node_m[v] * delta[a]
        snapped, flags = 0.0, -1
        if snap and v >= 2:
            snapped, flags = _snap(b0 + x, 0.5 * delta[a], heel_off, toe_off, s, z, slope,
                                   edges, margin, tolerance, max_slope)
            x = snapped - b0
        node_s[a, v] = x
        node_z[a, v] = _height(s, z, slope, b0 + x)
        if v >= 2:  # (_snap's flags where they are of this very foothold)
            support[v] = flags if flags >= 0 and b0 + x == snapped else _support(
                b0 + x, heel_off, toe_off, s, z, slope, edges, margin, tolerance, max_slope)
    far_a = -np.inf
    for v in range(last0, Nn):
        far_a = max(far_a, node_s[a, v])
    far[a] = far_a
    # each node's profile look-ups (:func:`_span_from`)
    node_right = np.empty(Nn, dtype=np.int64)
    node_left = np.empty(Nn, dtype=np.int64)
    for v in range(Nn):
        x = b0 + node_s[a, v]
        node_right[v] = _right(s, max(x, s[0])) - 1
        node_left[v] = _left(s, x)
    if terminal_cost:
        lo_i = max(_right(s, b0 + trailing[a] - 2.0) - 1, 0)
        hi_i = min(_left(s, b0 + far_a + 2.0), m_v - 1)
        starts = np.empty(Nn - last0)
        for v in range(last0, Nn):
            starts[v - last0] = b0 + node_s[a, v]
        _terminal(s, z, lo_i, hi_i, starts, b0 + far_a, terminal[a, last0:], leg,
                  speeds[a], normal[a], per_metre[a], neutral_len[a], weights, c_thigh,
                  c_calf, constants, lift, max_slope, min_ratio, max_ratio)
    # steps: stance node -> front node; with ``prune`` only those whose stance foothold a
    # legal sequence of steps from the start reaches (the others are never used)
    reach = np.zeros(Nn, dtype=np.bool_)
    reach[0] = True
    reach[1] = True
    key_frames = 0
    evaluated = 0
    # the stance leg at K1 of each stance node (computed once, shared by its steps)
    k1_thigh = np.empty(Nn)
    k1_shank = np.empty(Nn)
    k1_ok = np.zeros(Nn, dtype=np.bool_)
    k1_done = np.zeros(Nn, dtype=np.bool_)
    # and the former stance leg at K1' of each front node above its stance node
    k4_thigh = np.empty(Nn)
    k4_shank = np.empty(Nn)
    k4_ok = np.zeros(Nn, dtype=np.bool_)
    k4_done = np.zeros(Nn, dtype=np.bool_)
    for t in range(Ns):  # steps are ordered by depth
        st_v, fr_v = step_stance[t], step_front[t]
        ss, fs = node_s[a, st_v], node_s[a, fr_v]
        zs, zf = node_z[a, st_v], node_z[a, fr_v]
        r = zf - zs
        L = fs - ss
        length[a, t], rise[a, t] = L, r
        final = terminal_cost and step_depth[t] == n
        progress[a, t] = far_a - ss if final else L
        ej = flat_Ej[a, step_j[t]]
        if prune and not reach[st_v]:
            En[a, t], Ev[a, t], _ = _energy(L, r, ej, speeds[a], normal[a], weights)
            Ej[a, t], E[a, t], cost[a, t] = ej, np.inf, np.inf
            reason[a, t] = _UNREACHED
            continue
        highest = _span_from(s, z, slope, b0 + ss, node_right[st_v], node_left[st_v],
                             b0 + fs, node_right[fr_v])[0]
        nominal = lo[a] + delta[a] * step_j[t]
        level = r == 0 and highest == zs and abs(L - nominal) <= 1e-12
        hopeless = support[fr_v] != 0 or abs(r) > max_rise
        reachable = flat_reach[a, step_j[t]]
        if defer_steps and not level and not hopeless:
            # deferred step: its key frames (Ej and the knee's reach) left to step_at;
            # a lower bound of its cost (Ej >= 0) for the bounded DP, and legal so far
            en, ev, et = _energy(L, r, 0.0, speeds[a], normal[a], weights)
            En[a, t], Ev[a, t], Ej[a, t], E[a, t] = en, ev, 0.0, np.inf
            reason[a, t] = 0
            reach[fr_v] = True
            cost[a, t] = np.inf
            cost_lb[a, t] = et + terminal[a, fr_v] if final else et
            step_pending[a, t] = True
            legal[a, t] = False
            continue
        evaluated += 1
        if not level and not hopeless:
            summit = highest + ankle + lift
            if not k1_done[st_v]:
                k1_thigh[st_v], k1_shank[st_v], k1_ok[st_v] = stance_leg(
                    ss, zs, leg[0], leg[1], ankle, constants)
                k1_done[st_v] = True
            zs_a, zf_a = zs + ankle, zf + ankle
            if zs_a <= zf_a:
                if not k4_done[fr_v]:
                    k4_thigh[fr_v], k4_shank[fr_v], k4_ok[fr_v] = next_swing_leg(
                        fs, zf_a, zf_a, leg[0], leg[1], ankle + lift, constants)
                    k4_done[fr_v] = True
                s4 = (k4_thigh[fr_v], k4_shank[fr_v], k4_ok[fr_v])
            else:
                s4 = next_swing_leg(fs, zf_a, zs_a, leg[0], leg[1], ankle + lift,
                                    constants)
            th, ca, reachable = key_frame_from(
                ss, zs, fs, zf, ss, summit, leg[0], leg[1], toe_off, ankle, constants,
                (k1_thigh[st_v], k1_shank[st_v], k1_ok[st_v]), s4)
            ej = c_thigh * th + c_calf * ca
            key_frames += 1
        en, ev, et = _energy(L, r, ej, speeds[a], normal[a], weights)
        if hopeless and not level:
            et = np.inf
        En[a, t], Ev[a, t], Ej[a, t], E[a, t] = en, ev, ej, et
        flags = support[fr_v]
        if abs(r) > max_rise:
            flags |= _STEP_HEIGHT
        if not reachable:
            flags |= _KNEE_REACH
        reason[a, t] = flags
        if flags == 0:
            reach[fr_v] = True
        cost[a, t] = et + terminal[a, fr_v] if final else et
        if defer_steps:
            cost_lb[a, t] = cost[a, t]
            legal[a, t] = flags == 0
    # swings: only pairs some legal sequence of steps can use
    behind = (-trailing[a] - lo[a]) / delta[a]
    on_grid = (abs(behind - np.rint(behind)) < 1e-9 and behind > -0.5
               and behind < intervals + 0.5)
    rest = np.zeros(Np, dtype=np.bool_)
    rest_lo, rest_hi = np.inf, -np.inf
    reused = 0
    for q in range(Np):
        rounds[a, q] = -1
        bk, fr = swing_back[q], swing_front[q]
        if prune:
            through = False
            for jp in range(J):
                if (pair_valid[q, jp] and reason[a, pair_first[q, jp]] == 0
                        and reason[a, pair_second[q, jp]] == 0):
                    through = True
                    break
            if not (through and reach[bk]):
                continue
        elif support[fr] != 0 or support[bk] != 0:
            continue
        start, end = b0 + node_s[a, bk], b0 + node_s[a, fr]
        z0, z1 = node_z[a, bk], node_z[a, fr]
        stride = swing_stride[q]
        if stride < 0 and on_grid:
            stride = np.int64(np.rint(behind)) + node_m[fr]
        vertices = _left(s, end + toe_off) - _right(s, start - heel_off)
        grade = (z1 - z0) / (end - start)
        nominal = 2 * lo[a] + max(stride, 0) * delta[a]
        flat = (stride >= 0 and vertices == 0 and abs(grade) <= max_slope
                and abs(end - start - nominal) <= 1e-9)
        if flat:
            c = 0 if grade == 0 else 1
            if flat_ok[a, c, stride] and (abs(grade) * max(heel_off, toe_off)
                                          <= flat_slack[a, c, stride]):
                for i in range(4):
                    c0 = flat_ctrl[a, c, stride, i, 0]
                    controls[a, q, i, 1] = flat_ctrl[a, c, stride, i, 1] + (z0 + grade
                                                                            * c0)
                    controls[a, q, i, 0] = c0 + node_s[a, bk]
                rounds[a, q] = 0
                swing_ok[a, q] = True
                reused += 1
                continue
        rest[q] = True
        rest_lo = min(rest_lo, start)
        rest_hi = max(rest_hi, end)
    built = 0
    adjustments = 0
    if rest_hi >= rest_lo:
        span = 2 * leg[2]
        r_start = np.floor((rest_lo - span) / cell) * cell
        count = max(1, int(np.ceil((rest_hi + span - r_start) / cell)))
        levels_a = min(levels, _bit_length(count))
        deferred = defer and count < r_vcum_out.shape[1] and (
            levels_a * count <= r_table_out.shape[1])
        if deferred:  # the raster kept for build_swing, the curves left to the searches
            table = r_table_out[a, :levels_a * count].reshape((levels_a, count))
            vertex_cum = r_vcum_out[a, :count + 1]
            r_start_out[a], r_count_out[a], r_levels_out[a] = r_start, count, levels_a
        else:
            table = np.empty((levels_a, count))
            vertex_cum = np.empty(count + 1, dtype=np.int64)
        _raster(s, z, slope, r_start, cell, count, levels_a, table, vertex_cum)
        if deferred:
            for q in range(Np):
                pending[a, q] = rest[q]
            rest[:] = False
        scratch = np.empty((3, T))
        summit = np.empty(2)
        for q in range(Np):
            if not rest[q]:
                continue
            bk, fr = swing_back[q], swing_front[q]
            ok, used = adjust_one(b0 + node_s[a, bk], node_z[a, bk], b0 + node_s[a, fr],
                                  node_z[a, fr], heel_off, toe_off, ankle, leg[2],
                                  r_start, cell, table, vertex_cum, basis, influence,
                                  clearance, fparams[4], max_lift, max_slope,
                                  max_adjustments, controls[a, q], summit, scratch)
            for i in range(4):
                controls[a, q, i, 0] -= b0
            swing_ok[a, q] = ok
            rounds[a, q] = used
            built += 1
            adjustments += used
    work[a, 0] = key_frames
    work[a, 4] = evaluated
    work[a, 1] = built
    work[a, 2] = reused
    work[a, 3] = adjustments


# Deferred swings: the curves of the up-front tables that need the §5.2 adjustment, built
# where a search first reads them. The searches' kernels read every swing through
# swing_at and the context tuple of StepTables.swings (the arrays below, in this order);
# both are compiled without numba's runtime, so a read passes its arrays without
# reference counting (with it, each read would take and release every array: ~0.6 us).
SWING_CONTEXT = ("pending", "swing_ok", "swing_done", "swing_back", "swing_front",
                 "node_s", "node_z", "base", "legs", "r_start", "r_count", "r_levels",
                 "r_table", "r_vcum", "basis", "influence", "fparams", "iparams",
                 "controls", "rounds", "work", "scratch", "summit")


@_leaf
def swing_at(sw, a, q):
    """Whether swing ``q`` of agent ``a`` clears the ground, from the context ``sw``
    (:data:`SWING_CONTEXT`): ``swing_ok``, its curve built first where it is pending."""
    if sw[0][a, q]:
        build_swing(sw, a, q)
    return sw[1][a, q]


@_leaf
def build_swing(sw, a, q):
    """Build the pending swing curve ``q`` of agent ``a`` by the §5.2 adjustment, as
    :func:`build_agents` builds it up front (the same raster and arguments), and count
    it."""
    (pending, swing_ok, swing_done, swing_back, swing_front, node_s, node_z, base, legs,
     r_start, r_count, r_levels, r_table, r_vcum, basis, influence, fparams, iparams,
     controls, rounds, work, scratch, summit) = sw
    pending[a, q] = False
    leg = legs[a]
    b0 = base[a]
    bk, fr = swing_back[q], swing_front[q]
    count, levels = r_count[a], r_levels[a]
    table = r_table[a, :levels * count].reshape((levels, count))
    ctrl = controls[a, q]
    ok, used = adjust_one(b0 + node_s[a, bk], node_z[a, bk], b0 + node_s[a, fr],
                          node_z[a, fr], leg[3], leg[4], leg[5], leg[2], r_start[a],
                          fparams[12], table, r_vcum[a, :count + 1], basis, influence,
                          fparams[10], fparams[4], fparams[11], fparams[1], iparams[3], ctrl,
                          summit[a], scratch[a])
    for i in range(4):
        ctrl[i, 0] -= b0
    swing_ok[a, q] = ok
    rounds[a, q] = used
    swing_done[a, q] = True
    work[a, 1] += 1
    work[a, 3] += used


@_jit
def build_pending(sw, agents, part, parts):
    """Every pending swing of every ``parts``-th agent in ``agents`` from ``part``
    (:func:`planners.lattice.run_parts`)."""
    for i in range(part, agents.size, parts):
        a = agents[i]
        for q in range(sw[0].shape[1]):
            if sw[0][a, q]:
                build_swing(sw, a, q)


@_jit
def _bit_length(c):
    k = 0
    while c > 0:
        c >>= 1
        k += 1
    return k


# Deferred steps: the steps of the up-front tables that need key frames (neither level nor
# hopeless), evaluated where a search first reads them. ``cost_lb`` holds a lower bound of
# each step's cost (its Eq. 4 energy with Ej = 0: Ej sums joint rotations, never
# negative; the exact cost where evaluated), for the bounded DP (planners.dp.settle). The
# searches read a step's legality through step_at and the context tuple of
# StepTables.steps (these arrays, in this order), compiled without numba's runtime.
STEP_CONTEXT = ("step_pending", "legal", "cost_lb", "prof_s", "prof_z", "bounds", "slope",
                "base", "legs", "consts", "node_s", "node_z", "step_stance", "step_front",
                "step_depth", "length", "rise", "terminal", "fparams", "iparams", "weights",
                "speeds", "normal", "Ej", "E", "reason", "cost", "work", "leg_cache",
                "leg_done")


@_leaf
def step_at(sp, a, t):
    """Whether step ``t`` of agent ``a`` is legal, from the context ``sp``
    (:data:`STEP_CONTEXT`): ``legal``, the step evaluated first where it is pending."""
    if sp[0][a, t]:
        eval_pending_step(sp, a, t)
    return sp[1][a, t]


@_leaf
def eval_pending_step(sp, a, t):
    """Evaluate the deferred step ``t`` of agent ``a`` as :func:`build_agents` evaluates
    it up front (the same arithmetic: :func:`key_frame` is :func:`key_frame_from` of
    its stance and next-swing legs, :func:`_span` is :func:`_span_from`), and count
    it. A deferred step is neither level nor hopeless (support and rise are legal)."""
    (pending, legal, cost_lb, prof_s, prof_z, bounds, slope, base, legs, consts, node_s,
     node_z, step_stance, step_front, step_depth, length, rise, terminal, fparams,
     iparams, weights, speeds, normal, Ej, E, reason, cost, work, leg_cache, leg_done) = sp
    pending[a, t] = False
    lift = 0.75 * fparams[4]
    b, e_ = bounds[a], bounds[a + 1]
    s, z, sl = prof_s[b:e_], prof_z[b:e_], slope[b:e_]
    b0 = base[a]
    leg = legs[a]
    ankle = leg[5]
    st_v, fr_v = step_stance[t], step_front[t]
    ss, fs = node_s[a, st_v], node_s[a, fr_v]
    zs, zf = node_z[a, st_v], node_z[a, fr_v]
    highest = _span(s, z, sl, b0 + ss, b0 + fs)[0]
    c = consts[a]
    constants = (c[0], c[1], c[2], c[3], c[4], c[5], c[6])
    # key_frame, its stance leg at K1 kept per stance foothold and its next swing leg at
    # K1' per landing foothold where that is the higher one (as build_agents shares them)
    cache = leg_cache[a]
    if not leg_done[a, st_v, 0]:
        cache[st_v, 0], cache[st_v, 1], ok1 = stance_leg(ss, zs, leg[0], leg[1], ankle,
                                                         constants)
        cache[st_v, 2] = 1.0 if ok1 else 0.0
        leg_done[a, st_v, 0] = True
    s1 = (cache[st_v, 0], cache[st_v, 1], cache[st_v, 2] > 0)
    zs_a, zf_a = zs + ankle, zf + ankle
    if zs_a <= zf_a:
        if not leg_done[a, fr_v, 1]:
            cache[fr_v, 3], cache[fr_v, 4], ok4 = next_swing_leg(
                fs, zf_a, zf_a, leg[0], leg[1], ankle + lift, constants)
            cache[fr_v, 5] = 1.0 if ok4 else 0.0
            leg_done[a, fr_v, 1] = True
        s4 = (cache[fr_v, 3], cache[fr_v, 4], cache[fr_v, 5] > 0)
    else:
        s4 = next_swing_leg(fs, zf_a, zs_a, leg[0], leg[1], ankle + lift, constants)
    th, ca, reachable = key_frame_from(ss, zs, fs, zf, ss, highest + ankle + lift, leg[0],
                                       leg[1], leg[4], ankle, constants, s1, s4)
    ej = weights[6] * th + weights[7] * ca
    _, _, et = _energy(length[a, t], rise[a, t], ej, speeds[a], normal[a], weights)
    Ej[a, t], E[a, t] = ej, et
    reason[a, t] = 0 if reachable else _KNEE_REACH
    legal[a, t] = reachable
    final = iparams[1] > 0 and step_depth[t] == step_depth[step_depth.size - 1]
    cost[a, t] = et + terminal[a, fr_v] if final else et
    cost_lb[a, t] = cost[a, t]
    work[a, 0] += 1
    work[a, 4] += 1


@_jit
def build_pending_steps(sp, agents, part, parts):
    """Every deferred step of every ``parts``-th agent in ``agents`` from ``part``
    (:func:`planners.lattice.run_parts`)."""
    for i in range(part, agents.size, parts):
        a = agents[i]
        for t in range(sp[0].shape[1]):
            if sp[0][a, t]:
                eval_pending_step(sp, a, t)
