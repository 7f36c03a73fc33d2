"""ElevInterp and dataset sampling throughput and accuracy; prints a table.

    python benchmarks/bench_elevinterp.py [--n 1000] [--batches 6]

Requests come from bodies 1.50–1.95 m tall: random points of the servable region, and
level-walking steps (SH = 0) with step length from the WBDS fit at 0.9–1.7 m/s scaled by
leg length. Timings are wall-clock best of 3 for the sampler; ElevInterp batches are timed
in sequence on one interpolator, so later batches show the effect of inserted datasets.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from crowdwalk.gait.datasets import load_datasets, normative, sample
from crowdwalk.gait.elevinterp import ElevInterp, SagittalLeg, dataset_step


def region_requests(interp, heights, rng):
    poly = interp.legal_region(SagittalLeg.from_body_height(1.0))  # per metre of height
    w = rng.dirichlet(np.ones(len(poly)), size=len(heights))
    centre = poly.mean(axis=0)
    return (centre + 0.95 * (w @ poly - centre)) * heights[:, None]


def level_requests(heights, rng):
    fit = normative()["step_length_vs_speed"]
    speed = rng.uniform(0.9, 1.7, len(heights))
    sl = (fit["intercept_m"] + fit["slope_s"] * speed) * heights / 1.75
    return np.stack([sl, np.zeros_like(sl)], axis=1)


def run(label, interp, heights, req):
    body = SagittalLeg.from_body_height(heights)
    t0 = time.perf_counter()
    out = interp.request(body, req[:, 0], req[:, 1])
    dt = time.perf_counter() - t0
    got = np.stack([out.step_length, out.step_height], axis=1)
    served = ~out.clamped
    err = np.linalg.norm(got - out.target, axis=1)
    recheck = np.abs(dataset_step(out.angles, body) - got).max()
    print(f"{label:28s} {len(req):6d} {dt * 1e3:9.1f} {len(req) / dt:10.0f} "
          f"{out.refined.mean():8.1%} {out.clamped.mean():8.1%} {out.converged.mean():9.1%} "
          f"{1e3 * err[served].max():9.3f} {1e3 * recheck:8.1e}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--batches", type=int, default=6)
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    interp = ElevInterp()
    print(f"{'ElevInterp.request':28s} {'n':>6s} {'ms':>9s} {'req/s':>10s} {'refined':>8s} "
          f"{'clamped':>8s} {'converged':>9s} {'max err mm':>9s} {'FK diff':>8s}")
    for b in range(args.batches):
        heights = rng.uniform(1.5, 1.95, args.n)
        run(f"region, batch {b + 1}", interp, heights, region_requests(interp, heights, rng))
    for b in range(3):
        heights = rng.uniform(1.5, 1.95, args.n)
        run(f"level SH=0, batch {b + 1}", interp, heights, level_requests(heights, rng))
    print(f"inserted datasets: {interp.stats['inserted']}; "
          f"per-shape spaces: {len(interp._spaces)}")

    print(f"\n{'sample()':28s} {'n':>6s} {'us/call':>9s} {'samples/s':>10s}")
    curves = np.stack([d.angles for d in load_datasets()])
    batch = curves[rng.integers(0, len(curves), args.n)]
    t = rng.uniform(0, 1, args.n)
    for label, fn in [
        ("one dataset, n times", lambda: sample(curves[2], t)),
        ("n datasets, one t each", lambda: sample(batch, t)),
    ]:
        best = min(_timed(fn) for _ in range(3))
        print(f"{label:28s} {args.n:6d} {best * 1e6:9.1f} {args.n / best:10.0f}")


def _timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
