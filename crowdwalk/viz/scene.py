"""The viewer's scene: one code path for the interactive window, the CLI and notebooks.

:class:`Scene` holds what is shown (world, poses, footsteps) and builds a
:class:`SceneView` on any pyvista plotter — an interactive window (:meth:`Scene.show`)
or an off-screen one (:meth:`Scene.render_png`, :meth:`Scene.render_movie`).
``SceneView.set_time`` moves every agent and footprint to a simulated time by updating
mesh points in place; the view never adds an actor per agent.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid
from crowdwalk.viz import camera as cam
from crowdwalk.viz.figures import StickFigures
from crowdwalk.viz.footprints import COLOR_FIELDS, FootprintMesh, Footsteps
from crowdwalk.viz.playback import Playback
from crowdwalk.viz.sources import PoseSource, PoseTimeline, RunPoses, TrajectoryPoses
from crowdwalk.viz.world_meshes import (
    flat_ground,
    outline_lines,
    route_lines,
    terrain_edges,
    terrain_mesh,
)

__all__ = ["Scene", "SceneView", "COLOR_FIELDS", "MOVIE_SUFFIXES"]

MOVIE_SUFFIXES = (".gif", ".mp4")
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


def _head_joint(names: list[str], first_positions: np.ndarray | None) -> int:
    """The joint that carries the head: by H-Anim name, else the highest joint."""
    lower = [n.lower() for n in names]
    for name in _HEAD_NAMES:
        if name in lower:
            return lower.index(name)
    if first_positions is not None and len(first_positions):
        return int(np.argmax(first_positions[:, :, 2].mean(axis=0)))
    return len(names) - 1


def parse_size(text: str) -> tuple[int, int]:
    """``"WxH"`` to (width, height) [px]."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise invalid("render", "size", "WIDTHxHEIGHT in pixels, e.g. 640x480", text) from None
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise invalid("render", "size", "between 16x16 and 8192x8192 [px]", text)
    return w, h


@dataclass
class Scene:
    """What the viewer shows.

    Parameters
    ----------
    terrain : crowdwalk.terrain.Terrain, optional
        Ground (``mesh()``, ``height(xy)``).
    routes : crowdwalk.routes.RouteGraph, optional
        Route graph (``graph`` with node attribute ``pos`` [m]) and walkable area.
    walkable_area : shapely geometry, optional
        Overrides ``routes.walkable_area`` [m].
    poses : PoseSource, optional
        Agents' joint positions per output frame.
    footsteps : Footsteps, optional
        Every foot placement of the run.
    color : {"energy", "planner", "agent"}
        What colours the footprints.
    follow : int, optional
        Agent id the camera follows.
    footprint_trail : float, optional
        Show only footprints placed in the last this many seconds [s]; all when None.
    title : str
        Shown in the window title and the corner label.
    interpolate : bool
        Blend poses linearly between stored output frames (display only).
    """

    terrain: object | None = None
    routes: object | None = None
    walkable_area: object | None = None
    poses: PoseSource | None = None
    footsteps: Footsteps = field(default_factory=Footsteps.empty)
    color: str = "energy"
    follow: int | None = None
    footprint_trail: float | None = None
    title: str = "crowdwalk"
    interpolate: bool = True

    def __post_init__(self) -> None:
        if self.color not in COLOR_FIELDS:
            raise invalid("Scene", "color", f"one of {', '.join(COLOR_FIELDS)}", self.color)
        if self.footprint_trail is not None and not self.footprint_trail > 0:
            raise invalid("Scene", "footprint_trail", "> 0 [s]", self.footprint_trail)
        if self.walkable_area is None and self.routes is not None:
            self.walkable_area = getattr(self.routes, "walkable_area", None)

    # --- construction ---------------------------------------------------------------

    @classmethod
    def from_scenario(cls, path: str | Path, **options) -> Scene:
        """The world of a scenario file before any run (no agents)."""
        from crowdwalk.scenario import load_scenario
        from crowdwalk.world import build_world

        world = build_world(load_scenario(path))
        options.setdefault("title", Path(path).stem)
        return cls(terrain=world.terrain, routes=world.routes, **options)

    @classmethod
    def from_run(cls, path: str | Path, **options) -> Scene:
        """A run folder written by ``crowdwalk run`` (``crowdwalk.record`` layout)."""
        from crowdwalk.record import open_run

        run = open_run(path)
        terrain = routes = None
        if run.scenario_path.exists():
            from crowdwalk.scenario import load_scenario
            from crowdwalk.world import build_world

            world = build_world(load_scenario(run.scenario_path))
            terrain, routes = world.terrain, world.routes
        stored = run.poses()
        if stored is not None and len(stored.times):
            poses: PoseSource | None = RunPoses(stored)
        else:
            trajectories = run.trajectories()
            poses = TrajectoryPoses(trajectories) if len(trajectories.frame) else None
        footsteps = (
            Footsteps.from_table(run.footsteps()) if run.footsteps_path.exists()
            else Footsteps.empty()
        )
        options.setdefault("title", Path(path).name)
        return cls(
            terrain=terrain, routes=routes, walkable_area=run.walkable_area(), poses=poses,
            footsteps=footsteps, **options,
        )

    @classmethod
    def load(cls, path: str | Path, **options) -> Scene:
        """A run folder or a scenario file, whichever ``path`` is."""
        path = Path(path)
        if path.is_dir():
            return cls.from_run(path, **options)
        if not path.exists():
            raise FileNotFoundError(2, "No such run folder or scenario file", str(path))
        return cls.from_scenario(path, **options)

    # --- time -----------------------------------------------------------------------

    @property
    def time_range(self) -> tuple[float, float]:
        """First and last simulated time with something to show [s]."""
        if self.poses is not None and len(self.poses.times):
            return float(self.poses.times[0]), float(self.poses.times[-1])
        if len(self.footsteps):
            return float(self.footsteps.time.min()), float(self.footsteps.time.max())
        return 0.0, 0.0

    @property
    def frame_dt(self) -> float:
        """Interval between output frames [s] (0.04 s when unknown)."""
        if self.poses is not None and len(self.poses.times) > 1:
            return float(np.median(np.diff(self.poses.times)))
        return 0.04

    # --- views ----------------------------------------------------------------------

    def attach(self, plotter: pv.Plotter) -> SceneView:
        """Add this scene's actors to ``plotter``; returns the view that animates them."""
        return SceneView(self, plotter)

    def show(self, time: float | None = None, size: tuple[int, int] = (1280, 800)) -> None:
        """Open an interactive window (needs a display). Keys: space play/pause,
        Right/Left one frame, Up/Down speed, c colour, f follow on/off."""
        plotter = pv.Plotter(window_size=size, title=f"crowdwalk — {self.title}")
        view = self.attach(plotter)
        view.set_time(self.time_range[0] if time is None else time)
        view.install_controls()
        plotter.show()

    def render_png(
        self, out: str | Path, time: float | None = None, size: tuple[int, int] = (1280, 800)
    ) -> Path:
        """Render one instant off-screen to a PNG file.

        Parameters
        ----------
        out : path
            PNG file to write.
        time : float, optional
            Simulated time [s]; the end of the run when omitted.
        size : (int, int)
            Image width and height [px].
        """
        out = Path(out)
        t = self.time_range[1] if time is None else float(time)
        with _offscreen(size) as plotter:
            view = self.attach(plotter)
            view.set_time(t)
            out.parent.mkdir(parents=True, exist_ok=True)
            plotter.render()
            plotter.screenshot(str(out))
        return out

    def render_movie(
        self,
        out: str | Path,
        start: float | None = None,
        end: float | None = None,
        fps: float | None = None,
        size: tuple[int, int] = (960, 600),
        speed: float = 1.0,
        progress: Callable[[int, int], None] | None = None,
    ) -> Path:
        """Render a time range off-screen to a GIF or MP4 file.

        Parameters
        ----------
        out : path
            ``.gif`` or ``.mp4`` file.
        start, end : float, optional
            Simulated time range [s]; the whole run when omitted.
        fps : float, optional
            Frames per second of the movie [1/s]; the run's output rate when omitted.
        size : (int, int)
            Frame width and height [px].
        speed : float
            Simulated seconds per movie second.
        progress : callable(done, total), optional
            Called after every written frame.
        """
        out = Path(out)
        suffix = out.suffix.lower()
        if suffix not in MOVIE_SUFFIXES:
            raise invalid("render", "out", f"a file ending in {' or '.join(MOVIE_SUFFIXES)}", out)
        t0, t1 = self.time_range
        start = t0 if start is None else float(start)
        end = t1 if end is None else float(end)
        if not end >= start:
            raise invalid("render", "end", f">= start = {start} [s]", end)
        fps = 1.0 / self.frame_dt if fps is None else float(fps)
        if not 0 < fps <= 120:
            raise invalid("render", "fps", "in (0, 120] [1/s]", fps)
        if not speed > 0:
            raise invalid("render", "speed", "> 0", speed)
        n_frames = int(np.floor((end - start) / speed * fps + 1e-9)) + 1
        times = start + speed * np.arange(n_frames) / fps
        out.parent.mkdir(parents=True, exist_ok=True)
        with _offscreen(size) as plotter:
            view = self.attach(plotter)
            if suffix == ".gif":
                plotter.open_gif(str(out), fps=fps)
            else:
                plotter.open_movie(str(out), framerate=fps, quality=7)
            for i, t in enumerate(times):
                view.set_time(float(t))
                plotter.render()
                plotter.write_frame()
                if progress is not None:
                    progress(i + 1, len(times))
        return out


class _offscreen:
    """Context manager: an off-screen plotter of a given size, closed on exit."""

    def __init__(self, size: tuple[int, int]) -> None:
        self.size = size

    def __enter__(self) -> pv.Plotter:
        from crowdwalk.viz.headless import configure_offscreen

        configure_offscreen()
        self.plotter = pv.Plotter(off_screen=True, window_size=list(self.size))
        return self.plotter

    def __exit__(self, *exc) -> None:
        self.plotter.close()


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

    def __init__(self, scene: Scene, plotter: pv.Plotter) -> None:
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
            sides=4 if large else 8, head_detail=0 if large else 2,
        )
        self._root = int(np.flatnonzero(np.asarray(poses.parents) < 0)[0])
        self._timeline = PoseTimeline(poses, interpolate=self.scene.interpolate)
        self._show_time(float(poses.times[0]))
        self._figures_actor = None
        self._add_figures_actor()

    def _add_figures_actor(self) -> None:
        if self.figures is None:
            return
        kwargs = dict(interpolation="gouraud", name="agents", show_scalar_bar=False,
                      culling="back")
        if self.color == "agent":
            kwargs.update(scalars="agent", cmap="tab20", clim=[0, AGENT_HUES])
        else:
            kwargs.update(color=FIGURE_COLOR, scalars=None)
        self._figures_actor = self.plotter.add_mesh(self.figures.mesh, **kwargs)

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
            kwargs.update(
                clim=[-0.5, n - 0.5], n_colors=n,
                annotations={float(i): name for i, name in enumerate(fp.planners)},
            )
            bar.update(n_labels=0)
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
        """Legend in the top right corner: each entry's label written in its colour.

        (VTK's legend box clips long labels at some window sizes; plain text does not.)
        """
        entries = []
        if self.figures is not None:
            entries.append(("agents", FIGURE_COLOR))
        if self.scene.walkable_area is not None:
            entries.append(("walkable area", WALKABLE_COLOR))
        if getattr(self.scene.routes, "graph", None) is not None:
            entries.append(("route graph", ROUTE_COLOR))
        size = self._font(8, minimum=4)  # pyvista doubles the size of positioned text
        line = 2.6 * size / self.plotter.window_size[1] * 1.3
        for i, (label, color) in enumerate(entries):
            text = self.plotter.add_text(
                f"{label} —", position=(0.985, 0.96 - i * line), viewport=True,
                font_size=size, color=color, name=f"legend {label}",
            )
            text.GetTextProperty().SetJustificationToRight()
            text.GetTextProperty().SetVerticalJustificationToTop()

    # --- animation ------------------------------------------------------------------

    def _show_time(self, t: float) -> None:
        index, ids, positions = self._timeline.at_time(t)
        self.figures.update(positions, np.mod(ids, AGENT_HUES))
        self.agent_ids = np.asarray(ids)
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
            self.set_color(COLOR_FIELDS[(COLOR_FIELDS.index(self.color) + 1) % 3])

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
                lambda value: self.set_time(value), rng=[t0, t1], value=self.playback.time,
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
