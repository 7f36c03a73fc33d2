"""A scene's actors on one pyvista plotter, animated in simulated time.

``SceneView.set_time`` moves every agent and footprint to a simulated time by updating
mesh points in place (one mesh for all stick figures, one for all footprints; never an
actor per agent). Key bindings, the time slider and the playback timer of the
interactive window call the same methods, so they are testable off-screen.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid
from crowdwalk.viz import camera as cam
from crowdwalk.viz.figures import StickFigures
from crowdwalk.viz.footprints import COLOR_FIELDS, FootprintMesh
from crowdwalk.viz.playback import Playback
from crowdwalk.viz.sources import PoseTimeline
from crowdwalk.viz.world_meshes import (
    flat_ground,
    outline_lines,
    route_lines,
    terrain_edges,
    terrain_mesh,
)

__all__ = ["SceneView", "AGENT_HUES", "LARGE_CROWD"]

LARGE_CROWD = 200  # agents; above this the figures use fewer triangles
AGENT_HUES = 20  # agents are coloured by id modulo this many categorical colours
FIGURE_COLOR = "#3b3f4a"
ROUTE_COLOR = "#d9480f"
WALKABLE_COLOR = "#1971c2"
_HEAD_NAMES = ("skullbase", "skull_tip", "skull", "head", "vc4", "vc7")
_COLOR_STYLE = {
    "energy": dict(cmap="plasma", title="step energy [J/kg]"),
    "planner": dict(cmap="Set1", title="planner"),
    "agent": dict(cmap="tab20", title="agent (id mod 20)"),
}


def _ground_colormap():
    """Greens to browns of matplotlib's ``gist_earth`` (no deep-water blue for low ground)."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap

    return ListedColormap(colormaps["gist_earth"](np.linspace(0.35, 0.8, 256)), "ground")


def _planner_table(footsteps) -> tuple[list[str], tuple[np.ndarray, np.ndarray]]:
    """Planner names (sorted, as the footprint codes) and, per agent, its planner code:
    (sorted agent ids (m,), codes (m,) float), from the agents' foot placements."""
    names = sorted(set(footsteps.planner.tolist()))
    agents, first = np.unique(footsteps.agent, return_index=True)
    lookup = {name: float(i) for i, name in enumerate(names)}
    codes = np.array([lookup[p] for p in footsteps.planner[first]], dtype=float)
    return names, (agents, codes)


def _head_joint(names: list[str], first_positions: np.ndarray | None) -> int:
    """The joint that carries the head: by H-Anim name, else the highest joint."""
    lower = [n.lower() for n in names]
    for name in _HEAD_NAMES:
        if name in lower:
            return lower.index(name)
    if first_positions is not None and len(first_positions):
        return int(np.argmax(first_positions[:, :, 2].mean(axis=0)))
    return len(names) - 1


class SceneView:
    """A scene's actors on one plotter, animated by :meth:`set_time`.

    Attributes
    ----------
    figures : StickFigures or None
        All agents' stick figures (one mesh).
    footprints : FootprintMesh or None
        All footprints (one mesh).
    playback : Playback
        Current time, play/pause and speed.
    """

    def __init__(self, scene, plotter: pv.Plotter) -> None:
        self.scene = scene
        self.plotter = plotter
        self.color = scene.color
        self.follow = scene.follow
        start, end = scene.time_range
        self.playback = Playback(start, end, scene.frame_dt)
        self.figures: StickFigures | None = None
        self.footprints: FootprintMesh | None = None
        self.frame: int | None = None
        self._shown_time: float | None = None
        self.agent_ids = np.zeros(0, dtype=int)
        self.agent_roots = np.zeros((0, 3))
        self._framed: int | None = None
        self.figures_positions = np.zeros((0, 0, 3))
        self._planner_names, self._planner_of = _planner_table(scene.footsteps)
        plotter.set_background("white", top="#dde6ee")
        bounds = self._add_world()
        self._add_agents()
        self._add_footprints()
        self._add_legend()
        self._clock = plotter.add_text(
            "", position="upper_left", font_size=self._font(12), color="black"
        )
        plotter.camera_position = cam.oblique_view(bounds)
        plotter.reset_camera_clipping_range()

    # --- building -------------------------------------------------------------------

    @property
    def _small(self) -> bool:
        return self.plotter.window_size[1] < 500

    def _font(self, size_at_800: int, minimum: int = 6) -> int:
        """Font size [pt] scaled with the window height (``size_at_800`` at 800 px)."""
        return max(minimum, round(size_at_800 * self.plotter.window_size[1] / 800))

    def _add_world(self) -> np.ndarray:
        p, scene = self.plotter, self.scene
        bounds = None
        if scene.terrain is not None:
            ground = terrain_mesh(scene.terrain)
            heights = ground.point_data["height"]
            lo, hi = float(heights.min()), float(heights.max())
            p.add_mesh(
                ground, scalars="height", cmap=_ground_colormap(), smooth_shading=False,
                show_scalar_bar=hi - lo > 1e-6, name="terrain", ambient=0.25,
                clim=[lo, hi if hi - lo > 1e-6 else lo + 1.0],
                scalar_bar_args=dict(title="height [m]", vertical=True, position_x=0.92,
                                     position_y=0.12, height=0.3, width=0.035, fmt="%.2f",
                                     color="black", n_labels=3,
                                     title_font_size=self._font(16),
                                     label_font_size=self._font(14)),
            )
            edges = terrain_edges(ground)
            if edges.n_cells:
                p.add_mesh(edges, color="#333333", line_width=1, name="terrain edges")
            bounds = np.array(ground.bounds)
        elif scene.walkable_area is not None and not scene.walkable_area.is_empty:
            ground = flat_ground(scene.walkable_area)
            if ground.n_points:
                p.add_mesh(ground, color="#e9ecef", name="terrain", ambient=0.3)
        if scene.walkable_area is not None and not scene.walkable_area.is_empty:
            outline = outline_lines(scene.walkable_area, scene.terrain)
            if outline.n_points:
                p.add_mesh(outline, color=WALKABLE_COLOR, line_width=3, name="walkable area")
                if bounds is None:
                    bounds = np.array(outline.bounds)
        graph = getattr(scene.routes, "graph", None)
        if graph is not None and graph.number_of_nodes():
            edges_mesh, nodes = route_lines(graph, scene.terrain)
            if edges_mesh.n_points:
                p.add_mesh(edges_mesh, color=ROUTE_COLOR, line_width=2, name="route edges")
            if nodes is not None:
                p.add_mesh(nodes, color=ROUTE_COLOR, point_size=max(3, self._font(9)),
                           render_points_as_spheres=True, name="route nodes")
        if bounds is None:
            bounds = np.array([-5.0, 5.0, -5.0, 5.0, 0.0, 2.0])
        return bounds

    def _add_agents(self) -> None:
        poses = self.scene.poses
        if poses is None or not len(poses.times):
            return
        _, first = poses.at(0)
        # Level of detail: software rendering cost grows with triangles; a large crowd is
        # seen from afar, a small one close up (bench_render.py).
        large = poses.n_agents > LARGE_CROWD
        self.figures = StickFigures(
            poses.parents, head_joint=_head_joint(poses.names, first),
            radius=0.035 if len(poses.parents) > 2 else 0.12,
            sides=4 if large else 6, head_detail=0 if large else 1,
        )
        self._root = int(np.flatnonzero(np.asarray(poses.parents) < 0)[0])
        self._timeline = PoseTimeline(poses, interpolate=self.scene.interpolate)
        self._show_time(float(poses.times[0]))
        self._add_figures_actor()

    def _add_figures_actor(self) -> None:
        if self.figures is None:
            return
        kwargs = dict(interpolation="gouraud", name="agents", show_scalar_bar=False,
                      culling="back")
        if self.color == "agent":
            kwargs.update(scalars="value", cmap="tab20", clim=[0, AGENT_HUES])
        elif self.color == "planner":
            n = max(len(self._planner_names), 1)
            kwargs.update(scalars="value", cmap="Set1", clim=[-0.5, n - 0.5], n_colors=n,
                          nan_color=FIGURE_COLOR)
        else:
            kwargs.update(color=FIGURE_COLOR, scalars=None)
        self.plotter.add_mesh(self.figures.mesh, **kwargs)

    def _figure_values(self, ids: np.ndarray) -> np.ndarray | None:
        """Per-agent colour values (k,) for the current colour mode (None: one colour)."""
        if self.color == "agent":
            return np.mod(ids, AGENT_HUES).astype(float)
        if self.color == "planner":
            agents, codes = self._planner_of
            i = np.clip(np.searchsorted(agents, ids), 0, max(len(agents) - 1, 0))
            known = (agents[i] == ids) if len(agents) else np.zeros(len(ids), bool)
            return np.where(known, codes[i] if len(agents) else 0.0, np.nan)
        return None

    def _add_footprints(self) -> None:
        if not len(self.scene.footsteps):
            return
        self.footprints = FootprintMesh(self.scene.footsteps)
        self.footprints.mesh.point_data["agent"] = np.mod(
            self.footprints.mesh.point_data["agent"], AGENT_HUES
        )
        self._add_footprint_actor()

    def _add_footprint_actor(self) -> None:
        fp = self.footprints
        if fp is None:
            return
        style = _COLOR_STYLE[self.color]
        bar = dict(title=style["title"], color="black", position_x=0.3, position_y=0.02,
                   width=0.4, height=0.1, fmt="%.3g", n_labels=3 if self._small else 5,
                   title_font_size=self._font(16), label_font_size=self._font(14),
                   background_color="white", fill=True)
        kwargs = dict(scalars=self.color, cmap=style["cmap"], name="footprints",
                      scalar_bar_args=bar, show_scalar_bar=True)
        if self.color == "planner":
            n = max(len(fp.planners), 1)
            kwargs.update(clim=[-0.5, n - 0.5], n_colors=n, show_scalar_bar=False)
        elif self.color == "agent":
            kwargs.update(clim=[0, AGENT_HUES], show_scalar_bar=False)
        else:
            energy = self.scene.footsteps.energy
            finite = energy[np.isfinite(energy)]
            # 2nd-98th percentile: a few very costly steps must not wash out the rest
            lo, hi = (np.percentile(finite, [2, 98]) if finite.size else (0.0, 1.0))
            lo, hi = float(lo), float(hi)
            kwargs.update(clim=[lo, hi if hi > lo else lo + 1.0])
        if "footprints" in self.plotter.actors:
            self.plotter.remove_actor("footprints")
            for title in list(self.plotter.scalar_bars.keys()):
                if title != "height [m]":
                    self.plotter.remove_scalar_bar(title)
        self.plotter.add_mesh(fp.mesh, **kwargs)

    def _add_legend(self) -> None:
        """Legend in the top right corner: each entry's label written in its colour; in
        planner mode also one entry per planner (figures and footprints share them).

        (VTK's legend box clips long labels at some window sizes; plain text does not.)
        """
        for name in getattr(self, "_legend_names", []):
            self.plotter.remove_actor(name)
        entries = []
        if self.figures is not None and self.color != "planner":
            entries.append(("agents", FIGURE_COLOR))
        if self.scene.walkable_area is not None:
            entries.append(("walkable area", WALKABLE_COLOR))
        if getattr(self.scene.routes, "graph", None) is not None:
            entries.append(("route graph", ROUTE_COLOR))
        if self.color == "planner" and "footprints" in self.plotter.actors:
            table = self.plotter.actors["footprints"].mapper.lookup_table
            for i, name in enumerate(self._planner_names):
                rgb = table.map_value(float(i))[:3]
                entries.append((f"planner {name}", tuple(c / 255 for c in rgb)
                                if max(rgb) > 1 else tuple(rgb)))
        size = self._font(8, minimum=4)  # pyvista doubles the size of positioned text
        line = 2.6 * size / self.plotter.window_size[1] * 1.3
        self._legend_names = []
        for i, (label, color) in enumerate(entries):
            name = f"legend {label}"
            text = self.plotter.add_text(
                f"{label} —", position=(0.985, 0.96 - i * line), viewport=True,
                font_size=size, color=color, name=name,
            )
            text.GetTextProperty().SetJustificationToRight()
            text.GetTextProperty().SetVerticalJustificationToTop()
            self._legend_names.append(name)

    # --- animation ------------------------------------------------------------------

    def _show_time(self, t: float) -> None:
        index, ids, positions = self._timeline.at_time(t)
        self.figures.update(positions, self._figure_values(np.asarray(ids)))
        self.agent_ids = np.asarray(ids)
        self.figures_positions = positions
        self.agent_roots = np.asarray(positions)[:, self._root] if len(ids) else np.zeros((0, 3))
        self.frame = index
        self._shown_time = t

    def set_time(self, t: float) -> float:
        """Show the scene at simulated time ``t`` [s] (clamped to the run); returns it."""
        t = self.playback.seek(t)
        if self.figures is not None and t != self._shown_time:
            self._show_time(t)
        if self.footprints is not None:
            trail = self.scene.footprint_trail
            self.footprints.show_window(-np.inf if trail is None else t - trail, t)
        if self.follow is not None:
            root = self.agent_root(self.follow)
            if root is not None:
                if self._framed != self.follow:
                    box = np.repeat(root, 2) + np.array([-3.0, 3.0, -3.0, 3.0, -0.5, 1.5])
                    self.plotter.camera_position = cam.oblique_view(box, elevation=0.45)
                    self._framed = self.follow
                cam.follow(self.plotter, root)
        self.plotter.reset_camera_clipping_range()
        n = len(self.agent_ids)
        speed = self.playback.speed
        self._clock.SetText(
            2, f"{self.scene.title}\nt = {t:7.2f} s   agents: {n}   speed x{speed:g}"
            + (f"   following {self.follow}" if self.follow is not None else "")
        )
        return t

    def agent_root(self, agent_id: int) -> np.ndarray | None:
        """Root joint position (3,) [m] of an agent in the current frame, or None."""
        hit = np.flatnonzero(self.agent_ids == agent_id)
        return self.agent_roots[hit[0]] if hit.size else None

    def set_color(self, color: str) -> None:
        """Colour footprints (and, for ``"agent"``, figures) by ``color``."""
        if color not in COLOR_FIELDS:
            raise invalid("SceneView", "color", f"one of {', '.join(COLOR_FIELDS)}", color)
        self.color = color
        self._add_footprint_actor()
        self._add_legend()
        if self.figures is not None:
            values = self._figure_values(self.agent_ids)
            if values is not None:
                self.figures.update(self.figures_positions, values)
        self._add_figures_actor()

    # --- interaction ----------------------------------------------------------------

    def key_bindings(self) -> dict[str, Callable[[], None]]:
        """Key name (VTK keysym) → action; :meth:`install_controls` registers them."""
        pb = self.playback

        def redraw(action):
            def run():
                action()
                self.set_time(pb.time)
                self._sync_slider()
                self.plotter.render()

            return run

        def cycle_color():
            self.set_color(COLOR_FIELDS[(COLOR_FIELDS.index(self.color) + 1) % len(COLOR_FIELDS)])

        def toggle_follow():
            if self.follow is not None:
                self.follow = None
            elif len(self.agent_ids):
                self.follow = int(self.scene.follow if self.scene.follow is not None
                                  else self.agent_ids[0])

        return {
            "space": redraw(pb.toggle),
            "Right": redraw(lambda: pb.step(1)),
            "Left": redraw(lambda: pb.step(-1)),
            "Up": redraw(pb.faster),
            "Down": redraw(pb.slower),
            "c": redraw(cycle_color),
            "f": redraw(toggle_follow),
        }

    def tick(self, wall_dt: float) -> float:
        """One timer tick of ``wall_dt`` wall-clock seconds: advance when playing."""
        if self.playback.playing:
            self.set_time(self.playback.advance(wall_dt))
            self._sync_slider()
        return self.playback.time

    def _sync_slider(self) -> None:
        slider = getattr(self, "_slider", None)
        if slider is not None:
            slider.GetRepresentation().SetValue(self.playback.time)

    def install_controls(self, interval: float = 1 / 30) -> None:
        """Time slider, keys and a playback timer on an interactive plotter.

        Parameters
        ----------
        interval : float
            Timer period [s].
        """
        t0, t1 = self.scene.time_range
        if t1 > t0:
            self._slider = self.plotter.add_slider_widget(
                self.set_time, rng=[t0, t1], value=self.playback.time,
                title="time [s]", pointa=(0.3, 0.93), pointb=(0.7, 0.93), style="modern",
                interaction_event="always", fmt="%.1f",
            )
        for key, action in self.key_bindings().items():
            self.plotter.add_key_event(key, action)
        if t1 > t0:
            def on_timer(_step):
                if self.playback.playing:
                    self.tick(interval)
                    self.plotter.render()

            self.plotter.add_timer_event(max_steps=10**9, duration=int(interval * 1000),
                                         callback=on_timer)
