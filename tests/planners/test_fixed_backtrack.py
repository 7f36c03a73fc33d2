"""``fixed``'s depth-first backtracking (a dead end's retry) returns the first legal
configuration in the agent's preference order: of all configurations whose every step and
swing is legal in the complete table, the least by (rank of j_1, rank of j_2, ...)."""

import numpy as np

from planners.fixed import _backtrack
from planners.lattice import build_tables
from planners.plan import _default_config
from tests.planners.test_diagnose import _walls_batch


def test_backtrack_finds_the_first_legal_configuration_in_preference_order():
    profiles, legs, speeds, trailing = _walls_batch()
    tables = build_tables(profiles, legs, speeds, trailing, np.zeros(len(profiles)),
                          _default_config(), lazy=True)
    tables.complete()
    st = tables.struct
    steps, swings = st.all_indices
    configs = st.all_configs.astype(np.int64)
    rng = np.random.default_rng(3)
    none = found = 0
    for a in range(len(profiles)):
        order = rng.permutation(st.J).astype(np.int64)
        legal = (tables.step_legal[a, steps] & tables.swing_ok[a, swings]).all(axis=1)
        rank = np.argsort(order)[configs]  # (J**n, n) preference rank of each j
        result, pushes, looked = _backtrack(tables, a, order)
        if not legal.any():
            assert result is None
            none += 1
            continue
        # lexsort: the last key is the primary one (legal first, then rank of j_1, ...)
        first = np.lexsort([rank[:, k] for k in range(st.n - 1, -1, -1)] + [~legal])[0]
        assert result.tolist() == configs[first].tolist()
        assert pushes >= st.n - 1 and looked >= st.n
        found += 1
    assert none and found > 10
