"""The local steps of the one-record search (``hammerbound.joint.local``) stay well scaled
at points that already explain the record (residuals near rounding)."""

from __future__ import annotations

import numpy as np
from oracles import A_TRUE, B_TRUE, GAMMA_TRUE, THETA_TRUE, one_record
from scipy.signal import lfilter

from hammerbound.joint import RecordProblem, default_gamma_box, local, record_box
from hammerbound.tolerances import FEASIBILITY_RTOL


def test_a_step_at_an_exact_point_keeps_its_lp_well_scaled(monkeypatch):
    """At the truth with its own noise every residual is rounding (~1e-16). The step's
    rows are scaled by 1 / (current violation); without a floor their coefficients
    reached 1e13 and HiGHS ran such LPs into their time limit (11 LPs of 5 s in one
    starting pool at N = 300)."""
    u, y, x = one_record(120, 0.05, "uniform", 3)
    eta = y - lfilter(B_TRUE, A_TRUE, x)  # the record's own noise
    pr = RecordProblem(u, y, 0.05, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, 0.05)))
    v = np.concatenate([THETA_TRUE, GAMMA_TRUE, [x[0]]])
    lin = local._Linearised(pr, v, eta)
    F, _, _, scale = lin.equations()
    assert np.max(np.abs(F) / scale) < 1e-12  # the truth explains its record
    seen = []
    real = local.linprog

    def recording(c, A_ub=None, **kw):
        seen.append(float(abs(A_ub).max()))
        return real(c, A_ub=A_ub, **kw)

    monkeypatch.setattr(local, "linprog", recording)
    rho = 1e-2 * np.maximum(np.abs(v), 1e-3)
    step = local._step(lin, pr.box, rho, rho_eta=1e-2 * pr.deta)
    assert step is not None
    assert seen and max(seen) <= 1e3 / FEASIBILITY_RTOL, seen  # J entries are O(1-100)
    walk_step = local._step(lin, pr.box, rho, objective=(pr.p + 3, 1.0))
    assert walk_step is not None and max(seen) <= 1e3 / FEASIBILITY_RTOL


def test_node_searches_take_at_most_their_share_of_an_end(monkeypatch):
    """The local searches at the nodes of an end stop while they have taken more than
    MAX_SEARCH_SHARE of its time (under a time limit the nodes tighten the certified
    bound, the searches do not): with searches made slow, their time stays near the share
    and the nodes go on."""
    import time

    from hammerbound.joint import search

    u, y, x = one_record(60, 0.05, "uniform", 1)
    pr = RecordProblem(u, y, 0.05, 2, 2, 1, record_box(2, 2, u, default_gamma_box(u, y, 0.05)))
    spent = []

    def slow_restore(*a, **kw):
        t = time.perf_counter()
        time.sleep(0.05)
        spent.append(time.perf_counter() - t)
        return None  # finds nothing: the spacing rule alone would search again soon

    monkeypatch.setattr(search, "restore", slow_restore)
    monkeypatch.setattr(search, "MAX_SEARCH_SPACING", 1)  # only the share can hold them
    t0 = time.perf_counter()
    res = search.search_end(pr, pr.box, 0, 1.0, None, tol=1e-12, max_nodes=60)
    total = time.perf_counter() - t0
    assert res.nodes == 60 and len(spent) >= 1
    # at most one search past the share (the one that crossed it)
    assert sum(spent) <= search.MAX_SEARCH_SHARE * total + 0.06, (sum(spent), total)
