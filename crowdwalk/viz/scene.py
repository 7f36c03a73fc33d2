"""The viewer's scene: one code path for the interactive window, the CLI and notebooks.

:class:`Scene` holds what is shown (world, poses, footsteps, who the walkers are) and
builds a :class:`~crowdwalk.viz.view.SceneView` on any pyvista plotter — an interactive
window (:meth:`Scene.show`) or an off-screen one (:meth:`Scene.render_png`,
:meth:`Scene.render_movie`). Every one of them takes ``beside=[other scenes]`` to show
runs side by side, linked in time and camera (:func:`load_scenes` opens several run
folders, or a ``crowdwalk compare`` output folder, that way).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyvista as pv

from crowdwalk.errors import invalid
from crowdwalk.viz.footprints import COLOR_FIELDS, Footsteps
from crowdwalk.viz.headless import offscreen_plotter
from crowdwalk.viz.sources import PoseSource, RunPoses, TrajectoryPoses
from crowdwalk.viz.view import SceneView, attach_views
from crowdwalk.viz.walkers import Walkers

__all__ = ["Scene", "SceneView", "COLOR_FIELDS", "MOVIE_SUFFIXES", "load_scenes", "parse_size",
           "run_folders"]

MOVIE_SUFFIXES = (".gif", ".mp4")


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
        Route graph (``graph`` with node attributes ``x``, ``y`` or ``pos`` [m]) and
        walkable area.
    walkable_area : shapely geometry, optional
        Overrides ``routes.walkable_area`` [m]: everywhere walkable at some time.
    walkable_areas : crowdwalk.record.WalkableAreas, optional
        The walkable area over time (doors shut by events): the view outlines the one
        current at the time shown and draws what is shut then as walls.
    poses : PoseSource, optional
        Agents' joint positions per output frame.
    footsteps : Footsteps, optional
        Every foot placement of the run.
    walkers : Walkers, optional
        Group, planner and style of each walker (from the footsteps when omitted).
    color : {"energy", "group", "planner", "style", "agent"}
        What colours footprints (energy, or the walker's category) and bodies (the
        category; group in energy mode).
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
    walkable_areas: object | None = None
    poses: PoseSource | None = None
    footsteps: Footsteps = field(default_factory=Footsteps.empty)
    walkers: Walkers | None = None
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
        if self.follow is not None and self.poses is not None:
            ids = np.asarray(self.poses.agent_ids)
            if self.follow not in ids:
                shown = f"{ids.min()}..{ids.max()}" if len(ids) else "none"
                raise invalid("Scene", "follow", f"an agent id of the run ({shown})",
                              self.follow)
        if self.walkable_area is None and self.routes is not None:
            self.walkable_area = getattr(self.routes, "walkable_area", None)
        if self.walkers is None:
            self.walkers = Walkers.from_footsteps(self.footsteps)

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
        options.setdefault("title", _run_title(run))
        return cls(
            terrain=terrain, routes=routes, walkable_area=run.walkable_area(),
            walkable_areas=run.walkable_areas(), poses=poses,
            footsteps=footsteps, walkers=Walkers.from_run(run, footsteps), **options,
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

    def attach(self, plotter: pv.Plotter, beside: Sequence[Scene] = ()) -> SceneView:
        """Add this scene's actors (and those of ``beside``, each in its own column of a
        plotter with ``shape=(1, 1 + len(beside))``) to ``plotter``; returns the lead view
        that animates them all."""
        return attach_views([self, *beside], plotter)

    def show(self, time: float | None = None, size: tuple[int, int] = (1280, 800),
             beside: Sequence[Scene] = ()) -> None:
        """Open an interactive window of ``size`` [px] at ``time`` [s] (default: the start;
        needs a display), with ``beside`` scenes linked side by side. Keys: space
        play/pause, Right/Left one frame, Up/Down speed, c colour, f follow on/off."""
        titles = " | ".join(s.title for s in (self, *beside))
        plotter = pv.Plotter(off_screen=False, window_size=size, shape=(1, 1 + len(beside)),
                             border=False, title=f"crowdwalk — {titles}")
        view = self.attach(plotter, beside)
        view.set_time(view.playback.start if time is None else time)
        view.install_controls()
        plotter.show()

    def image(self, time: float | None = None, size: tuple[int, int] = (1280, 800),
              beside: Sequence[Scene] = ()):
        """Render one instant off-screen and return it (e.g. to show in a notebook).

        Parameters
        ----------
        time : float, optional
            Simulated time [s]; the end of the run when omitted.
        size : (int, int)
            Image width and height [px].
        beside : sequence of Scene
            Scenes shown side by side with this one, at the same time and camera.

        Returns
        -------
        (height, width, 3) uint8
            RGB image.
        """
        with offscreen_plotter(size, columns=1 + len(beside)) as plotter:
            view = self.attach(plotter, beside)
            view.set_time(view.playback.end if time is None else float(time))
            plotter.render()
            return plotter.screenshot(return_img=True)

    def render_png(
        self, out: str | Path, time: float | None = None, size: tuple[int, int] = (1280, 800),
        beside: Sequence[Scene] = (),
    ) -> Path:
        """Render ``time`` [s] off-screen at ``size`` [px] to a PNG file (see :meth:`image`);
        returns its path."""
        import imageio.v3 as iio

        out = Path(out)
        image = self.image(time, size, beside)
        out.parent.mkdir(parents=True, exist_ok=True)
        iio.imwrite(out, image)
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
        beside: Sequence[Scene] = (),
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
        beside : sequence of Scene
            Scenes shown side by side with this one.
        """
        out = Path(out)
        suffix = out.suffix.lower()
        if suffix not in MOVIE_SUFFIXES:
            raise invalid("render", "out", f"a file ending in {' or '.join(MOVIE_SUFFIXES)}", out)
        scenes = (self, *beside)
        start = min(s.time_range[0] for s in scenes) if start is None else float(start)
        end = max(s.time_range[1] for s in scenes) if end is None else float(end)
        if not end >= start:
            raise invalid("render", "end", f">= start = {start} [s]", end)
        fps = 1.0 / min(s.frame_dt for s in scenes) if fps is None else float(fps)
        if not 0 < fps <= 120:
            raise invalid("render", "fps", "in (0, 120] [1/s]", fps)
        if not speed > 0:
            raise invalid("render", "speed", "> 0", speed)
        n_frames = int(np.floor((end - start) / speed * fps + 1e-9)) + 1
        times = start + speed * np.arange(n_frames) / fps
        out.parent.mkdir(parents=True, exist_ok=True)
        with offscreen_plotter(size, columns=len(scenes)) as plotter:
            view = self.attach(plotter, beside)
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


def _run_title(run) -> str:
    """A run's title: its scenario name and the planners its walkers used."""
    summary = run.summary
    planners = sorted({g.get("planner", "") for g in summary.get("groups", {}).values()} - {""})
    name = summary.get("scenario") or run.path.name
    return f"{name} ({', '.join(planners)})" if planners else str(name)


def run_folders(path: str | Path) -> list[Path]:
    """The run folders ``path`` stands for: itself when it is one (it holds
    ``trajectories.sqlite``), else its sub-folders that are (a ``crowdwalk compare``
    output folder, one run per planner), sorted by name."""
    path = Path(path)
    if (path / "trajectories.sqlite").exists() or not path.is_dir():
        return [path]
    runs = sorted(p for p in path.iterdir() if (p / "trajectories.sqlite").exists())
    return runs or [path]


def load_scenes(paths: Sequence[str | Path], **options) -> list[Scene]:
    """Scenes of run folders, ``crowdwalk compare`` output folders (each of their runs)
    or scenario files, in order, for viewing side by side."""
    return [Scene.load(run, **options) for path in paths for run in run_folders(path)]
