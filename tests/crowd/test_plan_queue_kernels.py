"""stepping._take_queued / _queue_plans (plan_or_reuse's copies as kernels) against the
numpy assignments they replaced, on random queues."""

import numpy as np

from crowdwalk.crowd.stepping import PlanQueue, StepPlan, _queue_plans, _take_queued


def _queue(rng, n, h):
    q = PlanQueue(n, h)
    q.length[:], q.rise[:], q.energy[:] = (rng.normal(size=(n, h)) for _ in range(3))
    q.swing[:] = rng.normal(size=(n, h, 4, 2))
    q.swing[::5] = np.nan
    q.size[:], q.next[:] = rng.integers(0, h + 1, n), rng.integers(0, h, n)
    q.direction[:] = rng.normal(size=(n, 2))
    return q


def _same(x, y):
    for name in vars(x):
        assert getattr(x, name).tobytes() == getattr(y, name).tobytes(), name


def test_queue_kernels_are_the_numpy_assignments():
    rng = np.random.default_rng(11)
    n, h, k = 300, 3, 120
    ref, got = _queue(np.random.default_rng(1), n, h), _queue(np.random.default_rng(1), n, h)
    a = rng.choice(n, k, replace=False).astype(np.int64)
    reuse = rng.random(k) < 0.6
    q = ref.next[a]
    want, plan = StepPlan.standing(k), StepPlan.standing(k)
    r = np.flatnonzero(reuse)
    ar, qr = a[r], q[r]
    want.length[r], want.rise[r] = ref.length[ar, qr], ref.rise[ar, qr]
    want.energy[r], want.swing[r] = ref.energy[ar, qr], ref.swing[ar, qr]
    ref.next[ar] += 1
    _take_queued(a, q, reuse, got.length, got.rise, got.energy, got.swing, got.next,
                 plan.length, plan.rise, plan.energy, plan.swing)
    _same(ref, got)
    _same(want, plan)
    # the re-planning rows: their first steps into the plan, the plans into the queues
    p = np.flatnonzero(~reuse)
    ap, m = a[p], p.size
    ok = rng.random(m) < 0.8
    sl, sh, en = (rng.normal(size=(m, h)) for _ in range(3))
    sw = rng.normal(size=(m, h, 4, 2))
    d = rng.normal(size=(m, 2))
    want.move[p] = ok
    want.length[p], want.rise[p] = sl[:, 0], sh[:, 0]
    want.energy[p], want.swing[p] = en[:, 0], sw[:, 0]
    ref.length[ap], ref.rise[ap], ref.energy[ap], ref.swing[ap] = sl, sh, en, sw
    ref.size[ap] = np.where(ok, h, 0)
    ref.next[ap] = 1
    ref.direction[ap] = d
    _queue_plans(p, ap, ok, sl, sh, en, sw, d, plan.move, plan.length, plan.rise,
                 plan.energy, plan.swing, got.length, got.rise, got.energy, got.swing,
                 got.size, got.next, got.direction)
    _same(ref, got)
    _same(want, plan)
