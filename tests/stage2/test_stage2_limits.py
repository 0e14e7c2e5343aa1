"""Monotone knowledge (issue 19), total time budget (issue 20) and the moment size guard
(issue 13, item 5) of stage 2."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.signal import lfilter
from sklearn.base import clone

import hammerbound as hb
from hammerbound import LinearEIVSetEstimator
from hammerbound.exceptions import (
    ParameterValidationError,
    RelaxationTooLargeError,
    SearchLimitWarning,
)
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.moment import size as moment_size
from hammerbound.relaxations.moment.relaxation import MomentRelaxation, moment_bounds
from hammerbound.relaxations.problem import EIVProblem, check_theta, default_theta_box

REAL_PHYSICAL_MEMORY = moment_size.physical_memory  # before the suite fixes it

THETA = np.array([-0.76, 0.82, 2.15, -1.09])


def chapter_record(n, seed=0, d=0.05):
    """The chapter's linear block on a +-1 PRBS with uniform output noise in +-d."""
    rng = np.random.default_rng(seed)
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    y = lfilter([0.0, 2.15, -1.09], [1.0, -0.76, 0.82], x) + rng.uniform(-d, d, n)
    return x, y


def _fit(x, y, **kw):
    est = LinearEIVSetEstimator(output_bound=0.05, steady_state_gain=1.0, method="exact", **kw)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        est.fit(x, y)
    return est, [w for w in rec if issubclass(w.category, SearchLimitWarning)]


@pytest.mark.parametrize("box", [None, "default"])
def test_time_limited_exact_keeps_the_lp_bound(box):
    """Issue 19 repro family: a search stopped at its time limit reports finite bounds
    inside the LP ones, never +-inf and never a false UnboundedSetError."""
    x, y = chapter_record(300)
    theta_box = default_theta_box(2, 2, False) if box else None
    est, warns = _fit(x, y, time_limit=0.0, theta_box=theta_box)
    lp = est.result_.lp.bounds
    assert np.all(np.isfinite(est.bounds_))
    assert np.all(est.bounds_[:, 0] >= lp[:, 0]) and np.all(est.bounds_[:, 1] <= lp[:, 1])
    assert est.contains(THETA)
    assert np.all(np.isfinite(est.center_)) and np.all(np.isfinite(est.radius_))
    limited = [i for i in est.bound_info_ if i.status == "limit"]
    assert limited, "a zero time limit must stop the searches"
    assert len(warns) == 1
    for i in limited:
        assert f"{i.param} {'lower' if i.sense == 'min' else 'upper'}" in str(warns[0].message)
        assert "time limit" in i.message or "no verified" in i.message


def test_total_budget_zero_reports_the_lp_bounds_for_every_end():
    x, y = chapter_record(200)
    est, warns = _fit(x, y, total_time_limit=0.0)
    lp = est.result_.lp.bounds
    np.testing.assert_array_equal(est.bounds_, lp)
    assert all(i.status == "limit" and "total time budget" in i.message
               for i in est.bound_info_)
    assert len(warns) == 1 and "8 of 8" in str(warns[0].message)


def test_total_budget_shared_by_parallel_workers():
    x, y = chapter_record(200)
    est, _ = _fit(x, y, total_time_limit=0.0, n_jobs=2)
    assert all(i.status == "limit" for i in est.bound_info_)
    assert est.contains(THETA)


def test_identifier_passes_the_budget_to_stage_2():
    ex = hb.chapter_example(0.05, N=60)
    lin = LinearEIVSetEstimator(output_bound=0.05, method="exact", steady_state_gain=1.0)
    ident = hb.HammersteinBacklashIdentifier(hb.BacklashSetEstimator(0.05), linear=lin)
    ident.set_params(linear__total_time_limit=0.0)
    assert clone(ident).get_params()["linear__total_time_limit"] == 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SearchLimitWarning)
        ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    assert all(i.status == "limit" for i in ident.linear_.bound_info_)
    assert np.all(np.isfinite(ident.theta_bounds_))
    assert ident.contains(ex.gamma_true, ex.theta_true)


def test_moment_fallback_is_the_lp_bound_not_the_a_priori_box(monkeypatch):
    """on_failure="box" with an uncertifiable solve reports the LP bound."""
    import hammerbound.relaxations.moment.certify as moment_module

    x, y = chapter_record(15)
    pr = EIVProblem(y, x, 0.0, 0.05, 2, 2, steady_state_gain=1.0)
    lp = lp_bounds(pr, check_box=False).bounds
    # no certificate for any bound (as after a solver failure)
    monkeypatch.setattr(moment_module, "best_certificate", lambda *a, **k: None)
    res = moment_bounds(pr, order=1, on_failure="box")
    assert not any(i.certified for i in res.infos)
    assert np.all(lp[:, 1] - lp[:, 0] < 0.5 * np.diff(pr.theta_box, axis=1)[:, 0])
    for j, info in enumerate(res.infos):
        k, e = divmod(j, 2)
        assert (lp[k, 0] <= res.bounds[k, e] <= lp[k, 1]), (res.bounds, lp)
        if not info.certified:
            assert res.bounds[k, e] == lp[k, e]
    assert res.contains(THETA)


def _problem(n, dx=0.0, na=2, groups=False, gain=1.0):
    x, y = chapter_record(n)
    g = (x < 0).astype(int) if groups else None
    return EIVProblem(y, x, dx, 0.05, na, 2, steady_state_gain=gain, groups=g)


@pytest.mark.parametrize("n,order,dx,na,groups,gain", [
    (12, 1, 0.0, 2, False, 1.0), (12, 1, 0.01, 2, False, None), (10, 2, 0.0, 2, False, 1.0),
    (12, 1, 0.01, 1, True, 1.0), (10, 2, 0.01, 2, True, None), (8, 3, 0.0, 1, False, 1.0),
    (8, 3, 0.01, 1, False, None), (10, 3, 0.01, 2, True, None)])
def test_size_estimate_matches_the_built_relaxation(n, order, dx, na, groups, gain):
    pr = _problem(n, dx, na, groups, gain)
    est = moment_size.estimate_moment_relaxation(pr, order)
    rel = MomentRelaxation(pr, order)
    assert est.moments_exact
    assert est.n_rows == rel.data.m
    assert est.n_moments == rel.n_moments
    assert est.n_cliques == len(rel.pop.cliques)


def test_moment_guard_refuses_with_the_estimate_and_alternatives():
    """Order 3 at N = 200 is estimated at over an hour of one core (the budget): refused
    before anything is built, with the estimate and what to use instead. Order 1 at
    N = 2000 (about a minute) is only warned about."""
    x, y = chapter_record(200)
    est = LinearEIVSetEstimator(output_bound=0.05, steady_state_gain=1.0, method="moment",
                                relaxation_order=3)
    with pytest.raises(RelaxationTooLargeError, match="method='lp'") as ei:
        est.fit(x, y)
    msg = str(ei.value)
    assert "method='exact'" in msg and "198 cliques" in msg and "MB" in msg
    assert "above the budget of 3600 s (relaxation_max_work" in msg
    x, y = chapter_record(2000)
    pr = EIVProblem(y, x, 0.0, 0.05, 2, 2, steady_state_gain=1.0)
    size = moment_size.estimate_moment_relaxation(pr, 1)
    assert moment_size.MOMENT_WARN_WORK < size.work < moment_size.MOMENT_MAX_WORK
    with pytest.warns(RuntimeWarning, match="large moment relaxation"):
        moment_size.check_moment_budget(size)


def test_moment_guard_refuses_what_memory_cannot_hold(monkeypatch):
    """A relaxation within the time budget whose estimated memory, one copy per worker,
    exceeds the machine's is refused naming the memory; max_work=inf builds it anyway."""
    pr = _problem(12)
    size = moment_size.estimate_moment_relaxation(pr, 1)
    monkeypatch.setattr(moment_size, "physical_memory", lambda: 1.5 * size.est_bytes)
    moment_size.check_moment_budget(size, processes=1, warn_work=np.inf)
    with pytest.raises(RelaxationTooLargeError, match="in each of 2 processes, more than"):
        moment_size.check_moment_budget(size, processes=2)
    moment_size.check_moment_budget(size, max_work=np.inf, processes=2)
    # over both budgets: the memory is named (raising the time budget would not help)
    with pytest.raises(RelaxationTooLargeError, match="of memory \\(and above the time"):
        moment_size.check_moment_budget(size, max_work=size.work / 2, processes=2)


def test_high_order_refuses_before_forming_any_monomial(monkeypatch):
    """Issue 29.4: order 8 used to take minutes just to refuse (the moments were counted by
    enumerating the products of the basis). The count is closed-form now: the refusal
    forms no basis and no relaxation."""
    from hammerbound.relaxations.moment import basis, relaxation

    def forbidden(*args, **kwargs):
        raise AssertionError("the size estimate must not build a basis or a relaxation")

    monkeypatch.setattr(basis, "_sparse_basis", forbidden)
    monkeypatch.setattr(relaxation, "MomentRelaxation", forbidden)
    x, y = chapter_record(100)
    est = LinearEIVSetEstimator(output_bound=0.05, steady_state_gain=1.0, method="moment",
                                relaxation_order=8)
    with pytest.raises(RelaxationTooLargeError, match="order 8"):
        est.fit(x, y)


def test_moment_guard_warns_between_the_budgets():
    pr = _problem(12)
    size = moment_size.estimate_moment_relaxation(pr, 1)
    with pytest.warns(RuntimeWarning, match="large moment relaxation"):
        moment_bounds(pr, order=1, warn_work=size.work / 2)
    with pytest.raises(RelaxationTooLargeError, match=r"\(max_work; raise it"):
        moment_bounds(pr, order=1, max_work=size.work / 2)


def test_physical_memory_sees_a_container_limit(tmp_path, monkeypatch):
    """A container's memory limit (cgroup) below the machine's memory is what counts;
    "max" (no limit) leaves the machine's. (The real function: the suite's fixture fixes
    the memory every other test sees, tests/conftest.py.)"""
    limit = tmp_path / "memory.max"
    monkeypatch.setattr(moment_size, "CGROUP_LIMITS", (str(tmp_path / "none"), str(limit)))
    limit.write_text("max\n")
    machine = REAL_PHYSICAL_MEMORY()
    assert machine is None or machine > 2**20
    limit.write_text("1048576\n")
    assert REAL_PHYSICAL_MEMORY() == 1048576.0
    limit.write_text("max\n")
    assert REAL_PHYSICAL_MEMORY() == machine


def test_moment_budget_is_an_estimator_option():
    """The budget is a constructor parameter (get_params/clone/set_params), not a module
    global: below the estimate the fit refuses naming the option, inf lifts the refusal."""
    x, y = chapter_record(12)
    pr = EIVProblem(y, x, 0.0, 0.05, 2, 2, steady_state_gain=1.0)
    work = moment_size.estimate_moment_relaxation(pr, 1).work
    est = LinearEIVSetEstimator(output_bound=0.05, steady_state_gain=1.0, method="moment",
                                relaxation_max_work=work / 2)
    assert est.get_params()["relaxation_max_work"] == work / 2
    assert LinearEIVSetEstimator().relaxation_max_work == moment_size.MOMENT_MAX_WORK
    with pytest.raises(RelaxationTooLargeError, match=r"\(relaxation_max_work; raise it"):
        clone(est).fit(x, y)
    assert clone(est).set_params(relaxation_max_work=float("inf")).fit(x, y).contains(THETA)


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), "big", True, None])
def test_moment_budget_option_is_validated(bad):
    x, y = chapter_record(12)
    est = LinearEIVSetEstimator(output_bound=0.05, method="moment", relaxation_max_work=bad)
    with pytest.raises(ParameterValidationError, match="relaxation_max_work must be a number"):
        est.fit(x, y)
    if bad is not None:  # (None: the default budgets of moment_bounds)
        pr = EIVProblem(y, x, 0.0, 0.05, 2, 2)
        for name in ("max_work", "warn_work"):
            with pytest.raises(ParameterValidationError, match=f"{name} must be a number"):
                moment_bounds(pr, order=1, **{name: bad})


def _scaled_record(scale):
    n = 60
    rng = np.random.default_rng(3)
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0) * scale
    d = 0.05 * scale
    y = lfilter([0.0, 2.15, -1.09], [1.0, -0.76, 0.82], x) + d * rng.choice([-1.0, 1.0], n)
    return EIVProblem(y, x, 0.0, d, 2, 2, steady_state_gain=None), d


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 1e3, 1e6])
def test_check_theta_tolerance_is_relative_to_the_data(scale):
    """Noise exactly at +-D: the truth is accepted at every scale, and the (relative)
    violation of an infeasible point does not depend on the scale (no absolute tolerance,
    which would accept far too much at small scales)."""
    pr, d = _scaled_record(scale)
    ok = check_theta(pr, THETA)
    assert ok.feasible and ok.max_rel_violation <= 1.0
    assert np.all(np.abs(ok.eta) <= d)
    off = THETA + np.array([0.0, 0.0, 1e-6, -1e-6])
    bad, ref = check_theta(pr, off), check_theta(_scaled_record(1.0)[0], off)
    assert not bad.feasible
    assert bad.max_rel_violation == pytest.approx(ref.max_rel_violation, rel=1e-3)
