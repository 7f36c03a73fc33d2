"""The viewer in a web browser: the same scene served by trame (``crowdwalk view --web``).

The scene is rendered on the server, off-screen, by the very :class:`SceneView` the
window and ``crowdwalk render`` use; trame's remote view streams the pictures to the
page and sends mouse interaction back (rotate, zoom), and a toolbar carries the time
slider, play/pause and the colour mode. Works without a display (EGL).
"""

from __future__ import annotations

import asyncio
import socket
from collections.abc import Callable, Sequence

from crowdwalk.viz.footprints import COLOR_FIELDS
from crowdwalk.viz.headless import configure_offscreen

__all__ = ["build_app", "free_port", "serve"]


def free_port() -> int:
    """A TCP port that was free a moment ago on localhost."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def build_app(scenes: Sequence, *, time: float | None = None, size: tuple[int, int] = (1280, 800),
              name: str = "crowdwalk"):
    """A trame server showing ``scenes`` side by side (linked like ``crowdwalk view``).

    Parameters
    ----------
    scenes : sequence of Scene
    time : float, optional
        Simulated time shown first [s] (the start when omitted).
    size : (int, int)
        Initial render size [px] (the page resizes it).
    name : str
        Name of the trame server.

    Returns
    -------
    (trame Server, SceneView)
        The server (not started) and the lead view it animates.
    """
    import pyvista as pv
    from trame.app import get_server
    from trame.ui.vuetify3 import SinglePageLayout
    from trame.widgets import vtk as vtk_widgets
    from trame.widgets import vuetify3 as v3

    configure_offscreen(force=True)
    plotter = pv.Plotter(off_screen=True, window_size=list(size), shape=(1, len(scenes)),
                         border=False)
    view = scenes[0].attach(plotter, scenes[1:])
    pb = view.playback
    view.set_time(pb.start if time is None else time)
    plotter.render()

    server = get_server(name, client_type="vue3")
    state, ctrl = server.state, server.controller
    state.time = pb.time
    state.color = view.color
    state.playing = False

    @state.change("time")
    def _on_time(time, **_):
        if abs(float(time) - pb.time) > 1e-9:
            view.set_time(float(time))
            ctrl.view_update()

    @state.change("color")
    def _on_color(color, **_):
        if color != view.color:
            view.set_color(color)
            ctrl.view_update()

    @state.change("playing")
    def _on_playing(playing, **_):
        if bool(playing) != pb.playing:
            pb.toggle()

    async def _play(interval: float = 0.1) -> None:
        while True:
            await asyncio.sleep(interval)
            if pb.playing:
                view.tick(interval)
                with state:
                    state.time = pb.time
                    state.playing = pb.playing
                ctrl.view_update()

    ctrl.on_server_ready.add(lambda **_: asyncio.ensure_future(_play()))

    titles = " | ".join(s.title for s in scenes)
    with SinglePageLayout(server) as layout:
        layout.title.set_text(f"crowdwalk — {titles}")
        with layout.toolbar:
            v3.VSpacer()
            v3.VBtn(icon=("playing ? 'mdi-pause' : 'mdi-play'",), click="playing = !playing",
                    variant="text")
            v3.VSlider(v_model=("time", pb.time), min=pb.start, max=max(pb.end, pb.start + 1e-6),
                       step=pb.frame_dt, hide_details=True, density="compact",
                       style="max-width: 40%", thumb_label=True)
            v3.VSelect(v_model=("color", view.color), items=("colors", list(COLOR_FIELDS)),
                       hide_details=True, density="compact", style="max-width: 10rem")
        with layout.content:
            with v3.VContainer(fluid=True, classes="pa-0 fill-height"):
                remote = vtk_widgets.VtkRemoteView(plotter.ren_win, interactive_ratio=1)
                ctrl.view_update = remote.update
    server.plotter = plotter  # keep the plotter alive with the server
    return server, view


def serve(scenes: Sequence, *, port: int = 8080, time: float | None = None,
          host: str = "localhost", announce: Callable[[str], None] = print) -> None:
    """Serve ``scenes`` at ``http://host:port/`` until interrupted (port 0: a free one);
    ``announce`` receives the address before the server starts."""
    server, _ = build_app(scenes, time=time)
    port = free_port() if port == 0 else int(port)
    announce(f"crowdwalk viewer: http://{host}:{port}/  (Ctrl-C stops it)")
    server.start(port=port, host=host, open_browser=False, show_connection_info=False,
                 disable_logging=True)
