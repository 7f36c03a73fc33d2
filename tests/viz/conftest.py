"""Fixtures of the viewer tests: an off-screen GL check and a small synthetic run."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="session")
def offscreen():
    """Configure off-screen rendering; skip when this machine has no GL stack at all."""
    from crowdwalk.viz.headless import configure_offscreen, gl_available

    if not gl_available():
        pytest.skip("no off-screen GL stack (install libegl1 libegl-mesa0 libgl1-mesa-dri)")
    configure_offscreen()
    return True


@pytest.fixture(scope="session")
def crowd():
    """Twelve synthetic walkers for 3 s at 10 fps in an 8 m x 6 m area."""
    from crowdwalk.viz.synthetic import synthetic_crowd

    return synthetic_crowd(12, duration=3.0, fps=10.0, area=(8.0, 6.0), seed=1)


@pytest.fixture(scope="session")
def write_run():
    """The function that writes a synthetic run folder (see :func:`_write_run`)."""
    return _write_run


def _write_run(path, poses, steps, fps=10.0):
    """Write a run folder (crowdwalk.record layout) holding the given poses and footsteps,
    without ``scenario.yaml`` so the viewer falls back to flat ground."""
    from crowdwalk.record import FOOTSTEP_COLUMNS, RunWriter

    wkt = "POLYGON ((-2 -2, 12 -2, 12 9, -2 9, -2 -2))"
    with RunWriter(path, scenario_text="", walkable_wkt=wkt, fps=fps,
                   skeleton=(poses.names, poses.parents)) as writer:
        for frame, t in enumerate(poses.times):
            ids, pos = poses.at(frame)
            k, nj = pos.shape[:2]
            root = pos[:, 0]
            writer.write_frame(frame, ids, root[:, :2], np.zeros(k), np.tile([1.0, 0.0], (k, 1)))
            quat = np.tile([1.0, 0.0, 0.0, 0.0], (k, 1))
            writer.write_pose(frame, t, ids, root, quat, np.tile(quat[:, None], (1, nj, 1)), pos,
                              np.zeros((k, 2), bool), np.zeros(k, bool))
        n = len(steps)
        rows = {c: np.zeros(n) for c in FOOTSTEP_COLUMNS}
        rows.update(agent=steps.agent, step=np.arange(n), time=steps.time, foot=np.full(n, "l"),
                    x=steps.position[:, 0], y=steps.position[:, 1], z=steps.position[:, 2],
                    energy=steps.energy, planner=steps.planner, group=np.full(n, "g"),
                    heading=steps.heading, kind=np.zeros(n, int), on_obstacle=np.zeros(n, int))
        writer.write_footsteps(rows)
    (path / "scenario.yaml").unlink()
    return path


@pytest.fixture(scope="session")
def compare_folder(tmp_path_factory):
    """A real short run of the bundled quickstart scenario (4 s), once with every group
    planning (best_first) and once unplanned (fixed), laid out like ``crowdwalk compare``
    output: ``OUT/best_first/`` and ``OUT/fixed/``."""
    from pathlib import Path

    from crowdwalk.crowd.run import RunOverrides, run_scenario

    scenario = Path(__file__).parents[2] / "scenarios" / "quickstart.yaml"
    if not scenario.exists():
        pytest.skip("scenarios/quickstart.yaml is not in this checkout")
    out = tmp_path_factory.mktemp("compare")
    for planner in ("best_first", "fixed"):
        run_scenario(scenario, out / planner, overrides=RunOverrides(planner=planner,
                                                                     duration=4.0))
    return out


# --- a headless Chromium driven through the DevTools protocol (aiohttp comes with trame) ---

CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync")
_VIEW_RECT = """JSON.stringify([...document.querySelectorAll('img')].map(e => {
    const r = e.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; }))"""


@pytest.fixture(scope="session")
def chromium():
    """``look(url, size, ready, timeout) -> (image (h, w, 3) uint8, view box (x, y, w, h)
    [px])``: opens ``url`` in headless Chromium and screenshots it until ``ready(image,
    box)`` and the page stopped changing; skips where no Chromium is installed."""
    import shutil

    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.skip("no chromium executable (install.sh installs the Debian package chromium)")
    return lambda *args, **kwargs: _asyncio_run(_look(exe, *args, **kwargs))


def _asyncio_run(coroutine):
    import asyncio

    return asyncio.run(coroutine)


async def _look(exe, url, size=(1280, 800), ready=lambda image, box: True, timeout=40.0):
    import asyncio
    import base64
    import json
    import subprocess
    import tempfile
    import time

    import aiohttp
    import imageio.v3 as iio
    import numpy as np

    from crowdwalk.viz.web import free_port

    port = free_port()
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        proc = subprocess.Popen(
            [exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", f"--remote-debugging-port={port}",
             f"--window-size={size[0]},{size[1]}", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + timeout
        try:
            async with aiohttp.ClientSession() as http:
                pages = []
                while not pages and time.monotonic() < deadline:
                    try:
                        async with http.get(f"http://127.0.0.1:{port}/json/list") as r:
                            pages = [p for p in await r.json() if p["type"] == "page"]
                    except aiohttp.ClientError:
                        await asyncio.sleep(0.2)
                async with http.ws_connect(pages[0]["webSocketDebuggerUrl"], max_msg_size=0) as ws:
                    calls = iter(range(1, 10**6))

                    async def call(method, **params):
                        n = next(calls)
                        await ws.send_str(json.dumps({"id": n, "method": method, "params": params}))
                        while True:
                            message = json.loads((await ws.receive()).data)
                            if message.get("id") == n:
                                return message.get("result", {})

                    await call("Page.navigate", url=url)
                    image, box, last = None, None, None
                    while time.monotonic() < deadline:
                        await asyncio.sleep(1.0)
                        found = await call("Runtime.evaluate", expression=_VIEW_RECT,
                                           returnByValue=True)
                        rects = json.loads(found.get("result", {}).get("value") or "[]")
                        box = max(rects, key=lambda r: r[2] * r[3]) if rects else None
                        shot = await call("Page.captureScreenshot", format="png")
                        image = iio.imread(base64.b64decode(shot["data"]))[..., :3]
                        steady = last is not None and last.shape == image.shape and np.abs(
                            last.astype(int) - image).mean() < 0.2
                        if box is not None and steady and ready(image, box):
                            break
                        last = image
                    return image, box
        finally:
            proc.kill()
            proc.wait()
