"""The one-record branch-and-bound's certified bound after reduced-cost tightening."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

import hammerbound.joint.search as search


def test_a_box_cut_by_reduced_costs_keeps_its_certified_bound(monkeypatch):
    """Reduced-cost tightening cuts the part of a node whose LP bound reaches the incumbent
    minus the gap tolerance, not the incumbent itself: the minimum may lie in that part,
    below the incumbent, so the end's certified bound must not exceed that target (it
    reported the incumbent, review of the one-record search)."""
    box = np.array([[0.0, 1.0], [0.0, 1.0], [-1.0, 1.0]])
    rel = SimpleNamespace(box_cols=np.arange(3), structure=None)
    lps = [SimpleNamespace(status="optimal", bound=0.5, reduced=np.array([0.0, 2.0, 0.0])),
           SimpleNamespace(status="optimal", bound=0.95, reduced=None)]
    monkeypatch.setattr(search, "_solve", lambda *a, **k: (lps.pop(0), None, None, rel))
    srch = search._EndSearch(None, [box], 0, 1.0, None, 0.1, 100, np.inf)
    srch.inc.value = 1.0  # a verified point's value; gap tolerance 0.1 -> target 0.9
    srch.heap.clear()
    target = srch.inc.value - srch.gap_tol()
    out = srch.solve(box, 0.0, None, {})
    kept = out[3]
    # v_1's reduced cost 2 proves bound >= 0.5 + 2 v_1 >= 0.9 for v_1 >= 0.2: cut there
    assert 0.2 <= kept[1, 1] < 0.21
    # the part kept closes at 0.95 (>= target: dropped); the part cut was only >= 0.9
    assert srch.solve(kept, out[0], None, {}) is None
    assert not srch.heap
    assert srch.outer() <= target


def test_work_near_the_deadline_starts_no_worker_processes():
    """With less time left than starting workers takes, the items run in this process
    (each stops at the deadline): a fit with total_time_limit=0.5 and n_jobs=2 took 5 s
    while loky started its workers (review)."""
    import os
    import time

    from hammerbound.joint.tighten import POOL_MIN_SECONDS, map_jobs

    soon = time.time() + 0.5 * POOL_MIN_SECONDS
    assert map_jobs(os.getpid, [(), ()], 2, deadline=soon) == [os.getpid()] * 2
    assert map_jobs(os.getpid, [(), ()], 2, deadline=time.time() - 1.0) == [os.getpid()] * 2


def test_the_gain_equality_bounds_a_b_left_at_its_default_box():
    """A stopped search left b_j at the default box |b_j| <= 1e4 beside bounded a_i (new-
    user trial 14: b1 infinite, a1 bounded, na = nb = 1). The gain equality
    sum b = g (1 + sum a) bounds it; every point that satisfies the equality with the
    other parameters in their intervals lies inside (sampled here)."""
    from hammerbound.hammerstein.one_record import gain_tightened

    rng = np.random.default_rng(0)
    for g in (1.0, 2.5):
        box = np.array([[-2.0, 2.0], [-1.0, 1.0], [-1e4, 1e4], [-1e4, 1e4]])
        pr = SimpleNamespace(na=2, p=4, gain=g, box=box)
        tb = np.array([[-1.3, -1.2], [0.4, 0.5], [0.1, 0.3], [-1e4, 1e4]])
        out = gain_tightened(pr, tb)
        np.testing.assert_array_equal(out[:3], tb[:3])
        assert out[3, 1] - out[3, 0] < 1.0
        a = rng.uniform(tb[:2, 0], tb[:2, 1], (2000, 2))
        b1 = rng.uniform(tb[2, 0], tb[2, 1], 2000)
        b2 = g * (1.0 + a.sum(axis=1)) - b1
        assert np.all((out[3, 0] <= b2) & (b2 <= out[3, 1]))
        # and at the vertices, where the interval's ends are
        for s in (0, 1):
            b2v = g * (1.0 + tb[:2, s].sum()) - tb[2, 1 - s]
            assert out[3, 0] <= b2v <= out[3, 1]
            assert abs(b2v - out[3, s]) < 1e-4
    # the other b at its box too: each stays at its box (and so is not identified)
    tb = np.array([[-1.3, -1.2], [0.4, 0.5], [-1e4, 1e4], [-1e4, 1e4]])
    np.testing.assert_allclose(gain_tightened(pr, tb), tb, atol=1.0)
