"""A scene's actors on one pyvista plotter, animated in simulated time.

``SceneView.set_time`` moves every walker and footprint to a simulated time by updating
mesh points in place (one mesh for all bodies, one for all footprints; never an actor
per walker). Several views share one window side by side (:func:`attach_views`): the
first one leads — one time, one camera, one set of keys for all. Key bindings, the time
slider and the playback timer of the interactive window call the same methods, so they
are testable off-screen.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid
from crowdwalk.viz import camera as cam
from crowdwalk.viz.bodies import SolidBodies, detail_for
from crowdwalk.viz.footprints import COLOR_FIELDS, FootprintMesh
from crowdwalk.viz.overlay import Layout, Overlay
from crowdwalk.viz.playback import Playback
from crowdwalk.viz.sources import PoseTimeline
from crowdwalk.viz.walkers import Walkers, walker_status
from crowdwalk.viz.world_meshes import (
    closed_walls,
    flat_ground,
    outline_lines,
    route_lines,
    terrain_edges,
    terrain_mesh,
)

__all__ = ["SceneView", "attach_views", "PALETTE", "FADE_SECONDS"]

# Okabe & Ito's colour-blind-safe categories (yellow left out: it vanishes on light
# ground), then darker tones; the terrain is drawn in greys so every hue stands out.
PALETTE = np.array([
    [230, 159, 0], [0, 114, 178], [213, 94, 0], [0, 158, 115], [204, 121, 167],
    [86, 180, 233], [120, 60, 20], [60, 60, 160], [40, 40, 40], [150, 30, 80],
], dtype=np.uint8)  # fmt: skip
UNKNOWN_COLOR = np.array([110, 110, 110], dtype=np.uint8)
HIGHLIGHT_COLOR = "#ff1493"
ROUTE_COLOR = "#6a3d9a"
WALKABLE_COLOR = "#37474f"
CLOSED_COLOR = "#b71c1c"  # a shut door, as a wall
FADE_SECONDS = 8.0  # footprints fade to light grey over this age [s]
ENERGY_CMAP = "plasma"
ENERGY_RANGE = (0.0, 0.85)  # of the colour map: its light yellow end would vanish
_BODY_CATEGORY = {"energy": "group", "group": "group", "planner": "planner",
                  "style": "style", "agent": "agent"}
_TITLES = {"energy": "step energy [J/kg]", "group": "group", "planner": "planner",
           "style": "style", "agent": "walker"}


def _ground_colormap():
    """Light to mid greys: the ground recedes, footprints and bodies carry the colour."""
    from matplotlib.colors import LinearSegmentedColormap

    return LinearSegmentedColormap.from_list("ground", ["#e4e1d8", "#b4afa5", "#8a857b"])


def _energy_colormap():
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap

    return ListedColormap(colormaps[ENERGY_CMAP](np.linspace(*ENERGY_RANGE, 256)), "energy")


def _lookup_table(cmap, lo: float, hi: float) -> pv.LookupTable:
    table = pv.LookupTable(cmap=cmap)
    table.scalar_range = (lo, hi if hi > lo else lo + 1.0)
    return table


def _rgb(values: np.ndarray, cmap, lo: float, hi: float) -> np.ndarray:
    """Colours (n, 3) uint8 of ``values`` through ``cmap`` over [lo, hi]."""
    span = hi - lo if hi > lo else 1.0
    x = np.clip((np.asarray(values, dtype=float) - lo) / span, 0.0, 1.0)
    return (np.asarray(cmap(np.nan_to_num(x, nan=0.0)))[:, :3] * 255).astype(np.uint8)


def _category_rgb(codes: np.ndarray) -> np.ndarray:
    """Palette colour (k, 3) uint8 of each category code (grey for -1)."""
    codes = np.asarray(codes, dtype=int)
    out = PALETTE[np.mod(codes, len(PALETTE))]
    out[codes < 0] = UNKNOWN_COLOR
    return out


class SceneView:
    """A scene's actors and overlays in one region of a plotter, animated by
    :meth:`set_time`.

    Parameters
    ----------
    scene : Scene
    plotter : pyvista.Plotter
    layout : Layout
        The region of the window this view uses.
    subplot : int
        Column of the plotter's subplot that holds this view's 3-D renderer.

    Attributes
    ----------
    bodies : SolidBodies or None
        All walkers' bodies (one mesh).
    footprints : FootprintMesh or None
        All footprints (one mesh).
    overlay : Overlay
        Title, time, legend, colour bars and the followed walker's info.
    playback : Playback
        Current time, play/pause and speed (the lead view's drives linked views).
    """

    def __init__(self, scene, plotter: pv.Plotter, layout: Layout | None = None,
                 subplot: int = 0) -> None:
        layout = Layout() if layout is None else layout
        self.scene = scene
        self.plotter = plotter
        self._subplot = subplot
        plotter.subplot(0, subplot)
        self.renderer = plotter.renderer
        self.layout = layout
        self.color = scene.color
        self.follow = scene.follow
        self.linked: list[SceneView] = []
        start, end = scene.time_range
        self.playback = Playback(start, end, scene.frame_dt)
        self.actors: dict[str, pv.Actor] = {}
        self.bodies: SolidBodies | None = None
        self.footprints: FootprintMesh | None = None
        self.walkers: Walkers = scene.walkers if scene.walkers is not None else Walkers.empty()
        self.frame: int | None = None
        self._shown_time: float | None = None
        self._time: float | None = None  # the time this view shows [s]
        self.agent_ids = np.zeros(0, dtype=int)
        self.agent_roots = np.zeros((0, 3))
        self.agent_positions = np.zeros((0, 0, 3))
        self._framed: int | None = None
        self.overlay = Overlay(plotter, layout, self.renderer)
        self.renderer.set_background("#aebbc6", top="#eef2f5")
        self.bounds = self._add_world()
        self._add_bodies()
        self._add_footprints()
        self._lay_out()
        self._set_colors()
        # a resized window (by the user, or by a web page) gets fonts of its new size
        self.overlay.renderer.AddObserver("StartEvent", lambda *_: self._lay_out(redraw=True))
        cam.frame(self.renderer, self.bounds)
        self._clip()

    # --- building -------------------------------------------------------------------

    def _add(self, name: str, mesh, **kwargs) -> None:
        self.plotter.subplot(0, self._subplot)
        self.actors[name] = self.plotter.add_mesh(mesh, name=name, render=False, **kwargs)

    def _add_world(self) -> np.ndarray:
        scene = self.scene
        bounds = None
        if scene.terrain is not None:
            ground = terrain_mesh(scene.terrain)
            heights = ground.point_data["height"]
            lo, hi = float(heights.min()), float(heights.max())
            self._height_range = (lo, hi) if hi - lo > 1e-6 else None
            self._add("terrain", ground, scalars="height", cmap=_ground_colormap(),
                      smooth_shading=False, show_scalar_bar=False, ambient=0.15,
                      clim=[lo, hi if hi - lo > 1e-6 else lo + 1.0])
            edges = terrain_edges(ground)
            if edges.n_cells:
                self._add("terrain edges", edges, color="#55524c", line_width=1)
            bounds = np.array(ground.bounds)
        else:
            self._height_range = None
            if scene.walkable_area is not None and not scene.walkable_area.is_empty:
                ground = flat_ground(scene.walkable_area)
                if ground.n_points:
                    self._add("terrain", ground, color="#d9d6cc", ambient=0.15)
        if scene.walkable_area is not None and not scene.walkable_area.is_empty:
            outline = outline_lines(scene.walkable_area, scene.terrain)
            if outline.n_points:
                self._area_index = None
                self._add("walkable area", outline, color=WALKABLE_COLOR, line_width=3)
                if bounds is None:
                    bounds = np.array(outline.bounds)
        graph = getattr(scene.routes, "graph", None)
        if graph is not None and graph.number_of_nodes():
            edges_mesh, nodes = route_lines(graph, scene.terrain)
            if edges_mesh.n_points:
                self._add("route edges", edges_mesh, color=ROUTE_COLOR, line_width=2)
            if nodes is not None:
                self._add("route nodes", nodes, color=ROUTE_COLOR,
                          point_size=max(4, round(self.overlay.pixels[1] / 90)),
                          render_points_as_spheres=True)
        if bounds is None:
            bounds = np.array([-5.0, 5.0, -5.0, 5.0, 0.0, 2.0])
        return bounds

    def _add_bodies(self) -> None:
        poses = self.scene.poses
        if poses is None or not len(poses.times):
            return
        self.bodies = SolidBodies(poses.names, poses.parents, detail=detail_for(poses.n_agents),
                                  pole_radius=getattr(poses, "pole_radius", 0.035))
        self._root = int(np.flatnonzero(np.asarray(poses.parents) < 0)[0])
        self._timeline = PoseTimeline(poses, interpolate=self.scene.interpolate)
        self._show_time(float(poses.times[0]))
        self._add("agents", self.bodies.mesh, scalars="rgb", rgb=True, interpolation="gouraud",
                  show_scalar_bar=False, culling="back")
        ring = pv.Disc(inner=0.38, outer=0.5, c_res=32).triangulate()
        marker = pv.Cone(center=(0.0, 0.0, 0.0), direction=(0.0, 0.0, -1.0), height=0.25,
                         radius=0.12, resolution=12)
        self._add("highlight", ring.append_polydata(marker.translate((0.0, 0.0, 2.05))),
                  color=HIGHLIGHT_COLOR,
                  ambient=0.5, show_scalar_bar=False)
        self.actors["highlight"].visibility = False

    def _add_footprints(self) -> None:
        steps = self.scene.footsteps
        if not len(steps):
            return
        normals = None
        if self.scene.terrain is not None and hasattr(self.scene.terrain, "normal"):
            normals = np.asarray(self.scene.terrain.normal(steps.position[:, :2]), dtype=float)
        self.footprints = FootprintMesh(steps, normals=normals)
        energy = steps.energy[np.isfinite(steps.energy)]
        # 2nd-98th percentile: a few very costly steps must not wash out the rest
        lo, hi = np.percentile(energy, [2, 98]) if energy.size else (0.0, 1.0)
        self._energy_range = (float(lo), float(hi) if hi > lo else float(lo) + 1.0)
        self._add("footprints", self.footprints.mesh, scalars="rgb", rgb=True,
                  show_scalar_bar=False, ambient=0.35)

    # --- colours and overlays -------------------------------------------------------

    def _lay_out(self, redraw: bool = False) -> None:
        """Fonts for the current window size; the header and panel redrawn when it changed."""
        pixels = self.overlay.pixels
        if getattr(self, "_laid_out_for", None) == pixels:
            return
        self._laid_out_for = pixels
        self._font = self.overlay.font()
        self.overlay.text("title", self.scene.title, (0.015, 0.985),
                          size=round(1.25 * self._font), bold=True)
        if redraw:
            self._draw_panel()
            if self._time is not None:
                self._update(self._time)

    def _codes(self, category: str, ids: np.ndarray) -> np.ndarray:
        if category == "agent":
            return np.asarray(ids, dtype=int)
        return self.walkers.codes(category, ids)

    def _labels(self, category: str) -> list[str]:
        return self.walkers.labels(category) if category != "agent" else []

    def _body_colors(self, ids: np.ndarray) -> np.ndarray:
        return _category_rgb(self._codes(_BODY_CATEGORY[self.color], ids))

    def _set_colors(self) -> None:
        """Colour bodies and footprints for the current colour mode; redo the panel."""
        if self.bodies is not None and len(self.agent_ids):
            self.bodies.update(self.agent_positions, self._body_colors(self.agent_ids))
        steps = self.scene.footsteps
        if self.footprints is not None:
            if self.color == "energy":
                colors = _rgb(steps.energy, _energy_colormap(), *self._energy_range)
            else:
                colors = _category_rgb(self._codes(self.color, steps.agent))
            self.footprints.set_colors(colors)
        self._draw_panel()

    def _draw_panel(self) -> None:
        """Legend, colour bars and info, top to bottom in the right panel."""
        ov, size = self.overlay, self._font
        x = ov.layout.panel_x() + 0.015
        line = 1.45 * size / ov.pixels[1]
        for name in ov.names():
            if name.startswith(("legend", "bar")):
                ov.remove(name)
        y = 1.0 - ov.layout.header - 0.01
        entries: list[tuple[str, tuple]] = []
        category = _BODY_CATEGORY[self.color]
        if self.bodies is not None and category != "agent":
            ov.text("legend heading", f"walkers by {category}", (x, y), size=size, bold=True)
            y -= line
            labels = self._labels(category)
            for i, label in enumerate(labels[:8]):
                entries.append((label, tuple(PALETTE[i % len(PALETTE)] / 255)))
            if len(labels) > 8:
                entries.append((f"+{len(labels) - 8} more", tuple(UNKNOWN_COLOR / 255)))
        if self.follow is not None:
            entries.append(("followed walker", pv.Color(HIGHLIGHT_COLOR).float_rgb))
        if "walkable area" in self.actors:
            entries.append(("walkable area", pv.Color(WALKABLE_COLOR).float_rgb))
        areas = self.scene.walkable_areas
        if areas is not None and len(areas.areas) > 1:
            entries.append(("closed (events)", pv.Color(CLOSED_COLOR).float_rgb))
        if "route edges" in self.actors:
            entries.append(("route graph", pv.Color(ROUTE_COLOR).float_rgb))
        for i, (label, color) in enumerate(entries):
            ov.text(f"legend {i} {label}", f"— {label}", (x, y), size=size, color=color,
                    bold=True)
            y -= line
        inset = 2.2 * size / ov.pixels[0]  # half a label's width: labels stay in the panel
        bar = (x + inset, x + ov.layout.panel - 0.03 - inset)
        bar_h = 3.8 * line
        if self.footprints is not None and self.color == "energy":
            y -= 0.3 * line
            ov.color_bar("bar energy", _lookup_table(_energy_colormap(), *self._energy_range),
                         "step energy [J/kg]", (bar[0], y - bar_h, bar[1], y), size=size,
                         title_x=x)
            y -= bar_h + 0.5 * line
        if self._height_range is not None:
            y -= 0.3 * line
            ov.color_bar("bar height", _lookup_table(_ground_colormap(), *self._height_range),
                         "ground height [m]", (bar[0], y - bar_h, bar[1], y), size=size,
                         fmt="%.2f", title_x=x)
            y -= bar_h + 0.5 * line
        self._info_top = y

    def _draw_info(self, t: float) -> None:
        """The followed walker's id, group, planner, style, speed, step length, energy."""
        ov = self.overlay
        if self.follow is None:
            ov.remove("info")
            return
        row = self.walkers.index([self.follow])[0]
        group, planner, style = (("—",) * 3 if row < 0 else
                                 (self.walkers.group[row], self.walkers.planner[row],
                                  self.walkers.style[row]))
        status = walker_status(self.scene.footsteps, self.follow, t)
        present = self.agent_root(self.follow) is not None
        lines = [f"walker {self.follow}" + ("" if present else " (not here)"),
                 f"group: {group}", f"planner: {planner}", f"style: {style}",
                 f"speed: {status.speed:.2f} m/s", f"step length: {status.step_length:.2f} m",
                 f"energy so far: {status.energy:.1f} J/kg", f"steps so far: {status.steps}"]
        x = ov.layout.panel_x() + 0.015
        ov.text("info", "\n".join(lines), (x, self._info_top - 0.01), size=self._font)

    def set_color(self, color: str) -> None:
        """Colour by ``color`` (one of ``COLOR_FIELDS``): footprints by energy or by the
        walker's group / planner / style / id; bodies by the same category (group in
        energy mode)."""
        if color not in COLOR_FIELDS:
            raise invalid("SceneView", "color", f"one of {', '.join(COLOR_FIELDS)}", color)
        for view in (self, *self.linked):
            view.color = color
            view._set_colors()
            if view._time is not None:
                view._draw_info(view._time)

    # --- animation ------------------------------------------------------------------

    def _show_time(self, t: float) -> None:
        index, ids, positions = self._timeline.at_time(t)
        ids = np.asarray(ids)
        self.bodies.update(positions, self._body_colors(ids))
        self.agent_ids = ids
        self.agent_positions = positions
        self.agent_roots = np.asarray(positions)[:, self._root] if len(ids) else np.zeros((0, 3))
        self.frame = index
        self._shown_time = t

    def set_time(self, t: float) -> float:
        """Show the scene (and every linked one) at simulated time ``t`` [s], clamped to
        the lead's time range; returns it."""
        t = self.playback.seek(t)
        for view in (self, *self.linked):
            view._update(t)
        if self.follow is not None:
            root = self.agent_root(self.follow)
            if root is not None:
                if self._framed != self.follow:
                    box = np.repeat(root, 2) + np.array([-3.0, 3.0, -3.0, 3.0, -0.5, 1.5])
                    cam.frame(self.renderer, box, elevation=0.45, zoom=1.0)
                    self._framed = self.follow
                cam.follow(self.renderer, root)
        for view in (self, *self.linked):
            view._clip()
        return t

    def _clip(self) -> None:
        """Camera clipping range from the world's box raised by a body height (not from
        every actor's bounds, which would be recomputed for the moving meshes)."""
        b = np.asarray(self.bounds, dtype=float) + [-1.0, 1.0, -1.0, 1.0, -0.5, 2.5]
        self.renderer.ResetCameraClippingRange(*b)

    def _show_area(self, t: float) -> None:
        """Outline the walkable area current at time ``t`` [s] and draw what is shut then
        (a closed door) as a wall; rebuilt only when the area changes."""
        areas = self.scene.walkable_areas
        if areas is None or len(areas.areas) < 2 or "walkable area" not in self.actors:
            return
        k = areas.index(t)
        if k == getattr(self, "_area_index", None):
            return
        self._area_index = k
        terrain = self.scene.terrain
        self._add("walkable area", outline_lines(areas.at(t), terrain), color=WALKABLE_COLOR,
                  line_width=3)
        walls = closed_walls(self.scene.walkable_area, areas.at(t), terrain)
        if walls.n_points:
            self._add("closed", walls, color=CLOSED_COLOR, ambient=0.3)
        elif "closed" in self.actors:
            self.plotter.subplot(0, self._subplot)
            self.plotter.remove_actor(self.actors.pop("closed"), render=False)

    def _update(self, t: float) -> None:
        """Move this view's walkers, footprints, highlight, walkable area and texts to
        time ``t``."""
        self._time = t
        self._show_area(t)
        if self.bodies is not None and t != self._shown_time:
            self._show_time(t)
        if self.footprints is not None:
            trail = self.scene.footprint_trail
            self.footprints.show_window(-np.inf if trail is None else t - trail, t,
                                        fade=FADE_SECONDS)
        lead = self.playback
        root = self.agent_root(self.follow) if self.follow is not None else None
        if "highlight" in self.actors:
            self.actors["highlight"].visibility = root is not None
            if root is not None:
                feet = self.agent_positions[self.agent_ids == self.follow][0][:, 2].min()
                self.actors["highlight"].position = (root[0], root[1], feet + 0.015)
        self.overlay.text(
            "time", f"t = {t:6.2f} s    walkers: {len(self.agent_ids)}    "
            f"speed ×{lead.speed:g}", (0.015, 0.985 - 1.7 * self._font / self.overlay.pixels[1]),
            size=self._font)
        self._draw_info(t)

    def agent_root(self, agent_id: int) -> np.ndarray | None:
        """Root joint position (3,) [m] of an agent in the current frame, or None."""
        hit = np.flatnonzero(self.agent_ids == agent_id)
        return self.agent_roots[hit[0]] if hit.size else None

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
                follow = None
            elif len(self.agent_ids):
                follow = int(self.scene.follow if self.scene.follow is not None
                             else self.agent_ids[0])
            else:
                return
            for view in (self, *self.linked):
                view.follow = follow
                view._draw_panel()

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
        """Time slider (in the header band), keys and a playback timer on an interactive
        plotter.

        Parameters
        ----------
        interval : float
            Timer period [s].
        """
        t0, t1 = self.playback.start, self.playback.end
        if t1 > t0:
            x0, _, x1, y1 = self.layout.region
            y = y1 - 0.55 * self.layout.header * (y1 - self.layout.region[1])
            self._slider = self.plotter.add_slider_widget(
                self.set_time, rng=[t0, t1], value=self.playback.time, title="",
                style="modern", interaction_event="always", fmt="%.1f",
            )
            rep = self._slider.GetRepresentation()  # in window coordinates: the header
            for point, x in ((rep.GetPoint1Coordinate(), x0 + 0.5 * (x1 - x0)),
                             (rep.GetPoint2Coordinate(), x1 - 0.03 * (x1 - x0))):
                point.SetCoordinateSystemToNormalizedDisplay()
                point.SetValue(x, y)
        for key, action in self.key_bindings().items():
            self.plotter.add_key_event(key, action)
        if t1 > t0:
            def on_timer(_step):
                if self.playback.playing:
                    self.tick(interval)
                    self.plotter.render()

            self.plotter.add_timer_event(max_steps=10**9, duration=int(interval * 1000),
                                         callback=on_timer)


def attach_views(scenes: Sequence, plotter: pv.Plotter) -> SceneView:
    """Views of ``scenes`` side by side in one window (a plotter with ``shape=(1, n)``),
    one time and one camera for all.

    Returns
    -------
    SceneView
        The lead view (the first scene's); its playback covers every scene's time range
        and its :meth:`~SceneView.set_time`, keys and camera drive the others.
    """
    n = len(scenes)
    if n == 0 or plotter.shape != (1, n):
        raise invalid("attach_views", "plotter.shape", f"(1, {n}) for {n} scenes",
                      plotter.shape)
    views = [SceneView(scene, plotter, Layout(region=(i / n, 0.0, (i + 1) / n, 1.0)),
                       subplot=i) for i, scene in enumerate(scenes)]
    lead = views[0]
    lead.linked = views[1:]
    if n > 1:
        starts, ends = zip(*(s.time_range for s in scenes), strict=True)
        lead.playback = Playback(min(starts), max(ends), min(s.frame_dt for s in scenes))
        bounds = np.array([v.bounds for v in views])
        union = np.column_stack([bounds[:, 0::2].min(axis=0), bounds[:, 1::2].max(axis=0)])
        cam.frame(lead.renderer, union.ravel())
        for view in views[1:]:
            view.renderer.camera = lead.renderer.camera
        ranges = np.array([v._energy_range for v in views if v.footprints is not None])
        if len(ranges):  # one energy scale for all, so colours compare across runs
            for view in views:
                view._energy_range = (float(ranges[:, 0].min()), float(ranges[:, 1].max()))
                view._set_colors()
    plotter.subplot(0, 0)
    return lead
