"""Visual inspection in pyvista: the only package of crowdwalk that imports pyvista.

One scene builder serves the interactive window, off-screen pictures and movies, the
CLI (``crowdwalk view``, ``crowdwalk render``) and notebooks::

    from crowdwalk.viz import Scene
    scene = Scene.from_run("runs/quickstart", color="energy")
    scene.render_png("frame.png", time=10.0, size=(1280, 800))
    rgb = scene.image(time=10.0)  # (800, 1280, 3) uint8, e.g. for a notebook
    scene.render_movie("walk.mp4", start=0.0, end=20.0)
    scene.show()  # interactive window (needs a display)
    planned, fixed = load_scenes(["runs/compare"])  # a `crowdwalk compare` folder
    planned.render_png("side_by_side.png", time=10.0, beside=[fixed])

Without a display, rendering goes through EGL (see :mod:`crowdwalk.viz.headless`).
"""

from crowdwalk.viz.bodies import SolidBodies
from crowdwalk.viz.camera import follow, oblique_view, project_to_pixels
from crowdwalk.viz.footprints import COLOR_FIELDS, FootprintMesh, Footsteps
from crowdwalk.viz.headless import (
    configure_offscreen,
    gl_available,
    has_display,
    offscreen_plotter,
)
from crowdwalk.viz.playback import Playback
from crowdwalk.viz.scene import Scene, load_scenes, parse_size, run_folders
from crowdwalk.viz.sources import ArrayPoses, PoseSource, RunPoses, TrajectoryPoses
from crowdwalk.viz.synthetic import synthetic_crowd
from crowdwalk.viz.view import SceneView, attach_views
from crowdwalk.viz.walkers import Walkers, walker_status

__all__ = [
    "COLOR_FIELDS",
    "ArrayPoses",
    "FootprintMesh",
    "Footsteps",
    "Playback",
    "PoseSource",
    "RunPoses",
    "Scene",
    "SceneView",
    "SolidBodies",
    "TrajectoryPoses",
    "Walkers",
    "attach_views",
    "configure_offscreen",
    "follow",
    "gl_available",
    "has_display",
    "load_scenes",
    "oblique_view",
    "offscreen_plotter",
    "parse_size",
    "project_to_pixels",
    "run_folders",
    "synthetic_crowd",
    "walker_status",
]
