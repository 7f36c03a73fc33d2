"""``fixed``'s dead ends (:func:`planners.fixed._dead_ends`), evaluated lazily, give what
the step-by-step pass and depth-first backtracking give over the complete table: the
pass's configuration and candidates looked up, then the first legal configuration in the
agent's preference order (of all configurations whose every step and swing is legal in
the complete table, the least by (rank of j_1, rank of j_2, ...)) with the backtracking's
step decisions and candidates; and they evaluate less of the table."""

import numba as nb
import numpy as np

from planners.fixed import BACKTRACK_BUDGET, _complete_legal, _dead_ends
from planners.lattice import build_tables
from planners.plan import _default_config
from tests.planners.test_diagnose import _walls_batch


def _tables(complete: bool):
    profiles, legs, speeds, trailing = _walls_batch()
    tables = build_tables(profiles, legs, speeds, trailing, np.zeros(len(profiles)),
                          _default_config(), lazy=True)
    tables.prepare()
    if complete:
        tables.complete()
    return tables


def _reference(tables, a: int, order: list[int]):
    """The pass and the backtracking over the complete table of agent ``a``, read
    entry by entry: (pass configuration, pass candidates, whether the pass met a depth
    without a legal step, configuration or None, step decisions opened, candidates
    looked up)."""
    st = tables.struct
    n, J = st.n, st.J
    legal, swing_ok = tables.step_legal[a], tables.swing_ok[a]

    def ok(prefix):  # the last step and swing of configuration ``prefix``
        steps, swings = st.indices(np.array(prefix + [0] * (n - len(prefix))))
        k = len(prefix) - 1
        return bool(legal[steps[k]] and swing_ok[swings[k]])

    config, checks, stuck = [], 0, False
    for _ in range(n):
        tried = [c for c in range(J) if ok(config + [order[c]])]
        checks += tried[0] + 1 if tried else J
        stuck |= not tried
        config.append(order[tried[0]] if tried else order[0])
    prefix, stack, looked, pushes, budget = [], [iter(order)], 0, 0, BACKTRACK_BUDGET
    while stack and budget > 0:
        choice = next(stack[-1], None)
        if choice is None:
            stack.pop()
            if prefix:
                prefix.pop()
            continue
        budget -= 1
        looked += 1
        if ok(prefix + [choice]):
            prefix.append(choice)
            if len(prefix) == n:
                return config, checks, stuck, prefix, pushes, looked
            stack.append(iter(order))
            pushes += 1
    return config, checks, stuck, None, pushes, looked


def test_dead_ends_lazily_as_over_the_complete_table():
    lazy, full = _tables(False), _tables(True)
    st = full.struct
    A = full.neutral.size
    rng = np.random.default_rng(3)
    order = np.array([rng.permutation(st.J) for _ in range(A)], dtype=np.int64)
    configs = np.zeros((A, st.n), dtype=np.int64)
    found = np.zeros(A, dtype=np.bool_)
    expanded = np.full(A, st.n, dtype=np.int64)
    checks = np.zeros(A, dtype=np.int64)
    _dead_ends(full.lattice, np.arange(A), order, configs, found, expanded, checks, True,
               0, 1)  # (a complete table: evaluates nothing more)
    assert (full.lattice.work == _tables(True).lattice.work).all()
    lazy_out = [np.zeros((A, st.n), dtype=np.int64), np.zeros(A, dtype=np.bool_),
                np.full(A, st.n, dtype=np.int64), np.zeros(A, dtype=np.int64)]
    _dead_ends(lazy.lattice, np.arange(A), order, *lazy_out, True, 0, 1)
    for got, want in zip(lazy_out, (configs, found, expanded, checks), strict=True):
        assert (got == want).all()
    steps, swings = st.all_indices
    all_configs = st.all_configs.astype(np.int64)
    none = dead = 0
    for a in range(A):
        pass_config, pass_checks, stuck, result, pushes, looked = _reference(
            full, a, order[a].tolist())
        assert checks[a] == pass_checks + looked and expanded[a] == st.n + pushes
        legal = (full.step_legal[a, steps] & full.swing_ok[a, swings]).all(axis=1)
        if not legal.any():
            assert result is None and not found[a] and configs[a].tolist() == pass_config
            none += 1
            continue
        # lexsort: the last key is the primary one (legal first, then rank of j_1, ...)
        rank = np.argsort(order[a])[all_configs]  # (J**n, n) preference rank of each j
        first = np.lexsort([rank[:, k] for k in range(st.n - 1, -1, -1)] + [~legal])[0]
        assert found[a] and configs[a].tolist() == all_configs[first].tolist() == result
        dead += stuck  # backtracked to a legal configuration
    assert none and dead and A - none > 10
    # lazily: less evaluated, and every value read is the complete table's
    assert lazy.lattice.work[:, 4].sum() < full.lattice.work[:, 4].sum()
    done = lazy.lattice.step_done
    for name in ("reason", "E", "length"):
        assert (getattr(lazy.lattice, name)[done] == getattr(full.lattice, name)[done]).all()
    built = lazy.lattice.swing_done
    assert (lazy.swing_ok[built] == full.swing_ok[built]).all()


@nb.njit(cache=True)
def _legal_lazily(L, a, steps, swings, out):
    """:func:`_complete_legal` of each (step, swing) pair, in a random order; ``out``
    (P,) bool."""
    reach = np.full(L.node_depth.size, -1, dtype=np.int8)
    reach[0] = reach[1] = 1
    stack = np.empty((L.step_offset.size + 2, 2), dtype=np.int64)
    for i in range(steps.size):
        out[i] = _complete_legal(L, a, steps[i], swings[i], reach, stack, True)


def test_the_lazy_legality_of_a_step_and_its_swing_is_the_complete_tables():
    """For 20,000 (step, swing) pairs of each agent's configurations, read in a random
    order, so that steps past illegal ones (whose stance foothold another sequence may
    reach) and swings without a legal middle step are read too."""
    lazy, full = _tables(False), _tables(True)
    steps, swings = (x.ravel() for x in full.struct.all_indices)
    rng = np.random.default_rng(5)
    for a in range(full.neutral.size):
        pick = rng.permutation(steps.size)[:20000]
        out = np.zeros(pick.size, dtype=np.bool_)
        _legal_lazily(lazy.lattice, a, steps[pick], swings[pick], out)
        want = full.step_legal[a, steps[pick]] & full.swing_ok[a, swings[pick]]
        assert (out == want).all()
