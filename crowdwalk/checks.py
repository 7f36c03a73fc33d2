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
    if m := re.match(r"Scenario\.groups\[(\d+)\]\.(\w+)", message):
        return ("groups", int(m[1]), m[2])
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

# Bytes a run holds per agent (struct-of-arrays state, planner cache, steering index and the
# pose batch; measured as peak RSS growth / agents on stadium_egress, 1,000 vs 5,000 agents,
# rounded up) and per terrain grid node (heights, noise field and filter work arrays).
BYTES_PER_AGENT = 200_000
BYTES_PER_GRID_NODE = 64
MAX_AGENTS = 1_000_000  # beyond any machine's memory for a run, whatever it reports
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


def check_resources(scenario, memory: int | None = None) -> None:
    """Refuse agent counts and terrain grids that would not fit in ``memory`` [bytes]
    (default: what is available now), before any of them is allocated."""
    memory = available_memory() if memory is None else memory
    budget = memory // 2
    for i, f in enumerate(scenario.terrain.features):
        if f.type != "rough":
            continue
        if f.amplitude is not None:
            nodes = (f.size[0] / f.cell + 1) * (f.size[1] / f.cell + 1)
        elif f.heights is not None:
            nodes = len(f.heights) * max((len(r) for r in f.heights), default=0)
        else:
            continue  # a heights file: its array is checked when it is read
        need = nodes * BYTES_PER_GRID_NODE
        if need > budget:
            min_cell = f.cell * math.sqrt(need / budget)
            raise InputError(
                f"{scenario.where(('terrain', 'features', i, 'cell'))}: terrain.features[{i}]."
                f"cell must be ≥ {min_cell:.3g} m for this {f.size[0]:g} × {f.size[1]:g} m grid "
                f"({nodes:.3g} nodes need ~{_gib(need)}; {_gib(memory)} available); "
                f"got {f.cell:g}." if f.amplitude is not None else
                f"{scenario.where(('terrain', 'features', i, 'heights'))}: terrain.features[{i}]."
                f"heights must have at most {budget // BYTES_PER_GRID_NODE:,} values here; "
                f"got {nodes:,}.")
    total = sum(g.count for g in scenario.groups)
    fit = min(MAX_AGENTS, budget // BYTES_PER_AGENT)
    if total > fit:
        i = max(range(len(scenario.groups)), key=lambda k: scenario.groups[k].count)
        raise InputError(
            f"{scenario.where(('groups', i, 'count'))}: groups[{i}].count: the scenario's "
            f"agents must number at most {fit:,} on this machine (~{BYTES_PER_AGENT // 1000} kB "
            f"each, {_gib(memory)} available); got {total:,} in all.")


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
