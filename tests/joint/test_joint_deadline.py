"""An LP of the one-record search stopped by a deadline keeps a certified bound, never a
wrong one (hammerbound.joint.tighten._tighten_one with a deadline)."""

from __future__ import annotations

import time

import numpy as np
from oracles import one_record

from hammerbound.joint import RecordProblem, default_gamma_box, record_box
from hammerbound.joint.relaxation import LP_TIME_LIMIT, build_relaxation
from hammerbound.joint.tighten import _tighten_one


def _problem(N=400, deta=0.05, seed=0):
    u, y, _ = one_record(N, deta, "bound", seed)
    return RecordProblem(u, y, deta, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, deta)))


def test_every_relaxation_lp_carries_the_cap_and_the_deadline():
    pr = _problem(N=60)
    stop = time.time() + 100.0
    lp = build_relaxation(pr, pr.box, deadline=stop).lp
    assert lp.run_limit == LP_TIME_LIMIT and lp.deadline == stop
    assert build_relaxation(pr, pr.box).lp.deadline is None


def test_an_lp_stopped_by_the_deadline_keeps_an_outer_bound():
    pr = _problem()
    box = pr.box.copy()
    stopped = 0
    for k in (0, 1, pr.p + 1, pr.p + 3):
        full, _ = _tighten_one(pr, box, k)
        cut, _ = _tighten_one(pr, box, k, deadline=time.time() + 1e-4)
        assert cut is not None and full is not None
        # stopped early: never tighter than the LP solved to the end (rounding aside)
        tol = 1e-9 * max(1.0, float(np.max(np.abs(full))))
        assert cut[0] <= full[0] + tol and cut[1] >= full[1] - tol
        assert box[k, 0] <= cut[0] and cut[1] <= box[k, 1]
        stopped += bool(cut[1] - cut[0] > full[1] - full[0] + tol)
    assert stopped  # the deadline did stop LPs
