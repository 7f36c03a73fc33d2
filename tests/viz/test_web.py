"""``crowdwalk view --web``: the scene served through trame, seen in headless Chromium."""

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from crowdwalk.viz.scene import Scene
from crowdwalk.viz.web import free_port

ROOT = Path(__file__).parents[2]


def _blocks(image, box, k=8):
    """Mean colour of k x k pixel blocks of the view's part of a page screenshot."""
    x, y, w, h = (int(round(v)) for v in box)
    view = image[y:y + h, x:x + w].astype(float)
    h, w = (h // k) * k, (w // k) * k
    return view[:h, :w].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))


def test_browser_shows_the_scene_the_off_screen_renderer_draws(offscreen, compare_folder,
                                                                chromium):
    run = compare_folder / "best_first"
    port = free_port()
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    server = subprocess.Popen(
        [sys.executable, "-m", "crowdwalk.cli", "view", "--web", str(run), "--port", str(port),
         "--time", "3", "--follow", "3"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    try:
        address = server.stdout.readline().strip()  # printed before serving
        assert f"http://localhost:{port}/" in address, address
        url = f"http://localhost:{port}/"
        deadline = time.monotonic() + 60
        image, box = chromium(url, (1024, 700), timeout=deadline - time.monotonic(),
                              ready=lambda im, b: _blocks(im, b).std() > 15)
        assert box is not None and box[2] > 500 and box[3] > 300
        page = _blocks(image, box)
        size = (int(round(box[2])), int(round(box[3])))
        same = Scene.from_run(run, follow=3).image(time=3.0, size=size)
        wide = Scene.from_run(run).image(time=3.0, size=size)
        full = (0, 0, *size)
        error_same = np.abs(page - _blocks(same, full)).mean()
        error_wide = np.abs(page - _blocks(wide, full)).mean()
        assert error_same < 4.0  # the page shows this scene (JPEG-streamed) ...
        assert error_wide > 3 * error_same  # ... and a different view would not match
    finally:
        server.terminate()
        server.wait(timeout=20)
