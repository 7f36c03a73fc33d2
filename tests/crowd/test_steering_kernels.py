"""The steering kernels' building blocks give numpy's values bit for bit (the compiled
steering claims the array formulation's results exactly)."""

import numpy as np

from crowdwalk.crowd.steering_kernels import _segments, _sum, _wrap


def test_sum_adds_in_numpys_order():
    # numpy sums a last axis of up to 128 items pairwise (eight partial sums): sequential
    # addition differs from 8 items on; the soft terms sum 10 and 12
    rng = np.random.default_rng(3)
    for n in (0, 1, 2, 5, 7, 8, 9, 10, 12, 16, 17, 33, 128):
        x = np.exp(3.0 * rng.normal(size=(400, max(n, 1))))[:, :n]
        want = np.where(x > 0.5, x, 0.0).sum(axis=-1)
        got = np.array([_sum(np.where(row > 0.5, row, 0.0), n) for row in x])
        np.testing.assert_array_equal(got, want)


def test_wrap_and_segment_distance_give_numpys_values():
    from crowdwalk.crowd.geometry import segment_distance

    rng = np.random.default_rng(4)
    x = 20.0 * rng.normal(size=2000)
    np.testing.assert_array_equal([_wrap(v) for v in x], (x + np.pi) % (2 * np.pi) - np.pi)
    p = rng.normal(size=(2000, 4, 2))
    p[::7, 1] = p[::7, 0]  # points (degenerate segments) too
    want = segment_distance(p[:, 0], p[:, 1], p[:, 2], p[:, 3])
    got = [_segments(*q.ravel()) for q in p]
    np.testing.assert_array_equal(got, want)
    assert (want == 0.0).any() and (want > 0.0).any()  # crossing and apart both occur


def test_the_crowd_kernel_cache_is_stamped_with_the_crowd_sources():
    # the steering kernels call clearance's and shape's: importing crowdwalk.crowd cleared
    # its numba cache unless the stamp (planners.kernel_cache) matched every crowd source
    import os
    from pathlib import Path

    import crowdwalk.crowd
    from planners.kernel_cache import STAMP, cache_dir, sources_digest

    package = Path(crowdwalk.crowd.__file__).resolve().parent
    directory = cache_dir(package)
    if directory is None or not os.access(directory, os.W_OK):
        return  # numba caches nothing here
    assert (directory / STAMP).read_text().strip() == sources_digest(package)
