"""Camera helpers: project world points to image pixels, frame a scene, follow an agent."""

from __future__ import annotations

import numpy as np

__all__ = ["project_to_pixels", "oblique_view", "follow", "frame"]


def project_to_pixels(plotter, points: np.ndarray, renderer=None) -> np.ndarray:
    """Pixel coordinates of world points in the plotter's current image.

    Parameters
    ----------
    plotter : pyvista.Plotter
    points : (n, 3) float
        World points [m].
    renderer : vtkRenderer, optional
        The renderer (and viewport) that draws them; the plotter's current one when
        omitted.

    Returns
    -------
    (n, 2) float
        Column and row [px] (row 0 at the top, as in ``screenshot()`` images); points
        behind the camera get NaN.
    """
    renderer = plotter.renderer if renderer is None else renderer
    window_w, window_h = plotter.window_size
    vx0, vy0, vx1, vy1 = renderer.GetViewport()
    width, height = (vx1 - vx0) * window_w, (vy1 - vy0) * window_h
    camera = renderer.GetActiveCamera()
    matrix = camera.GetCompositeProjectionTransformMatrix(width / height, -1.0, 1.0)
    m = np.array([[matrix.GetElement(i, j) for j in range(4)] for i in range(4)])
    pts = np.column_stack([np.asarray(points, dtype=float).reshape(-1, 3), np.ones(len(points))])
    clip = pts @ m.T
    with np.errstate(divide="ignore", invalid="ignore"):
        ndc = clip[:, :2] / clip[:, 3:4]
    ndc[clip[:, 3] <= 0] = np.nan
    col = vx0 * window_w + (ndc[:, 0] + 1.0) * 0.5 * width
    row = window_h - vy0 * window_h - (ndc[:, 1] + 1.0) * 0.5 * height
    return np.column_stack([col, row])


def oblique_view(bounds, elevation: float = 0.6, azimuth: float = -2.2):
    """A camera (position, focal point, view up) that frames the box from above and aside.

    Parameters
    ----------
    bounds : (6,) float
        xmin, xmax, ymin, ymax, zmin, zmax [m].
    elevation : float
        Angle of the line of sight above the ground plane [rad].
    azimuth : float
        Direction from the focal point to the camera in the ground plane, from +x [rad].
    """
    b = np.asarray(bounds, dtype=float)
    centre = np.array([(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2])
    radius = 0.5 * np.linalg.norm([b[1] - b[0], b[3] - b[2], b[5] - b[4]])
    distance = 2.0 * max(radius, 2.0)
    ce, se = np.cos(elevation), np.sin(elevation)
    direction = np.array([ce * np.cos(azimuth), ce * np.sin(azimuth), se])
    return [tuple(centre + distance * direction), tuple(centre), (0.0, 0.0, 1.0)]


def follow(renderer, target: np.ndarray) -> None:
    """Move the camera of ``renderer`` (or a plotter) with ``target`` (3,) [m], keeping its
    current offset (so a user can still orbit around the followed agent)."""
    camera = renderer.camera
    shift = np.asarray(target, dtype=float) - np.asarray(camera.focal_point)
    camera.position = tuple(np.asarray(camera.position) + shift)
    camera.focal_point = tuple(np.asarray(target, dtype=float))


def frame(renderer, bounds, elevation: float = 0.6, azimuth: float = -2.2,
          zoom: float = 1.5) -> None:
    """Look at the box ``bounds`` (6,) [m] obliquely (see :func:`oblique_view`) from as
    close as its bounding sphere fits the renderer's viewport, then ``zoom`` in (the
    sphere is a loose fit for a flat scene)."""
    renderer.camera_position = oblique_view(bounds, elevation=elevation, azimuth=azimuth)
    renderer.ResetCamera(*np.asarray(bounds, dtype=float))
    renderer.GetActiveCamera().Zoom(zoom)
