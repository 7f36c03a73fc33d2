"""Input checks a run makes before it simulates, each error located in the scenario file.

The world's builders (terrain, routes, population) raise
:class:`~crowdwalk.errors.InputError` naming their own owner ("Block.footprint ...",
"RouteGraph.edges['a'->'b'].corridor ...", "spawn_points.n ..."); :func:`located` turns
that into the one-line form ``file:line: <message>`` using the field path the builder was
working on. :func:`check_resources` refuses, before anything is allocated, a scenario
whose agents or grids would not fit in this machine's memory.
"""

from __future__ import annotations

import math
import os
import re

from crowdwalk.errors import InputError

__all__ = ["located", "at", "check_resources", "available_memory", "plain",
           "world_and_population"]

_NUMPY_REPR = re.compile(r"np\.(?:float|int|uint|bool_?)\d*\(([^()]*)\)")


def plain(text: str) -> str:
    """``text`` without numpy reprs: ``np.float64(-1.5)`` -> ``-1.5``."""
    return _NUMPY_REPR.sub(r"\1", text)


def at(loc: tuple, func, *args):
    """``func(*args)``; an InputError it raises without a location gets ``loc``."""
    try:
        return func(*args)
    except InputError as exc:
        if getattr(exc, "loc", None) is None:
            exc.loc = loc
        raise


def _loc_from_message(scenario, message: str) -> tuple | None:
    """The field path an owner-style message refers to, or None."""
    routes = scenario.routes
    if m := re.match(r"Scenario\.(groups|events|waiting_areas)\[(\d+)\]\.(\w+)", message):
        return (m[1], int(m[2]), m[3])
    if m := re.match(r"Terrain\.features\[(\d+)\]", message):
        return ("terrain", "features", int(m[1]))
    if m := re.match(r"Terrain\.(\w+)", message):
        return ("terrain", m[1])
    if m := re.match(r"(?:RouteGraph\.nodes|Place)\['((?:[^']|\\')*)'\]", message):
        names = [n.name for n in routes.nodes]
        return ("routes", "nodes", names.index(m[1])) if m[1] in names else ("routes",)
    if m := re.match(r"(?:RouteGraph\.edges|Corridor)\['([^']*)'->'([^']*)'\]", message):
        ends = [{e.from_, e.to} for e in routes.edges]
        return ("routes", "edges", ends.index({m[1], m[2]})) if {m[1], m[2]} in ends \
            else ("routes",)
    if message.startswith(("RouteGraph", "GraphML", "Place", "Corridor")):
        return ("routes", "graphml") if routes.graphml else ("routes",)
    return None


def located(scenario, exc: InputError, default: tuple = ()) -> InputError:
    """``exc`` as ``file:line: message`` (unchanged if it already names the file)."""
    message = plain(str(exc))
    source = scenario._source
    if message.startswith(f"{source}:"):
        return InputError(message)
    loc = _loc_from_message(scenario, message) or getattr(exc, "loc", None) or default
    return InputError(f"{scenario.where(loc)}: {message}")


# --- memory ---------------------------------------------------------------------------

# Bytes a run holds per agent, the run's worker process included (crowdwalk.workers):
# `python benchmarks/bench_memory.py --agents 500 1000 2000` measures 49-54 kB of peak-RSS
# growth per agent with poses (4 s; about a third in the run's process, the rest in the
# worker that holds the gait engine) and `--agents 1000 5000 10000 --no-poses --seconds 2`
# ~5 kB (steering threads share the run's process; no worker). Per terrain grid node:
# heights, the noise field and the filter's work arrays (8 float64 arrays).
BYTES_PER_AGENT = 60_000
BYTES_PER_GRID_NODE = 64
MAX_AGENTS = 20_000  # 4x the largest crowd benchmarked (bench_crowd.py); setup grows beyond
MAX_ROUTE_NODES = 10_000  # route nodes (and edges) per scenario: validation within seconds


def available_memory() -> int:
    """Memory this process may still allocate [bytes] (MemAvailable; 4 GiB if unknown)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 4 << 30


def _gib(n: float) -> str:
    return f"{n / 2**30:.1f} GiB"


def _grid_nodes(f) -> float:
    """Nodes of a rough-terrain grid, from its spec (a .npy file: from its header only)."""
    if f.amplitude is not None:
        return (f.size[0] / f.cell + 1) * (f.size[1] / f.cell + 1)
    if f.heights is not None:
        return len(f.heights) * max((len(r) for r in f.heights), default=0)
    if f.heights_file.endswith(".npy") and os.path.exists(f.heights_file):
        import numpy as np

        return math.prod(np.load(f.heights_file, mmap_mode="r").shape)
    return 0  # a CSV file: its size bounds its array


def check_resources(scenario, memory: int | None = None) -> None:
    """Refuse agent counts and terrain grids that would not fit in ``memory`` [bytes]
    (default: what is available now), before any of them is allocated."""
    memory = available_memory() if memory is None else memory
    budget = memory // 2
    for i, f in enumerate(scenario.terrain.features):
        nodes = _grid_nodes(f) if f.type == "rough" else 0
        if nodes * BYTES_PER_GRID_NODE <= budget:
            continue
        fit = f"at most {budget // BYTES_PER_GRID_NODE:,} grid nodes ({_gib(memory)} available)"
        if f.amplitude is None:
            key = "heights" if f.heights is not None else "heights_file"
            raise InputError(f"{scenario.where(('terrain', 'features', i, key))}: "
                             f"terrain.features[{i}].{key} must have {fit}; got {nodes:,.0f}.")
        min_cell = f.cell * math.sqrt(nodes * BYTES_PER_GRID_NODE / budget)
        raise InputError(f"{scenario.where(('terrain', 'features', i, 'cell'))}: "
                         f"terrain.features[{i}].cell must be ≥ {min_cell:.3g} m for a "
                         f"{f.size[0]:g} × {f.size[1]:g} m grid of {fit} [m]; got {f.cell:g}.")
    total = sum(g.count for g in scenario.groups)
    fit = min(MAX_AGENTS, budget // BYTES_PER_AGENT)
    if total > fit:
        i = max(range(len(scenario.groups)), key=lambda k: scenario.groups[k].count)
        why = ("the largest crowd crowdwalk sets up in bounded time" if fit == MAX_AGENTS else
               f"~{BYTES_PER_AGENT // 1000} kB each, {_gib(memory)} available")
        raise InputError(
            f"{scenario.where(('groups', i, 'count'))}: groups[{i}].count: the scenario's "
            f"agents must number at most {fit:,} ({why}); got {total:,} in all.")


def world_and_population(scenario):
    """The world and the seeded population of a loaded scenario: every input check a run
    makes before it simulates (``crowdwalk validate`` calls exactly this).

    Returns
    -------
    (World, Population)
    """
    import numpy as np

    from crowdwalk.population import Population
    from crowdwalk.world import build_world

    world = build_world(scenario)
    rng = np.random.default_rng(scenario.simulation.seed)
    try:
        pop = Population.from_scenario(scenario, world.routes, rng)
    except InputError as exc:
        raise located(scenario, exc, ("groups",)) from None
    return world, pop
