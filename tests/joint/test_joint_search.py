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
