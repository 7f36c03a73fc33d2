"""Dynamic programming over the foothold lattice: the cheapest legal configuration.

The state before step k is (m_{k-1}, j_{k-1}): the lattice index of the stance foothold
and the previous step (the swing curve of step k depends on f_{k-2} = m_{k-1} - j_{k-1}).
Step costs are additive, so one pass per depth over (state, j_k) gives the exact minimum
for all agents at once.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numba as nb
import numpy as np

from planners.lattice import StepTables, Structure, run_parts
from planners.lattice_kernel import eval_pending_step, swing_at

__all__ = ["DPWork", "cheapest", "dp_one", "dp_scratch", "settle", "settle_scratch"]

#: Slack of the bounded DP's test (:func:`settle`) [row units]: far above the rounding of
#: sums of a few rows, far below the differences that decide anything.
SETTLE_SLACK = 1e-7
#: Rounds of :func:`settle` that evaluate the least path over the footholds before the
#: bound is applied (each tightens the values and may give a legal configuration's sum).
SETTLE_ROUNDS = 2


class DPWork(NamedTuple):
    """Work of one DP pass, per agent (B,) each, counted in the pass.

    ``states``: reachable (m_{k-1}, j_{k-1}) states expanded over all depths (a state no
    legal sequence of steps reaches is skipped); ``transitions``: their state -> j_k
    transitions (each step's legality looked up, then the swing of every legal one). Both
    summed over the passes run (:func:`dp_one`: the pass taking every swing as legal,
    the swings of its configuration checked, one transition each, and where one is
    illegal the pass reading the swings).
    """

    states: np.ndarray
    transitions: np.ndarray


@lru_cache(maxsize=16)
def _depth_indices(struct: Structure):
    """Per depth: step and swing indices (M, P, J) over (m_{k-1}, j_{k-1}, j_k), validity."""
    J, out = struct.J, []
    for k in range(1, struct.n + 1):
        M = (J - 1) * (k - 1) + 1
        P = 1 if k == 1 else J
        m, jp, j = np.meshgrid(np.arange(M), np.arange(P), np.arange(J), indexing="ij")
        step = struct.step_offset[k - 1] + m * J + j
        if k == 1:
            swing = struct.swing_offset[0] + j
            valid = np.ones(m.shape, dtype=bool)
        else:
            m2 = m - jp  # lattice index of f_{k-2}; states outside its range are impossible
            valid = (m2 >= 0) & (m2 <= (J - 1) * (k - 2))
            m2 = np.clip(m2, 0, (J - 1) * (k - 2))
            swing = struct.swing_offset[k - 1] + m2 * struct.swing_strides[k - 1] + jp + j
        mm, jj = np.meshgrid(np.arange(M), np.arange(J), indexing="ij")
        out.append((step, swing, valid, mm + jj, jj))
    return out


def cheapest(tables: StepTables, step_cost: np.ndarray, agents: np.ndarray | None = None):
    """The legal configuration of least total ``step_cost`` for each agent.

    Parameters
    ----------
    tables : StepTables
    step_cost : ndarray, shape (B, Ns)
        Additive cost of every step entry, for the agents ``agents``.
    agents : ndarray of int, shape (B,), optional
        Rows of ``tables`` (default: all).

    Returns
    -------
    configs : ndarray of int, shape (B, n)
    found : ndarray of bool, shape (B,)
    work : DPWork
        States and transitions the pass went through, per agent.
    """
    st = tables.struct
    J, n = st.J, st.n
    agents = np.arange(tables.neutral.size) if agents is None else agents
    B = agents.size
    step_cost = np.ascontiguousarray(np.round(step_cost, 10))  # ties broken alike
    configs = np.zeros((B, n), dtype=np.int64)
    found = np.zeros(B, dtype=np.bool_)
    states = np.zeros(B, dtype=np.int64)
    transitions = np.zeros(B, dtype=np.int64)
    run_parts(_cheapest, B, tables.step_legal, tables.swings, step_cost,
              agents.astype(np.int64), J, st._step_offsets, st._swing_offsets,
              st._swing_strides, configs, found, states, transitions)
    return configs, found, DPWork(states, transitions)


@nb.njit(cache=True, nogil=True)
def _cheapest(step_legal, sw, step_cost, agents, J, step_off, swing_off, strides,
              configs, found, states, transitions, part, parts):
    """The DP of :func:`cheapest` (:func:`dp_one`) for every ``parts``-th agent from
    ``part`` (:func:`planners.lattice.run_parts`)."""
    B, n = configs.shape
    value, new, choice = dp_scratch(J, n)
    for b in range(part, B, parts):
        found[b], states[b], transitions[b] = dp_one(
            step_legal, sw, step_cost[b], agents[b], J, step_off, swing_off, strides,
            value, new, choice, configs[b])


@nb.njit(cache=True, nogil=True)
def dp_scratch(J, n):
    """The work arrays of :func:`dp_one` for ``J`` step lengths and horizon ``n``."""
    M_last = (J - 1) * n + 1
    return (np.empty((M_last, J)), np.empty((M_last, J)),
            np.zeros((n, M_last, J), dtype=np.int64))


@nb.njit(cache=True, nogil=True, _nrt=False)
def _least_after(value, m, cost, lo, hi, last_t, last_jp):
    """The predecessor j_{k-1} in ``lo..hi-1`` of least total ``value[m, j_{k-1}] + cost``
    after (``last_t``, ``last_jp``) in the order (total, j_{k-1}): (total, j_{k-1}), or
    (+inf, -1) where none is left (infinite and NaN totals are never taken). Compiled
    without numba's runtime (no reference counting per call)."""
    pick = -1
    low = np.inf
    for jp in range(lo, hi):
        v = value[m, jp]
        if not v < np.inf:
            continue
        t = v + cost
        if t < last_t or (t == last_t and jp <= last_jp):
            continue  # tried
        if t < low:
            low = t
            pick = jp
    return low, pick


#: Relative distance above which two values cannot give the same rounded total with
#: any cost: fl(v + c) = fl(V + c) needs v - V <= ulp(fl(V + c)) <= 2**-52 |V + c| (1 +
#: 2**-53) (or the least subnormal; hence + 1e-300); 4.5e-16 leaves a factor of two.
_TIE = 4.5e-16


@nb.njit(cache=True, nogil=True, _nrt=False)
def _least_value(value, m, lo, hi):
    """Over ``value[m, lo:hi]``: the least finite value V, the first j_{k-1} with it, and
    the least ``v - V`` of the finite values before that one (+inf where none).
    Rounding is monotone, so V + c is the least total of any cost c, and where ``v - V``
    exceeds :data:`_TIE` (|V| + |c|) no earlier predecessor ties with it: the first
    j_{k-1} is then :func:`_least_after`'s first pick (a NaN or infinite total falls
    back to it)."""
    least = np.inf
    first = -1
    for jp in range(lo, hi):
        v = value[m, jp]
        if v < least:
            least = v
            first = jp
    gap = np.inf
    for jp in range(lo, max(first, lo)):
        v = value[m, jp]
        if v < np.inf:
            gap = min(gap, v - least)
    return least, first, gap


@nb.njit(cache=True, nogil=True)
def dp_one(step_legal, sw, step_cost, a, J, step_off, swing_off, strides, value, new,
           choice, config):
    """The DP of :func:`cheapest` for table row ``a`` and its step costs ``step_cost``
    (Ns,) into ``config`` (n,): the configuration :func:`_dp_pass` finds reading the
    swings, found with as few swings read as it can.

    First a pass that takes every swing as legal (a lower bound of every state's value;
    no swing read), then the swings of the configuration it found (``swing_at``, up to
    the first illegal one). Where they are all legal, that configuration is the one the
    pass reading the swings gives, ties included: along its path the two passes have the
    same values and choices (every other predecessor's total is at least its lower bound,
    so none comes first in the order (total, j_{k-1})), and no final state before it in
    (m, j) order can have the same least total (its lower bound would have come first).
    Only where one of them is illegal is the pass reading the swings run. Where the first
    pass finds none, neither would the second. ``value``, ``new``, ``choice``:
    :func:`dp_scratch`. Returns (found, states, transitions): the work of the passes run,
    the swings of the check counted as transitions."""
    ok, states, transitions = _dp_pass(step_legal, sw, step_cost, a, J, step_off,
                                       swing_off, strides, value, new, choice, config,
                                       False)
    if not ok:
        return ok, states, transitions
    m_prev2, j_prev = 0, 0
    legal = True
    for k in range(config.size):  # (:func:`_swings_legal`, counting the look-ups)
        swing = swing_off[k] + m_prev2 * strides[k] + config[k] + (j_prev if k > 0 else 0)
        transitions += 1
        if not swing_at(sw, a, swing):
            legal = False
            break
        if k > 0:
            m_prev2 += j_prev
        j_prev = config[k]
    if legal:
        return ok, states, transitions
    ok, more_states, more_transitions = _dp_pass(step_legal, sw, step_cost, a, J, step_off,
                                                 swing_off, strides, value, new, choice,
                                                 config, True)
    return ok, states + more_states, transitions + more_transitions


@nb.njit(cache=True, nogil=True)
def _dp_pass(step_legal, sw, step_cost, a, J, step_off, swing_off, strides, value, new,
             choice, config, swings):
    """One DP pass for table row ``a`` and its step costs ``step_cost``
    (Ns,): per depth k, the value of each state (m_{k-1}, j_{k-1}) plus each step j_k, the
    least over j_{k-1} of a legal swing (the first on ties), then the way back from the
    least final state (the first in (m, j) order) into ``config`` (n,). States of
    infinite value (no legal way to them) are skipped: they cannot lower any value.
    With ``swings`` False every swing is taken as legal (none is read).

    Only the swings that decide the result are read (``sw``:
    :func:`~planners.lattice_kernel.swing_at`, which builds a deferred curve on first
    read): below the last depth, a step's predecessors in order of total (then of
    j_{k-1}) up to the first whose swing is legal, which is the least; at the last depth,
    where only the least final state is used, the candidates (total, m, j, j_{k-1}) of
    every final state in that order up to the first legal one. That is the least final
    state and its least legal predecessor, the first on ties, as reading every swing
    gives. ``value``, ``new``, ``choice``: :func:`dp_scratch`. Returns (found, states,
    transitions)."""
    n = config.size
    M_last = (J - 1) * n + 1
    states = 0
    transitions = 0
    value[0, 0] = 0.0
    for k in range(1, n + 1):
        M = (J - 1) * (k - 1) + 1
        P = 1 if k == 1 else J
        last = k == n
        new[:M + J - 1, :] = np.inf
        choice[k - 1, :M + J - 1, :] = 0
        for m in range(M):
            reachable = 0  # states (m, jp) of this depth some legal sequence reaches
            for jp in range(P):
                if value[m, jp] < np.inf:
                    reachable += 1
            states += reachable
            if reachable == 0:
                continue  # new[m + j, j] stays +inf
            # the predecessors j_{k-1} whose f_{k-2} = m - j_{k-1} lies in its depth
            lo = 0 if k == 1 else max(m - (J - 1) * (k - 2), 0)
            hi = 1 if k == 1 else min(P, m + 1)
            # the least finite value over them, the first predecessor with it, and how
            # far above it the values of the predecessors before that one lie
            least, first, gap = _least_value(value, m, lo, hi)
            for j in range(J):
                transitions += reachable
                step = step_off[k - 1] + m * J + j
                if not step_legal[a, step]:
                    continue
                cost = step_cost[step]
                swing0 = swing_off[0] + j if k == 1 else swing_off[k - 1] + j
                last_t, last_jp = -np.inf, -1  # the last predecessor tried
                while True:  # the least total not tried yet (the first on ties)
                    low = least + cost
                    if last_jp < 0 and low < np.inf and gap > (
                            _TIE * (abs(least) + abs(cost)) + 1e-300):
                        pick = first  # (what _least_after finds: see _least_value)
                    else:
                        low, pick = _least_after(value, m, cost, lo, hi, last_t, last_jp)
                    if pick < 0 or last or not swings:  # (last depth: the least,
                        break  # its swing unread)
                    swing = swing0 if k == 1 else swing0 + (m - pick) * strides[k - 1] + pick
                    if swing_at(sw, a, swing):
                        break
                    last_t, last_jp = low, pick
                new[m + j, j] = low
                choice[k - 1, m + j, j] = max(pick, 0)
        if not last:
            M_next = M + J - 1
            value[:M_next, :] = new[:M_next, :]
    # the least final candidate (total, m, j, then j_{n-1}) whose swing is legal
    k = n
    M = (J - 1) * (k - 1) + 1
    while True:
        best = np.inf
        last_m, last_j = 0, 0
        for m in range(M_last):
            for j in range(J):
                if new[m, j] < best:
                    best = new[m, j]
                    last_m, last_j = m, j
        if not best < np.inf:
            break
        m, j = last_m - last_j, last_j
        jp = choice[k - 1, last_m, last_j]
        swing = (swing_off[0] + j if k == 1
                 else swing_off[k - 1] + j + (m - jp) * strides[k - 1] + jp)
        if not swings or swing_at(sw, a, swing):
            break
        # this state's next predecessor (the state keeps its place in (m, j) order)
        lo = 0 if k == 1 else max(m - (J - 1) * (k - 2), 0)
        hi = 1 if k == 1 else min(J, m + 1)
        low, pick = _least_after(value, m, step_cost[step_off[k - 1] + m * J + j], lo, hi,
                                 best, jp)
        new[last_m, last_j] = low
        choice[k - 1, last_m, last_j] = max(pick, 0)
    if not best < np.inf:
        last_m, last_j = 0, 0
    m_cur, j_cur = last_m, last_j
    for k in range(n, 0, -1):
        config[k - 1] = j_cur
        jp = choice[k - 1, m_cur, j_cur]
        m_cur, j_cur = m_cur - j_cur, jp
    return best < np.inf, states, transitions


@nb.njit(cache=True, nogil=True)
def settle_scratch(Nn, n):
    """The work arrays of :func:`settle`: node values forward and backward (Nn,), the
    step into each node (Nn,), a configuration and its steps (n,)."""
    return (np.empty(Nn), np.empty(Nn), np.zeros(Nn, dtype=np.int64),
            np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64))


@nb.njit(cache=True, nogil=True, _nrt=False)
def _swings_legal(sw, a, q, swing_off, strides):
    """Whether every swing of configuration ``q`` (n,) of agent ``a`` is legal (read
    through :func:`~planners.lattice_kernel.swing_at`, up to the first illegal one)."""
    m_prev2, j_prev = 0, 0
    ok = True
    for k in range(q.size):
        swing = swing_off[k] + m_prev2 * strides[k] + q[k] + (j_prev if k > 0 else 0)
        if ok and not swing_at(sw, a, swing):
            ok = False
        if k > 0:
            m_prev2 += j_prev
        j_prev = q[k]
    return ok


@nb.njit(cache=True, nogil=True, _nrt=False)
def _row_of(mode, centre, lam, j, c, progress):
    """A DP row entry of a step of cost ``c``: mode 0 the nearest-legal criterion
    ``|j - centre| + 1e-7 c``, mode 1 Dinkelbach's ``c - lam progress``, rounded to 1e-10
    as the callers round them (non-decreasing in ``c``)."""
    if mode == 0:
        return np.rint((abs(j - centre) + 1e-7 * c) * 1e10) / 1e10
    return np.rint((c - lam * progress) * 1e10) / 1e10


@nb.njit(cache=True, nogil=True)
def settle(sp, sw, a, row, mode, centre, lam, step_j, progress, J, step_off, swing_off,
           strides, ub, F, H, pred, q, path):
    """Evaluate the deferred steps of agent ``a`` that the next :func:`dp_one` pass over
    ``row`` (Ns,) may use, so that the pass over the evaluated steps alone (a deferred
    step is not legal) gives the result of a pass over every step.

    ``row`` holds the pass's entries of the evaluated steps (:func:`_row_of` of their
    cost); a deferred step gets the entry of its cost's lower bound (``cost_lb``) and is
    taken as legal, an illegal step +inf. Over the footholds alone (no swings: a lower
    bound of every configuration), the least path is found forward (``F``); up to
    :data:`SETTLE_ROUNDS` times its deferred steps are evaluated and the values found
    again from the shallowest depth that changed. Where a path so evaluated is legal
    (steps and swings) its sum, in the DP's order, bounds the pass's least total from
    above, as does ``ub`` (the sum of a legal configuration, or +inf). Then every
    deferred step whose least path through it (``F`` to its stance, its entry, ``H``
    from its landing to the end) is within :data:`SETTLE_SLACK` of that bound is
    evaluated: each step left lies on no configuration of the least total nor on any
    way to a state of one, so the pass's values, ties and result are those of a pass
    over every step. ``sp``: :attr:`~planners.lattice.StepTables.steps`; ``F``, ``H``,
    ``pred``, ``q``, ``path``: :func:`settle_scratch`. Updates ``row``.
    """
    pending, legal, cost_lb = sp[0], sp[1], sp[2]
    step_stance, step_front, cost = sp[12], sp[13], sp[26]
    Ns = row.size
    Nn = F.size
    n = q.size
    deferred = False
    for t in range(Ns):  # (an illegal step's entry: +inf, which dp_one never reads)
        if pending[a, t]:
            row[t] = _row_of(mode, centre, lam, step_j[t], cost_lb[a, t], progress[a, t])
            deferred = True
        elif not legal[a, t]:
            row[t] = np.inf
    if not deferred:
        return
    last0 = Nn - ((J - 1) * n + 1)
    F[:] = np.inf
    F[1] = 0.0
    first = 0  # the depth (0-based) from which the values must be found again
    for _ in range(SETTLE_ROUNDS + 1):
        F[step_front[step_off[first]]:] = np.inf  # the nodes of that depth and deeper
        for t in range(step_off[first], Ns):  # steps are ordered by depth
            v = F[step_stance[t]] + row[t]
            fr = step_front[t]
            if v < F[fr]:
                F[fr] = v
                pred[fr] = t
        end = -1
        best = np.inf
        for v in range(last0, Nn):
            if F[v] < best:
                best, end = F[v], v
        if end < 0:
            return  # no configuration is legal even with every deferred step legal
        if _ == SETTLE_ROUNDS:
            break
        # the least path: its deferred steps evaluated; where it is then legal, its sum
        # (in the DP's order) bounds the least total from above
        first = n
        v, k = end, n
        while v != 1:
            t = pred[v]
            k -= 1
            path[k] = t
            q[k] = step_j[t]
            if pending[a, t]:
                eval_pending_step(sp, a, t)
                row[t] = (_row_of(mode, centre, lam, step_j[t], cost[a, t], progress[a, t])
                          if legal[a, t] else np.inf)
                first = k
            v = step_stance[t]
        total = 0.0
        for k in range(n):
            total = total + row[path[k]]
        if total < ub and _swings_legal(sw, a, q, swing_off, strides):
            ub = total
        if first == n:
            break  # the least path was evaluated: the values stand
    H[:] = np.inf
    H[last0:] = 0.0
    for t in range(Ns - 1, -1, -1):
        v = row[t] + H[step_front[t]]
        st = step_stance[t]
        if v < H[st]:
            H[st] = v
    limit = ub + SETTLE_SLACK * (1.0 + abs(ub))
    for t in range(Ns):
        if pending[a, t]:
            through = F[step_stance[t]] + row[t] + H[step_front[t]]
            if through <= limit and through < np.inf:
                eval_pending_step(sp, a, t)
                row[t] = (_row_of(mode, centre, lam, step_j[t], cost[a, t], progress[a, t])
                          if legal[a, t] else np.inf)
