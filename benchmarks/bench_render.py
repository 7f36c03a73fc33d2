"""Off-screen render speed of the viewer for large crowds (issues 6 and 18: >= 10 frames/s
for 1,000 walkers at 640x480).

Builds a synthetic crowd (``crowdwalk.viz.synthetic_crowd``: 20-joint H-Anim skeletons
drawn as solid bodies, and their footsteps), or uses a run folder given with ``--run``,
and times whole frames the way ``crowdwalk render`` produces them: move every body and
footprint to the next time (``SceneView.set_time``: bodies, fading footprints, overlays),
render, read the image back.

    python benchmarks/bench_render.py [--agents 100 1000 2000] [--frames 40] [--run DIR]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def bench(scene, frames: int, size=(640, 480)) -> dict:
    """Mean milliseconds per frame for update, render and read-back."""
    from crowdwalk.viz.headless import offscreen_plotter

    t0, t1 = scene.time_range
    times = np.linspace(t0, t1, frames + 1)
    update = draw = read = 0.0
    with offscreen_plotter(size) as plotter:
        view = scene.attach(plotter)
        view.set_time(times[0])
        plotter.render()
        plotter.screenshot(return_img=True)  # warm-up: shaders, buffers
        for t in times[1:]:
            a = time.perf_counter()
            view.set_time(float(t))
            b = time.perf_counter()
            plotter.render()
            c = time.perf_counter()
            plotter.screenshot(return_img=True)
            d = time.perf_counter()
            update, draw, read = update + b - a, draw + c - b, read + d - c
        triangles = view.bodies.mesh.n_cells if view.bodies is not None else 0
        footprints = view.footprints.mesh.n_cells if view.footprints is not None else 0
    total = update + draw + read
    return dict(update=1e3 * update / frames, render=1e3 * draw / frames,
                read=1e3 * read / frames, fps=frames / total, triangles=triangles,
                footprint_triangles=footprints)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agents", type=int, nargs="+", default=[100, 1000, 2000])
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--run", help="also time this run folder")
    args = parser.parse_args()

    from rich.console import Console
    from rich.table import Table

    from crowdwalk.viz import Scene, configure_offscreen, gl_available, synthetic_crowd

    if not gl_available():
        raise SystemExit("no off-screen GL stack: install libegl1 libegl-mesa0 libgl1-mesa-dri")
    configure_offscreen()
    import shapely

    table = Table(title="crowdwalk render: off-screen frames at 640x480 (EGL, Mesa llvmpipe)")
    for column in ("scene", "walkers", "body tris", "footprint tris", "update ms",
                   "render ms", "read-back ms", "frames/s"):
        table.add_column(column, justify="right" if column != "scene" else "left")
    rows = []
    for n in args.agents:
        side = float(np.sqrt(n) * 2.0)  # about 4 m² per agent
        poses, steps = synthetic_crowd(n, duration=4.0, fps=25.0, area=(side, side), seed=0)
        area = shapely.box(-3, -3, side + 3, side + 3)
        rows.append(("synthetic, footprints of last 2 s", n,
                     Scene(poses=poses, footsteps=steps, walkable_area=area, footprint_trail=2.0)))
        rows.append(("synthetic, all footprints", n,
                     Scene(poses=poses, footsteps=steps, walkable_area=area)))
    if 1000 in args.agents:  # a long run: every footprint of 30 s stays on the ground
        poses, steps = synthetic_crowd(1000, duration=30.0, fps=2.0, area=(63.0, 63.0), seed=0)
        area = shapely.box(-3, -3, 66, 66)
        rows.append((f"synthetic, 30 s: all {len(steps) // 1000}k footprints", 1000,
                     Scene(poses=poses, footsteps=steps, walkable_area=area)))
    if args.run:
        scene = Scene.from_run(args.run)
        n = max(len(scene.poses.at(i)[0]) for i in range(len(scene.poses.times)))
        rows.append((f"run {args.run}", n, scene))
    for name, n, scene in rows:
        r = bench(scene, args.frames)
        table.add_row(name, str(n), f"{r['triangles']:,}", f"{r['footprint_triangles']:,}",
                      f"{r['update']:.1f}", f"{r['render']:.1f}", f"{r['read']:.1f}",
                      f"{r['fps']:.1f}")
    console = Console(width=130)
    console.print(table)
    load = os.getloadavg()
    console.print(f"load average during the run: {load[0]:.2f} (1 min), {load[1]:.2f} (5 min) "
                  f"on {os.cpu_count()} cores — other processes slow software rendering.")


if __name__ == "__main__":
    main()
