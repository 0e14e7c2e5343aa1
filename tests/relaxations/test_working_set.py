"""Exact intervals on a working set of equations (relaxations/working_set.py, long records)."""

from __future__ import annotations

import functools

import numpy as np
import pytest
import scipy.sparse as sp
from oracles import chapter_eiv_data, explains, two_level_data
from scipy.optimize import linprog
from scipy.signal import lfilter

from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.exact.mccormick import McCormickRelaxation
from hammerbound.relaxations.exact.obbt import _solve
from hammerbound.relaxations.exact.points import _Screen
from hammerbound.relaxations.exact.working_set import WorkingSetRelaxation, interval_excess
from hammerbound.relaxations.problem import EIVProblem

TOL = 1e-3


def _scipy_lp_min(lp, c):
    """min c'z over the rows/columns of a HighsLP, solved independently by scipy."""
    A = lp.A.tocsr()
    rl, ru = lp.rl, lp.ru
    up, lo = np.isfinite(ru), np.isfinite(rl)
    A_ub = sp.vstack([A[up], -A[lo]])
    b_ub = np.concatenate([ru[up], -rl[lo]])
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, bounds=np.column_stack([lp.lb, lp.ub]),
                  method="highs")
    assert res.status == 0, res.message
    return res.fun


@functools.cache
def _pair(seed=1, deta=0.05, N=50):
    data, theta = chapter_eiv_data(N=N, deta=deta, seed=seed)
    pr = EIVProblem(**data)
    full = exact_bounds(pr, tol=TOL, working_set=False)
    ws = exact_bounds(pr, tol=TOL, working_set=True)
    return pr, theta, full, ws


def test_working_set_equals_full_lp_method_within_tolerance():
    pr, theta, full, ws = _pair()
    assert full.details.working_set is None and 0 < ws.details.working_set <= pr.N
    for f, w in zip(full.infos, ws.infos, strict=True):
        assert f.status == w.status == "optimal"
        v = max(abs(f.inner), abs(w.inner))
        tol = TOL * max(1.0, v)
        # both are certified outer bounds within tol of a verified value: they agree
        assert abs(f.bound - w.bound) <= tol + 1e-12, (f.param, f.sense, f.bound, w.bound)
        assert w.gap <= tol + 1e-12
    assert ws.contains(theta)
    for i in ws.infos:  # witnesses verified by our own LP, on the right side of the bound
        assert explains(pr, i.witness)
        s = 1.0 if i.sense == "min" else -1.0
        k = list(ws.param_names).index(i.param)
        assert s * i.witness[k] >= s * i.bound - 1e-12


def test_working_set_lp_relaxes_the_full_lp_scipy_check():
    """The working-set LP bound is <= the full McCormick LP (solved by scipy), and equal
    to it once every equation is in the set."""
    pr, _, full, _ = _pair()
    box = full.root_box
    fullr = McCormickRelaxation(pr, box)
    m = pr.equation_times.size
    ws = WorkingSetRelaxation(pr, box, np.arange(0, m, 7))
    screen = _Screen(pr, working_set=True)
    for k, s in [(0, 1.0), (2, -1.0), (3, 1.0)]:
        c = np.zeros(fullr.ncol)
        c[k] = s
        ref = _scipy_lp_min(fullr.lp, c)
        cw = np.zeros(ws.ncol)
        cw[k] = s
        ws.lp.set_cost(cw)
        r = _solve(ws, screen)
        assert r.status == "optimal" and r.bound <= ref + 1e-9
        ws.add_equations(np.arange(m))
        cw = np.zeros(ws.ncol)
        cw[k] = s
        ws.lp.set_cost(cw)
        r = ws.lp.solve()
        assert r.bound <= ref + 1e-9 and r.bound >= ref - 1e-6 * (1 + abs(ref))
        ws = WorkingSetRelaxation(pr, box, np.arange(0, m, 7))


def test_interval_excess_flags_only_equations_that_fail():
    data, theta = chapter_eiv_data(N=60, deta=0.05, seed=3)
    pr = EIVProblem(**data)
    # the truth explains every equation: no excess
    assert np.all(interval_excess(pr, theta) <= 0)
    bad = theta.copy()
    bad[0] += 0.5
    exc = interval_excess(pr, bad)
    assert np.any(exc > 0)
    # an equation flagged cannot be satisfied at ``bad`` by any errors: check by brute force
    t = int(np.argmax(exc))
    phi, yt = pr.regressors()
    r = yt[t] + phi[t] @ bad
    e = pr.deta[pr.eta_index()[t]] @ np.concatenate([[1.0], np.abs(bad[:2])]) + \
        pr.dx_group[pr.dx_index()[t]] @ np.abs(bad[2:])
    assert abs(r) > e


def _noise_at_the_bound(seed, N, deta):
    """Own simulation: y = B/A x + eta with |eta_t| = deta exactly (random signs)."""
    rng = np.random.default_rng(seed)
    a = np.array([1.0, -1.5, 0.7])
    b = np.array([0.0, 0.12, 0.08])
    b = b * a.sum() / b.sum()  # unit static gain (22.8)
    x = np.where(rng.random(N) < 0.5, 0.5, -0.5)
    y = lfilter(b, a, x) + deta * rng.choice([-1.0, 1.0], N)
    return EIVProblem(y, x, 0.0, deta, na=2, nb=2, steady_state_gain=1.0), \
        np.concatenate([a[1:], b[1:]])


@pytest.mark.parametrize("seed", [0, 1])
def test_noise_exactly_at_the_bound_truth_inside_working_set(seed):
    pr, theta = _noise_at_the_bound(seed, N=90, deta=0.1)
    res = exact_bounds(pr, tol=TOL, working_set=True)
    assert res.contains(theta), (res.bounds, theta)
    assert explains(pr, theta)
    for i in res.infos:
        assert i.status == "optimal" and explains(pr, i.witness)
    lp = res.lp.bounds
    assert np.all(res.bounds[:, 0] >= lp[:, 0] - 1e-12)
    assert np.all(res.bounds[:, 1] <= lp[:, 1] + 1e-12)


def test_working_set_limits_give_valid_outer_bounds():
    pr, theta, full, _ = _pair()
    res = exact_bounds(pr, tol=TOL, working_set=True, max_nodes=1)
    assert res.contains(theta)
    inner = full.inner  # hull of the full method's verified witnesses
    assert np.all(res.bounds[:, 0] <= inner[:, 0]) and np.all(res.bounds[:, 1] >= inner[:, 1])
    for i in res.infos:
        assert i.status in ("optimal", "limit") and i.gap is not None


def test_check_theta_witness_only_saves_the_lp_never_changes_the_rule():
    from hammerbound.relaxations.problem import check_theta

    data, theta = chapter_eiv_data(N=60, deta=0.05, seed=4)

    pr = EIVProblem(**data)
    ref = check_theta(pr, theta)
    assert ref.feasible
    # its own witness is accepted as is
    chk = check_theta(pr, theta, witness=(ref.eta, ref.dx))
    assert chk.feasible and np.allclose(chk.eta, ref.eta)
    # a useless witness falls back to the LP: same decision
    chk = check_theta(pr, theta, witness=(np.zeros(pr.N), np.zeros(pr.n_groups)))
    assert chk.feasible
    # an infeasible theta stays infeasible whatever witness is offered
    bad = theta.copy()
    bad[0] += 0.5
    assert not check_theta(pr, bad).feasible
    assert not check_theta(pr, bad, witness=(ref.eta, ref.dx)).feasible
    assert not check_theta(pr, bad, witness=(np.full(pr.N, 9.0), np.zeros(pr.n_groups))).feasible


def test_automatic_working_set_only_for_independent_input_errors():
    """working_set=None: a working set from AUTO_MIN_EQUATIONS equations on, but not with
    input errors shared by groups of samples (two-level), where the full LPs with the SLP
    walk are faster; either way the bounds are certified and the truth is inside."""
    from hammerbound.relaxations.exact.working_set import AUTO_MIN_EQUATIONS

    n = AUTO_MIN_EQUATIONS + 20
    data, truth = two_level_data(0, N=n, deta=0.05)
    shared = EIVProblem(**data)
    res = exact_bounds(shared, tol=1e-4, max_nodes=50)
    assert res.details.working_set is None
    assert np.all((res.bounds[:, 0] <= truth) & (truth <= res.bounds[:, 1]))
    data, truth = chapter_eiv_data(N=n, deta=0.05, dx=0.003, seed=1)
    indep = EIVProblem(**data)
    res = exact_bounds(indep, tol=1e-4, max_nodes=50)
    assert res.details.working_set is not None
    assert np.all((res.bounds[:, 0] <= truth) & (truth <= res.bounds[:, 1]))
