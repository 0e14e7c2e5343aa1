"""Exact intervals (22.36)-(22.37) by McCormick branch-and-bound (bnb.py)."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from oracles import A_TRUE, B_TRUE, chapter_eiv_data
from scipy.signal import lfilter

from hammerbound.exceptions import EmptyFeasibleSetError, UnboundedSetError
from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.lp import lp_bounds, touches_box
from hammerbound.relaxations.moment.relaxation import moment_bounds
from hammerbound.relaxations.problem import EIVProblem, check_theta

ATOL = 1e-7  # slack of check_theta's acceptance, see tests/test_lp.py
TOL = 1e-3


@functools.cache
def _case(seed, deta, two_level, N=30):
    data, theta = chapter_eiv_data(N=N, deta=deta, two_level=two_level, seed=seed)
    pr = EIVProblem(**data)
    return pr, theta, exact_bounds(pr, tol=TOL)


def witnesses(res):
    return np.array([i.witness for i in res.infos if i.witness is not None])


def sampled_feasible(problem, res, rng, n=100):
    """Convex combinations of witnesses and random gain-plane points, verified."""
    W = witnesses(res)
    g = problem.gain_row()
    cands = [rng.dirichlet(np.ones(len(W))) @ W for _ in range(n // 2)]
    for _ in range(n // 2):
        th = rng.uniform(res.bounds[:, 0], res.bounds[:, 1])
        th[-1] = (g[1] - g[0][:-1] @ th[:-1]) / g[0][-1]
        cands.append(th)
    return np.array([th for th in cands if check_theta(problem, th).feasible])


def assert_contains(bounds, pts, atol=ATOL, what="bounds"):
    for th in np.atleast_2d(pts):
        ok = np.all(th >= bounds[:, 0] - atol) and np.all(th <= bounds[:, 1] + atol)
        assert ok, f"{what} exclude the verified-feasible point {th!r}: {bounds!r}"


def direct_residuals(pr, theta, eta, dxv):
    """Residuals of (22.34) written out sample by sample from the raw data."""
    a, b = theta[: pr.na], theta[pr.na :]
    lags = range(0 if pr.b0 else 1, pr.nb + 1)
    out = []
    for t in range(max(pr.na, pr.nb), pr.N):
        lhs = (pr.y[t] - eta[t]) + sum(a[i - 1] * (pr.y[t - i] - eta[t - i])
                                       for i in range(1, pr.na + 1))
        rhs = sum(bj * (pr.x[t - j] - dxv[pr.groups[t - j]]) for bj, j in zip(b, lags, strict=True))
        out.append(lhs - rhs)
    return np.array(out)


CASES = [(0, 0.005, False), (1, 0.05, False), (2, 0.2, False), (3, 0.05, True),
         (4, 0.2, True)]


@pytest.mark.parametrize("seed,deta,two_level", CASES)
def test_true_theta_inside_exact_intervals(seed, deta, two_level):
    pr, theta, res = _case(seed, deta, two_level)
    assert res.method == "exact" and res.bounds.shape == (4, 2)
    assert res.contains(theta), (res.bounds, theta)
    assert_contains(res.bounds, witnesses(res), what="exact bounds")
    # the exact intervals lie in the OBBT root box, itself inside the LP intervals
    lp = res.lp.bounds
    assert np.all(res.bounds[:, 0] >= lp[:, 0] - 1e-12)
    assert np.all(res.bounds[:, 1] <= lp[:, 1] + 1e-12)
    assert np.sum(res.width) < np.sum(lp[:, 1] - lp[:, 0])  # tighter than the LP


@pytest.mark.parametrize("seed,deta,two_level", CASES)
def test_witnesses_satisfy_every_constraint(seed, deta, two_level):
    pr, theta, res = _case(seed, deta, two_level)
    assert len(res.infos) == 2 * pr.p
    scale = 1.0 + np.max(np.abs(pr.y))
    for j, info in enumerate(res.infos):
        k, e = divmod(j, 2)
        assert info.status == "optimal", info.message
        w = info.witness
        assert w is not None and w.shape == (pr.p,)
        assert check_theta(pr, w).feasible
        # recompute (22.34) directly with the witness noise
        eta, dxv = info.point.eta, info.point.dx
        assert eta.shape == (pr.N,) and dxv.shape == (pr.n_groups,)
        assert np.all(np.abs(eta) <= pr.deta)
        assert np.all(np.abs(dxv) <= pr.dx_group)
        assert np.max(np.abs(direct_residuals(pr, w, eta, dxv))) <= 1e-8 * scale
        g_row, g_rhs = pr.gain_row()
        assert abs(g_row @ w - g_rhs) <= 1e-9
        b = w[pr.na:]
        assert abs(b.sum() - pr.gain * (1 + w[: pr.na].sum())) <= 1e-9
        assert np.all(w >= pr.theta_box[:, 0]) and np.all(w <= pr.theta_box[:, 1])
        # the value, the bound and the certified gap are consistent
        v = info.inner
        assert v == w[k] == res.inner[k, e]
        assert info.gap is not None and 0.0 <= info.gap <= TOL * max(1.0, abs(v)) + 1e-12
        if info.sense == "min":
            assert info.bound <= v <= info.bound + info.gap + 1e-12
        else:
            assert info.bound - info.gap - 1e-12 <= v <= info.bound
        assert info.bound == res.bounds[k, e] and info.certified and info.nodes >= 1


@pytest.mark.parametrize("seed,deta,two_level", [(1, 0.05, False), (4, 0.2, True)])
def test_exact_contains_sampled_feasible_points(seed, deta, two_level):
    pr, theta, res = _case(seed, deta, two_level)
    pts = sampled_feasible(pr, res, np.random.default_rng(seed))
    assert len(pts) >= 10
    assert_contains(res.bounds, np.vstack([pts, theta]), what="exact bounds")
    assert_contains(res.lp.bounds, pts, what="LP bounds")


def test_two_level_exact_intervals_inside_independent_ones():
    pr_i, theta, r_i = _case(1, 0.05, False)
    pr_t, _, r_t = _case(1, 0.05, True)
    np.testing.assert_array_equal(pr_i.y, pr_t.y)
    # two-level set is a subset: its verified points belong to the independent set ...
    for w in witnesses(r_t):
        assert check_theta(pr_i, w).feasible
    assert_contains(r_i.bounds, witnesses(r_t), what="independent exact bounds")
    # ... and its outer bounds cannot be looser by more than its own certified gap
    for j, info in enumerate(r_t.infos):
        k, e = divmod(j, 2)
        if e == 0:
            assert r_t.bounds[k, 0] >= r_i.bounds[k, 0] - info.gap - 1e-12
        else:
            assert r_t.bounds[k, 1] <= r_i.bounds[k, 1] + info.gap + 1e-12
    assert np.sum(r_t.width) < np.sum(r_i.width)


@pytest.mark.parametrize("limit", [dict(max_nodes=1), dict(time_limit=0.0)])
def test_node_and_time_limits_return_valid_outer_bounds(limit):
    pr, theta, full = _case(2, 0.2, False)
    res = exact_bounds(pr, tol=1e-7, **limit)
    statuses = [i.status for i in res.infos]
    assert "limit" in statuses and set(statuses) <= {"limit", "optimal"}
    for info in res.infos:
        assert info.certified and info.gap is not None and info.gap >= 0
        if info.status == "limit":
            assert "limit" in info.message or "no verified" in info.message
        if info.witness is not None:
            assert check_theta(pr, info.witness).feasible
    pts = np.vstack([witnesses(full), witnesses(res), theta])
    assert_contains(res.bounds, pts, what="node/time-limited exact bounds")


def test_theta_box_argument():
    pr, theta, full = _case(1, 0.05, False)
    lp = full.lp.bounds
    loose = lp + np.array([-0.5, 0.5])
    res = exact_bounds(pr, tol=TOL, theta_box=loose)
    assert res.contains(theta)
    assert_contains(res.bounds, witnesses(full), what="exact bounds (loose box)")
    # a box cutting the set: the bound sits on the box, which is reported
    cut = lp.copy()
    cut[0, 1] = theta[0]
    with pytest.raises(UnboundedSetError, match="a1 upper"):
        exact_bounds(pr, tol=TOL, theta_box=cut)


# ---------------------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------------------


def test_inconsistent_data_raise_empty_set_with_the_equation():
    data, _ = chapter_eiv_data(N=30, deta=0.05, seed=3)
    pr = EIVProblem(**data)
    y = pr.y.copy()
    y[12:] -= 2.0
    bad = EIVProblem(y, pr.x, pr.dx, pr.deta, 2, 2, steady_state_gain=1.0)
    with pytest.raises(EmptyFeasibleSetError, match="equation t = ") as ei:
        exact_bounds(bad, tol=TOL)
    assert 12 <= ei.value.first_index <= 14


def _varying_inner_signal(seed, deta_scale, N=30, deta=0.01, dxv=0.05):
    """Two-level model on data whose inner signal varies from sample to sample.

    The LP (which cannot exploit the shared input error) stays feasible while the exact
    two-level set may be empty.
    """
    rng = np.random.default_rng(seed)
    lev = np.where(rng.random(N) < 0.5, 1.0, -1.0)
    y = lfilter(B_TRUE, A_TRUE, lev + rng.uniform(-dxv, dxv, N)) + rng.uniform(-deta, deta, N)
    return EIVProblem(y, lev, dxv, deta * deta_scale, 2, 2, steady_state_gain=1.0,
                      groups=(lev < 0).astype(int))


@pytest.mark.parametrize("seed,deta_scale", [
    (0, 1.0),  # the McCormick relaxation is infeasible at the root (OBBT)
    # borderline: the root relaxation is feasible and every branch-and-bound leaf is
    # certified infeasible (used to return bounds [+inf, -inf] with status "limit")
    (0, 7.64080810546875),
])
def test_empty_two_level_set_raises(seed, deta_scale):
    pr = _varying_inner_signal(seed, deta_scale)
    lp_bounds(pr)  # the LP outer set is not empty
    with pytest.raises(EmptyFeasibleSetError):
        exact_bounds(pr, tol=TOL, max_nodes=300, time_limit=20)


def test_constant_input_is_unbounded():
    data, _ = chapter_eiv_data(N=30, deta=0.05, seed=6)
    pr = EIVProblem(**data)
    bad = EIVProblem(pr.y, np.full(pr.N, 0.5), pr.dx, pr.deta, 2, 2, steady_state_gain=1.0)
    with pytest.raises(UnboundedSetError, match="b1"):
        exact_bounds(bad, tol=TOL)


# ---------------------------------------------------------------------------------------
# parallel execution
# ---------------------------------------------------------------------------------------


def test_n_jobs_two_matches_serial():
    data, theta = chapter_eiv_data(N=15, deta=0.05, seed=8)
    pr = EIVProblem(**data)
    lp1, lp2 = lp_bounds(pr, n_jobs=1), lp_bounds(pr, n_jobs=2)
    np.testing.assert_array_equal(lp1.bounds, lp2.bounds)
    box = lp1.bounds
    m1 = moment_bounds(pr, order=1, theta_box=box, n_jobs=1)
    m2 = moment_bounds(pr, order=1, theta_box=box, n_jobs=2)
    np.testing.assert_allclose(m1.bounds, m2.bounds, rtol=0, atol=1e-12)
    assert [i.certified for i in m1.infos] == [i.certified for i in m2.infos]
    e1 = exact_bounds(pr, tol=TOL, n_jobs=1)
    e2 = exact_bounds(pr, tol=TOL, n_jobs=2)
    assert e2.contains(theta)
    # both are certified brackets of the same numbers: they agree up to their gaps
    for j, (i1, i2) in enumerate(zip(e1.infos, e2.infos, strict=True)):
        assert i1.status == i2.status == "optimal"
        assert check_theta(pr, i2.witness).feasible
        k, e = divmod(j, 2)
        assert abs(e1.bounds[k, e] - e2.bounds[k, e]) <= max(i1.gap, i2.gap) + 1e-12
    assert_contains(e2.bounds, witnesses(e1), what="n_jobs=2 exact bounds")
    assert_contains(e1.bounds, witnesses(e2), what="n_jobs=1 exact bounds")


# ---------------------------------------------------------------------------------------
# property-based coverage
# ---------------------------------------------------------------------------------------


@st.composite
def stable_systems(draw):
    """Random stable 1st/2nd-order systems with unit gain, data and noise bounds."""
    na = draw(st.sampled_from([1, 2]))
    if na == 1:
        pole = draw(st.floats(-0.85, 0.85))
        A = np.array([1.0, -pole])
    else:
        r = draw(st.floats(0.1, 0.85))
        ang = draw(st.floats(0.0, np.pi))
        A = np.array([1.0, -2 * r * np.cos(ang), r * r])
    B = np.array([0.0] + draw(st.lists(st.floats(-2.0, 2.0), min_size=na, max_size=na)))
    # keep the gain away from zero so that normalising it does not blow B up
    s = B.sum()
    if abs(s) < 0.3 * np.abs(B).sum() or np.abs(B).sum() < 0.2:
        B[1] += np.sign(s or 1.0) * (0.3 * np.abs(B).sum() + 0.5)
    B = B * A.sum() / B.sum()  # unit steady-state gain (22.8)
    rel_noise = draw(st.floats(0.005, 0.2))
    dx = draw(st.sampled_from([0.0, 0.002, 0.01]))
    seed = draw(st.integers(0, 2**31 - 1))
    return A, B, rel_noise, dx, seed


@settings(max_examples=6, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(stable_systems())
def test_property_true_theta_inside_lp_and_exact(system):
    A, B, rel_noise, dx, seed = system
    na = A.size - 1
    rng = np.random.default_rng(seed)
    N = 40
    x = rng.uniform(-1.0, 1.0, N)
    w = lfilter(B, A, x)
    deta = rel_noise * np.sqrt(np.mean(w**2))  # noise level relative to the output
    y = w + rng.uniform(-deta, deta, N)
    xc = x + rng.uniform(-dx, dx, N)
    pr = EIVProblem(y, xc, dx, deta, na=na, nb=na, steady_state_gain=1.0)
    theta = np.concatenate([A[1:], B[1:]])
    assert check_theta(pr, theta).feasible
    lp = lp_bounds(pr, check_box=False)
    assert lp.contains(theta), (lp.bounds, theta)
    # data that do not bound theta inside the a priori box are not an exact-method case
    assume(not np.any(touches_box(lp.bounds, pr.theta_box)))
    ex = exact_bounds(pr, tol=TOL, max_nodes=60, time_limit=2.0)
    assert ex.contains(theta), (ex.bounds, theta)
    assert_contains(lp.bounds, witnesses(ex), what="LP bounds")
    for info in ex.infos:
        if info.witness is not None:
            assert check_theta(pr, info.witness).feasible


# ---- the pieces that keep the search small (cap, reduced costs, seek, node options) -----

@pytest.mark.parametrize("k,sense", [(0, 1.0), (2, -1.0), (3, 1.0)])
def test_reduced_cost_tightening_cuts_only_parts_above_the_target(k, sense):
    from hammerbound.relaxations.exact.mccormick import McCormickRelaxation
    from hammerbound.relaxations.exact.node_box import _reduced_cost_tightening

    data, _ = chapter_eiv_data(N=30, deta=0.1, seed=4)

    pr = EIVProblem(**data)
    box = lp_bounds(pr).bounds.copy()  # results are read-only
    relax = McCormickRelaxation(pr, box)
    c = np.zeros(relax.ncol)
    c[k] = sense
    relax.lp.set_cost(c)
    lo = relax.lp.solve().x[k]
    relax.lp.set_cost(-c)
    hi = relax.lp.solve().x[k]
    relax.lp.set_cost(c)
    # a node box that excludes the relaxation's optimum in theta_k: theta_k sits at the
    # box edge with a nonzero reduced cost (inside the box every reduced cost is zero)
    box[k, 0 if sense > 0 else 1] = lo + 0.2 * (hi - lo)
    relax.set_box(box)
    res = relax.lp.solve()
    assert res.status == "optimal"
    target = res.bound + 0.05 * (box[k, 1] - box[k, 0])
    new, cut = _reduced_cost_tightening(box, res.reduced[: pr.p], res.bound, target)
    assert cut, "the test needs a case where something is cut"
    assert np.all(new[:, 0] >= box[:, 0]) and np.all(new[:, 1] <= box[:, 1])
    for j in range(pr.p):
        for side, removed in ((1, (new[j, 1], box[j, 1])), (0, (box[j, 0], new[j, 0]))):
            if removed[1] - removed[0] <= 1e-12:
                continue
            part = box.copy()
            part[j] = removed
            relax.set_box(part)
            r = relax.lp.solve()
            # the removed part cannot hold anything below the target
            assert r.status in ("infeasible", "cutoff") or r.value >= target - 1e-9, (j, side)
    relax.set_box(box)


def test_cap_keeps_only_the_part_below_the_incumbent():
    from hammerbound.relaxations.exact.node_box import _cap

    box = np.array([[0.0, 1.0], [-2.0, 2.0]])
    np.testing.assert_array_equal(_cap(box, 1, 1.0, 0.5), [[0.0, 1.0], [-2.0, 0.5]])
    np.testing.assert_array_equal(_cap(box, 1, -1.0, 0.5), [[0.0, 1.0], [-0.5, 2.0]])
    assert _cap(box, 0, 1.0, -0.1) is None
    assert _cap(box, 0, -1.0, -1.5) is None
    assert _cap(box, 0, 1.0, 3.0) is box  # nothing to cap: no copy


def test_seek_finds_a_verified_point_from_an_infeasible_start():
    from hammerbound.relaxations.exact.points import _Pool

    data, theta = chapter_eiv_data(N=60, deta=0.1, two_level=True, seed=2)

    pr = EIVProblem(**data)
    box = lp_bounds(pr).bounds
    start = box[:, 0] + 0.8 * (box[:, 1] - box[:, 0])
    pool = _Pool(pr)
    assert pool.add(start) is None  # neither feasible nor on the gain plane
    pt = pool.seek([start], box)
    assert pt is not None
    chk = check_theta(pr, pt.theta)
    assert chk.feasible and chk.gain_residual <= 1e-9
    assert np.all(pt.theta >= box[:, 0]) and np.all(pt.theta <= box[:, 1])


def test_node_lp_options_keep_scaling_for_badly_scaled_data():
    from hammerbound.relaxations.exact.mccormick import McCormickRelaxation
    from hammerbound.solvers.highs import HighsLP

    data, _ = chapter_eiv_data(N=20, deta=0.05, seed=1)

    pr = EIVProblem(**data)
    box = lp_bounds(pr).bounds
    def opts(problem, name):
        return McCormickRelaxation(problem, box).lp.h.getOptionValue(name)[1]

    assert opts(pr, "simplex_scale_strategy") == 0
    assert opts(pr, "simplex_dual_edge_weight_strategy") == 1
    for f in (1e5, 1e-4):  # the gain row's unit coefficients must not hide the data scale
        other = EIVProblem(pr.y * f, pr.x * f, pr.dx * f, pr.deta * f, na=2, nb=2,
                           steady_state_gain=1.0)
        assert opts(other, "simplex_scale_strategy") != 0
    with pytest.raises(ValueError, match="no_such_option"):
        HighsLP(np.eye(1), [0.0], [1.0], [0.0], [1.0], options={"no_such_option": 1})


def test_unscaled_node_lp_turns_scaling_on_when_its_bound_trails(monkeypatch):
    from hammerbound.relaxations.exact.mccormick import McCormickRelaxation
    from hammerbound.solvers import highs as _highs

    data, _ = chapter_eiv_data(N=20, deta=0.05, seed=1)

    pr = EIVProblem(**data)
    relax = McCormickRelaxation(pr, lp_bounds(pr).bounds)
    assert relax.lp.h.getOptionValue("simplex_scale_strategy")[1] == 0
    c = np.zeros(relax.ncol)
    c[0] = 1.0
    relax.lp.set_cost(c)
    real = _highs.row_dual_bound
    calls = []

    def trailing(*args, **kw):  # first certificate 0.01 weaker than it should be
        b, r = real(*args, **kw)
        calls.append(b)
        return (b - 0.01 if len(calls) == 1 else b), r

    monkeypatch.setattr(_highs, "row_dual_bound", trailing)
    res = relax.lp.solve()
    assert relax.lp.rescaled and len(calls) == 2
    assert relax.lp.h.getOptionValue("simplex_scale_strategy")[1] != 0
    assert res.bound == calls[1] and res.value - res.bound <= 1e-9
