"""Heterogeneous populations: who walks, how tall, how fast, from where to where, when.

Body heights and free speeds are drawn per group from the scenario's distributions with
the scenario's seeded ``numpy.random.Generator``. Defaults (when a group gives none):

- free speed and body height: the scenario's defaults (``crowdwalk.scenario``:
  Weidmann 1993 normal(1.34, 0.26) m/s; adult normal(1.71, 0.09) m);
- the shortest step duration of an agent follows the measured cadence–speed relation
  shipped in ``crowdwalk/data/normative.json`` (Fukuchi et al. 2018):
  cadence = a·v^b steps/s.

Heights are rounded to 1 cm and speeds to 1 cm/s (the precision of the measurements),
which lets agents share footstep plans in the planner cache.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from functools import lru_cache
from importlib import resources

import numpy as np

from crowdwalk.errors import invalid
from crowdwalk.style import Style, sample_styles

__all__ = ["Population", "normative", "cadence_at", "step_length_at"]



@lru_cache(maxsize=1)
def normative() -> dict:
    """The normative gait references shipped in ``crowdwalk/data/normative.json``."""
    text = resources.files("crowdwalk").joinpath("data/normative.json").read_text()
    return json.loads(text)


def cadence_at(speed: np.ndarray) -> np.ndarray:
    """Measured mean cadence [steps/s] at walking speed ``speed`` [m/s] (Fukuchi et al.
    2018 fit in normative.json; fallback 1.74 v^0.49)."""
    try:
        model = normative()["cadence_vs_speed"]
        a, b = float(model["coefficient"]), float(model["exponent"])
    except (FileNotFoundError, KeyError, ValueError):
        a, b = 1.7398, 0.4921
    return a * np.maximum(np.asarray(speed, dtype=float), 0.1) ** b


def step_length_at(speed: np.ndarray) -> np.ndarray:
    """Measured mean step length [m] at walking speed ``speed`` [m/s] (normative.json)."""
    try:
        model = normative()["step_length_vs_speed"]
        c, k = float(model["intercept_m"]), float(model["slope_s"])
    except (FileNotFoundError, KeyError, ValueError):
        c, k = 0.2555, 0.312
    return c + k * np.asarray(speed, dtype=float)


@dataclass(frozen=True)
class Population:
    """Every agent of a run, struct-of-arrays (n agents).

    Attributes
    ----------
    group : (n,) int
        Index into ``group_names``.
    group_names : tuple of str
    planner_names : tuple of str
        Planner per group.
    body_height : (n,) float [m]
    free_speed : (n,) float [m/s]
    spawn_time : (n,) float [s]
    spawn_xy : (n, 2) float [m]
    origin : (n,) str
        Route node the agent starts from.
    destinations : (n,) object
        Tuples of route node names, visited in order.
    route_start : (n, 2) float
        Where the agent's route polyline begins [m] (NaN: at the origin node).
    style : crowdwalk.style.Style or None
        Each agent's KLAW style (None: the default style at ``free_speed``).
    gait_names : tuple of str
        Gait engine per group (empty: ``elevation_angles`` for all).
    """

    group: np.ndarray
    group_names: tuple[str, ...]
    planner_names: tuple[str, ...]
    body_height: np.ndarray
    free_speed: np.ndarray
    spawn_time: np.ndarray
    spawn_xy: np.ndarray
    origin: np.ndarray
    destinations: np.ndarray
    route_start: np.ndarray
    style: Style | None = None
    gait_names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        n = self.group.size
        if self.style is None:
            object.__setattr__(self, "style", Style.default(self.body_height, self.free_speed))
        if len(self.style) != n:
            raise invalid("Population", "style", f"of {n} walkers", len(self.style))
        for name in ("body_height", "free_speed", "spawn_time", "origin", "destinations"):
            if getattr(self, name).shape != (n,):
                raise invalid("Population", name, f"of shape ({n},)", getattr(self, name).shape)
        if self.spawn_xy.shape != (n, 2):
            raise invalid("Population", "spawn_xy", f"of shape ({n}, 2) [m]", self.spawn_xy.shape)
        if n and not np.all((self.body_height >= 0.5) & (self.body_height <= 2.5)):
            raise invalid("Population", "body_height", "in [0.5, 2.5] [m]",
                          float(self.body_height.min()))
        if n and not np.all(self.free_speed > 0):
            raise invalid("Population", "free_speed", "> 0 [m/s]", float(self.free_speed.min()))

    def __len__(self) -> int:
        return int(self.group.size)

    @property
    def planner(self) -> np.ndarray:
        """Planner name per agent (n,)."""
        return np.asarray(self.planner_names, dtype=object)[self.group]

    def take(self, index: np.ndarray) -> Population:
        """The sub-population at ``index``."""
        return replace(
            self, group=self.group[index], body_height=self.body_height[index],
            free_speed=self.free_speed[index], spawn_time=self.spawn_time[index],
            spawn_xy=self.spawn_xy[index], origin=self.origin[index],
            destinations=self.destinations[index], route_start=self.route_start[index],
            style=self.style.take(index),
        )

    @property
    def gait(self) -> np.ndarray:
        """Gait engine name per agent (n,)."""
        names = self.gait_names or ("elevation_angles",) * len(self.group_names)
        return np.asarray(names, dtype=object)[self.group]

    def with_planner(self, planner: str) -> Population:
        """The same agents, every group using ``planner`` (the planned-vs-unplanned
        comparison runs identical agents with each planner)."""
        return replace(self, planner_names=tuple(planner for _ in self.planner_names))

    @classmethod
    def from_scenario(cls, scenario, routes, rng: np.random.Generator) -> Population:
        """Draw the population of a validated scenario.

        Per group, in file order: body heights, free speeds (the group's ``Normal``
        distributions), then spawn positions inside the spawn node's area (or polygon),
        all from ``rng``; then the styles (:func:`crowdwalk.style.sample_styles`; a
        preset or locked velocity replaces the free speed). Spawn times come from the
        group's ``spawn_times``.

        Parameters
        ----------
        scenario : crowdwalk.scenario.Scenario
        routes : crowdwalk.routes.RouteGraph
        rng : numpy.random.Generator
        """
        from shapely.geometry import Polygon

        from crowdwalk.exits import choose_exits
        from crowdwalk.routes import lattice_points, spawn_points

        parts: dict[str, list] = {k: [] for k in (
            "group", "height", "speed", "time", "xy", "origin", "dest", "start")}
        for gi, g in enumerate(scenario.groups):
            n = g.count
            heights = np.round(g.body_height.sample(rng, n), 2)
            speeds = np.round(g.free_speed.sample(rng, n), 2)
            if isinstance(g.spawn, str):
                area = routes.node_area(g.spawn)
                origin = g.spawn
                start = np.full(2, np.nan)
            else:
                area = Polygon(g.spawn)
                centre = np.asarray(area.representative_point().coords[0])
                names = list(routes.graph.nodes)
                xy = np.array([routes.node_xy(v) for v in names])
                origin = names[int(np.argmin(np.linalg.norm(xy - centre, axis=1)))]
                start = centre
            inner = area.buffer(-0.25)  # keep bodies off the walls
            if inner.area > 0.05 * area.area:
                area = inner
            if g.density is not None:
                front = routes.node_xy((g.destinations or g.exit_choice.among)[0])
                xy = lattice_points(area, n, g.density, rng, front=front)
            else:
                try:
                    xy = spawn_points(area, n, rng, min_spacing=0.5)
                except ValueError:  # more agents than fit at once: they enter one by one
                    xy = spawn_points(area, n, rng, min_spacing=0.0)
            parts["group"].append(np.full(n, gi))
            parts["height"].append(heights)
            parts["speed"].append(speeds)
            times = g.spawn_times.times(n, rng)
            parts["time"].append(times)
            parts["xy"].append(xy)
            parts["origin"].append(np.full(n, origin, dtype=object))
            dest = np.empty(n, dtype=object)
            dest[:] = [tuple(g.destinations)] * n
            if g.exit_choice is not None:
                here = g.destinations[-1] if g.destinations else origin
                exits = choose_exits(g.exit_choice, routes, here, xy, speeds, times, rng)
                dest[:] = [(*g.destinations, e) for e in exits]
            parts["dest"].append(dest)
            parts["start"].append(np.tile(start, (n, 1)))
        group = np.concatenate(parts["group"]).astype(np.int64)
        height = np.concatenate(parts["height"])
        style = sample_styles(scenario.groups, group, height, np.concatenate(parts["speed"]), rng)
        style = style.with_values(velocity=np.round(style.velocity, 2))
        return cls(
            group=group,
            group_names=tuple(g.name for g in scenario.groups),
            planner_names=tuple(g.planner for g in scenario.groups),
            body_height=height,
            free_speed=style.velocity,
            spawn_time=np.concatenate(parts["time"]).astype(float),
            spawn_xy=np.concatenate(parts["xy"]),
            origin=np.concatenate(parts["origin"]),
            destinations=np.concatenate(parts["dest"]),
            route_start=np.concatenate(parts["start"]),
            style=style,
            gait_names=tuple(g.gait for g in scenario.groups),
        )
