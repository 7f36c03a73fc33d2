"""Speed of terrain queries, profiles, meshing and routing. Prints a table.

    python benchmarks/bench_terrain.py

Target (issue 2): 100k height queries on flat + stairs + blocks well under 0.1 s.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import trimesh

from crowdwalk.routes import Corridor, Place, RouteGraph
from crowdwalk.scenario import load_scenario
from crowdwalk.terrain import Block, Heightfield, MeshFeature, Slope, StairFlight, Terrain
from crowdwalk.world import build_world

ROOT = Path(__file__).resolve().parents[1]
N = 100_000


def best_of(fn, repeat: int = 5) -> float:
    """Fastest wall time of ``repeat`` calls [s]."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def terrains() -> dict[str, Terrain]:
    ext = (0.0, 0.0, 60.0, 40.0)
    stairs = StairFlight((10, 20), 0.0, 3.0, 0.3, 0.17, 8)
    blocks = tuple(Block.box((20 + 6 * i, 10 + 4 * (i % 3)), (3, 1.5), 0.15 + 0.1 * i, 0.3 * i)
                   for i in range(5))
    curb = Block([(40, 30), (55, 30), (55, 30.3), (40, 30.3)], 0.15)
    rng = np.random.default_rng(1)
    obstacles = tuple(Block.box(rng.uniform((2, 2), (58, 38)), (0.5, 0.5), rng.uniform(0.1, 1))
                      for _ in range(200))
    ramp = Slope.ramp((5, 5), 0.0, 8, 2.5, 0.0, 0.7)
    rough = Heightfield.noise((45, 2), (12, 10), 0.25, 0.04, 1.0, seed=1)
    box = trimesh.creation.box(extents=(4, 4, 1.0))
    box.apply_translation((30, 32, 0.5))
    return {
        "flat": Terrain.flat(ext),
        "flat+stairs+blocks": Terrain(ext, 0.0, (stairs, *blocks, curb)),
        "+ramp+rough": Terrain(ext, 0.0, (ramp, stairs, *blocks, curb, rough)),
        "+mesh (embree rays)": Terrain(ext, 0.0, (ramp, stairs, *blocks, curb, rough,
                                                   MeshFeature(box))),
        "stairs + 200 obstacles": Terrain(ext, 0.0, (stairs, *obstacles)),
    }


def main() -> None:
    rng = np.random.default_rng(0)
    xy = rng.uniform((0, 0), (60, 40), (N, 2))
    rows = []
    for name, ter in terrains().items():
        t_h = best_of(lambda ter=ter: ter.height(xy))
        t_n = best_of(lambda ter=ter: ter.normal(xy), 3)
        t_k = best_of(lambda ter=ter: ter.kind(xy), 3)
        path = np.array([[8.0, 20.3], [13.0, 20.0], [16.0, 21.0]])  # 8 m across the stairs
        t_p = best_of(lambda ter=ter, path=path: ter.profile_arrays(path), 20)
        starts = rng.uniform((5, 15), (20, 25), (200, 2))
        lines = [np.stack([q, q + (3.0, 0.5)]) for q in starts]
        t_b = best_of(lambda ter=ter, lines=lines: ter.profiles(lines), 5) / len(lines)
        t_m = best_of(lambda ter=ter: ter.mesh(), 1)
        rows.append((name, len(ter.features), t_h * 1e3, t_h / N * 1e9, t_n * 1e3, t_k * 1e3,
                     t_p * 1e6, t_b * 1e6, t_m * 1e3))
    print(f"Terrain queries, {N:,} random points (best of several runs)")
    head = ("terrain", "features", "height ms", "ns/pt", "normal ms", "kind ms",
            "profile µs", "batched µs/profile", "mesh() ms")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]:.1f} | {r[3]:.0f} | {r[4]:.1f} | {r[5]:.1f} | "
              f"{r[6]:.0f} | {r[7]:.1f} | {r[8]:.0f} |")

    # routing
    sc = load_scenario(ROOT / "scenarios" / "quickstart.yaml")
    t_build = best_of(lambda: build_world(sc), 3)
    world = build_world(sc)
    r = world.routes
    t_field = best_of(lambda: (r._fields.clear(), r.distances_to("east_exit")), 10)
    t_path = best_of(lambda: (r._paths.clear(), r.path("west_gate", "east_exit")), 10)
    side = 40
    ij = [(i, j) for i in range(side) for j in range(side)]
    places = [Place(f"{i},{j}", 2.0 * i + 1, 2.0 * j + 1) for i, j in ij]
    cors = [Corridor(f"{i},{j}", f"{i + 1},{j}", 1.0) for i, j in ij if i + 1 < side]
    cors += [Corridor(f"{i},{j}", f"{i},{j + 1}", 1.0) for i, j in ij if j + 1 < side]
    ter = Terrain((0, 0, 2.0 * side, 2.0 * side), 0.0,
                  (StairFlight((20.5, 20), 0.0, 30, 0.3, 0.1, 4),))
    t0 = time.perf_counter()
    grid = RouteGraph(places, cors, ter)
    t_grid = time.perf_counter() - t0
    t_gfield = best_of(lambda: (grid._fields.clear(), grid.distances_to("0,0")), 3)
    print()
    print("Routing")
    print("| task | ms |")
    print("|---|---|")
    print(f"| build quickstart world (terrain + 8 corridors costed) | {t_build * 1e3:.1f} |")
    print(f"| quickstart distance field to one destination | {t_field * 1e3:.2f} |")
    print(f"| quickstart smooth path west_gate→east_exit | {t_path * 1e3:.2f} |")
    print(f"| build {side}×{side} grid graph, {len(cors)} corridors costed on terrain | "
          f"{t_grid * 1e3:.0f} |")
    print(f"| grid distance field ({side * side} nodes) | {t_gfield * 1e3:.1f} |")


if __name__ == "__main__":
    main()
