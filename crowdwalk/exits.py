"""Exit choice: which of several exits each agent of a group heads for.

Three rules (``groups[].exit_choice.rule``), decided once per agent when the population is
drawn, in spawn order:

- ``nearest``: the least route cost [m]. An agent standing in its origin's area reaches
  the origin or one of the nodes joined to it in a straight line, then follows the route
  graph: cost = min over those nodes v of ‖x − v‖ + cost(v → exit).
- ``least_congested``: the least expected time [s] — route cost over the agent's free
  speed, plus the queue of the walkers who chose that exit before and are still on
  their way (expected arrival later than this agent's spawn time), over the exit's
  capacity: 1.3 persons/(s·m) (Weidmann 1993's specific flow in a jam) times the
  narrowest corridor width on the cheapest route there.
- ``weights``: at random in proportion to the weights (the scenario's seeded generator).
"""

from __future__ import annotations

import bisect

import numpy as np

__all__ = ["choose_exits", "SPECIFIC_FLOW"]

#: Specific flow of a queue through an opening [1/(m s)] (Weidmann 1993).
SPECIFIC_FLOW = 1.3


def _costs(routes, here: str, exits: list[str], xy: np.ndarray) -> np.ndarray:
    """Route cost (n, E) [m] from agents at ``xy`` (n, 2) [m] in ``here``'s area to each
    exit (inf where unreachable)."""
    entry = [here, *sorted(set(routes.graph.successors(here)))]
    node_xy = np.array([routes.node_xy(v) for v in entry])  # (m, 2)
    to_exit = np.array([[routes.distances_to(e).get(v, np.inf) for e in exits]
                        for v in entry])  # (m, E)
    reach = np.linalg.norm(xy[:, None, :] - node_xy[None, :, :], axis=2)  # (n, m)
    return np.min(reach[:, :, None] + to_exit[None, :, :], axis=1)


def _capacity(routes, here: str, exit_: str) -> float:
    """Persons per second [1/s] through the narrowest corridor from ``here`` to the exit."""
    if here == exit_:
        return np.inf
    nodes = routes.route(here, exit_)
    width = min(routes.graph.edges[u, v]["width"] for u, v in zip(nodes[:-1], nodes[1:],
                                                                   strict=True))
    return SPECIFIC_FLOW * width


def choose_exits(choice, routes, here: str, xy: np.ndarray, speed: np.ndarray,
                 spawn_time: np.ndarray, rng: np.random.Generator) -> list[str]:
    """The exit of each of n agents.

    Parameters
    ----------
    choice : crowdwalk.behaviours.ExitChoice
    routes : crowdwalk.routes.RouteGraph
    here : str
        Node the agents leave from (their origin, or their last ordered destination).
    xy : (n, 2) float
        Start positions [m] (used when ``here`` is the origin whose area they stand in).
    speed : (n,) float
        Free speeds [m/s].
    spawn_time : (n,) float
        Spawn times [s].
    rng : numpy.random.Generator

    Returns
    -------
    list of n exit node names
    """
    exits = list(choice.among)
    n = len(xy)
    if choice.rule == "weights":
        w = np.asarray(choice.weights, float)
        return [exits[k] for k in rng.choice(len(exits), size=n, p=w / w.sum())]
    cost = _costs(routes, here, exits, np.asarray(xy, float))
    if not np.isfinite(cost).any(axis=1).all():
        from crowdwalk.errors import invalid

        raise invalid("Group", "exit_choice.among", f"reachable from {here!r}", exits)
    if choice.rule == "nearest":
        return [exits[k] for k in np.argmin(cost, axis=1)]
    capacity = np.array([_capacity(routes, here, e) if np.isfinite(cost[:, k]).any()
                         else np.inf for k, e in enumerate(exits)])
    walk = cost / speed[:, None]  # (n, E) [s]
    arrive = [[] for _ in exits]  # sorted expected arrival times of those who chose each
    chosen = np.empty(n, dtype=np.int64)
    for i in np.argsort(spawn_time, kind="stable"):  # setup only: one pass in spawn order
        t = float(spawn_time[i])
        queue = np.array([len(a) - bisect.bisect_right(a, t) for a in arrive])  # still going
        k = int(np.argmin(walk[i] + queue / capacity))
        chosen[i] = k
        bisect.insort(arrive[k], t + float(walk[i, k]))
    return [exits[k] for k in chosen]
