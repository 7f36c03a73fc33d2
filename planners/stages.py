"""Wall time per stage of planning, accumulated while :func:`recording` (off otherwise).

Stages: ``grids`` (the lattice's structure and the per-leg grids and flat-ground caches,
:func:`~planners.grids.leg_grids`), ``arrays`` (the rest of
:func:`~planners.lattice.build_tables` before its kernel: shifted profiles, the
lattice's arrays), ``kernel`` (the up-front
table kernel, or the lazy tables' preparation of the nodes), ``search`` (the planner's
search, including the entries a lazy search evaluates) and ``assemble`` (the plans built
from the tables, with the diagnosis of failed plans). For ``benchmarks/bench_planners.py
--stages``.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["STAGES", "add", "recording"]

#: The stages, in planning order.
STAGES = ("grids", "arrays", "kernel", "search", "assemble")
_TIMES: list[dict[str, float]] = []


def add(stage: str, since: float) -> float:
    """Add the time from ``since`` (a :func:`time.perf_counter` reading) to now to
    ``stage`` while recording; returns now."""
    now = time.perf_counter()
    if _TIMES:
        _TIMES[-1][stage] += now - since
    return now


@contextmanager
def recording() -> Iterator[dict[str, float]]:
    """A dict {stage: seconds} (:data:`STAGES`) filled by the planning done inside."""
    times = dict.fromkeys(STAGES, 0.0)
    _TIMES.append(times)
    try:
        yield times
    finally:
        _TIMES.remove(times)
