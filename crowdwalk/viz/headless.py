"""Off-screen rendering without a display.

VTK's PyPI wheel renders without a display through EGL (Mesa's software renderer is
enough) once ``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow`` is set before the first
render window is created. Without any GL stack VTK crashes the interpreter instead of
raising, so :func:`gl_available` asks a child process first.
"""

from __future__ import annotations

import contextlib
import functools
import os
import subprocess
import sys

__all__ = ["configure_offscreen", "display_problem", "gl_available", "has_display",
           "offscreen_plotter"]

_PROBE = """
import os
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
import pyvista as pv
pv.global_theme.multi_samples = 0
plotter = pv.Plotter(off_screen=True, window_size=(32, 32))
plotter.add_mesh(pv.Sphere(), color="red")
image = plotter.screenshot(return_img=True)
plotter.close()
print("ok" if image.shape == (32, 32, 3) and image.std() > 0 else "blank")
"""


def has_display() -> bool:
    """True when an X11 or Wayland display is available for interactive windows."""
    return display_problem() is None


def display_problem() -> str | None:
    """Why no interactive window can open (None when one can): VTK's windows on Linux are
    X11 (a Wayland session provides one through XWayland), so the X server named by
    ``DISPLAY`` is connected to once and released."""
    display = os.environ.get("DISPLAY")
    if not display:
        return "DISPLAY is unset"
    if sys.platform != "linux":
        return None
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("X11")
    if name is None:
        return None  # no libX11 to ask; let VTK try
    x11 = ctypes.CDLL(name)
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    handle = x11.XOpenDisplay(display.encode())
    if not handle:
        return f"the X display {display!r} cannot be opened"
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    x11.XCloseDisplay(handle)
    return None


def configure_offscreen(force: bool = False) -> None:
    """Prepare pyvista for off-screen rendering; call before the first Plotter.

    Selects the EGL render window when there is no display (or when ``force``) and
    switches off multi-sampling, which makes software rendering about 3x faster.
    """
    import pyvista as pv

    if force or not has_display():
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    pv.global_theme.multi_samples = 0
    pv.OFF_SCREEN = True


@functools.cache
def gl_available(timeout: float = 60.0) -> bool:
    """Whether off-screen rendering works here, probed safely in a child process.

    Parameters
    ----------
    timeout : float
        Seconds to wait for the probe [s].
    """
    try:
        result = subprocess.run(
            [sys.executable, "-c", _PROBE],
            capture_output=True,
            text=True,
            timeout=timeout,
        )
    except (OSError, subprocess.TimeoutExpired):
        return False
    return result.returncode == 0 and result.stdout.strip().endswith("ok")


@contextlib.contextmanager
def offscreen_plotter(size: tuple[int, int] = (1280, 800), columns: int = 1):
    """An off-screen :class:`pyvista.Plotter` of ``size`` (width, height) [px] with
    ``columns`` side-by-side subplots, closed on exit; configures EGL first when there is
    no display."""
    import pyvista as pv

    configure_offscreen()
    plotter = pv.Plotter(off_screen=True, window_size=list(size), shape=(1, columns),
                         border=False)
    try:
        yield plotter
    finally:
        plotter.close()
