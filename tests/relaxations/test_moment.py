"""Sparse moment relaxations with certified dual bounds (moment.py, solvers/conic.py) and
the term-sparse order-2 basis."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from oracles import boundary_case, chapter_eiv_data

from hammerbound import LinearEIVSetEstimator
from hammerbound.exceptions import (
    ParameterValidationError,
    SolverError,
    SolverNotAvailableError,
    SolverOptionError,
)
from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.moment import size as moment_size
from hammerbound.relaxations.moment.relaxation import MomentRelaxation, moment_bounds
from hammerbound.relaxations.problem import EIVProblem, check_theta
from hammerbound.solvers import available_solvers, get_solver
from hammerbound.solvers.clarabel import ClarabelConic
from hammerbound.solvers.conic import verified_lower_bound

ATOL = 1e-7  # slack of check_theta's acceptance, see tests/test_lp.py


def first_order_problem(N=10, deta=0.05, dx=0.01, two_level=False, seed=0):
    """y_t - 0.6 y_{t-1} = 0.4 x_{t-1} (unit gain) with a two-level inner signal."""
    rng = np.random.default_rng(seed)
    A, B = np.array([1.0, -0.6]), np.array([0.0, 0.4])
    lev = np.where(rng.random(N) < 0.5, 1.0, -1.0)
    lev[:2] = [1.0, -1.0]
    from scipy.signal import lfilter

    y = lfilter(B, A, lev) + rng.uniform(-deta, deta, N)
    shift = rng.uniform(-dx, dx, 2)
    xc = np.where(lev > 0, 1.0 + shift[0], -1.0 + shift[1])
    groups = (lev < 0).astype(int) if two_level else None
    pr = EIVProblem(y, xc, dx, deta, na=1, nb=1, steady_state_gain=1.0, groups=groups)
    return pr, np.array([-0.6, 0.4])


@functools.cache
def _chapter(seed, deta, two_level, N=30):
    data, theta = chapter_eiv_data(N=N, deta=deta, two_level=two_level, seed=seed)
    pr = EIVProblem(**data)
    lp = lp_bounds(pr)
    ex = exact_bounds(pr, tol=1e-3)
    return pr, theta, lp, ex, feasible_points(pr, theta, ex, seed)


@functools.cache
def _order1(seed, deta, two_level):
    pr, theta, lp, ex, pts = _chapter(seed, deta, two_level)
    return moment_bounds(pr, order=1, theta_box=lp.bounds)


def feasible_points(pr, theta, ex, seed, n=60):
    """theta_true, the exact witnesses and verified random points of the exact box."""
    rng = np.random.default_rng(seed)
    W = np.array([i.witness for i in ex.infos if i.witness is not None])
    cands = [theta, *W] + [rng.dirichlet(np.ones(len(W))) @ W for _ in range(n // 2)]
    g_row, g_rhs = pr.gain_row()
    for _ in range(n // 2):
        th = rng.uniform(ex.bounds[:, 0], ex.bounds[:, 1])
        th[-1] = (g_rhs - g_row[:-1] @ th[:-1]) / g_row[-1]
        cands.append(th)
    pts = np.array([th for th in cands if check_theta(pr, th).feasible])
    assert len(pts) >= len(W) + 1
    return pts


def assert_sound(res, pts, box, atol=ATOL):
    """Every bound contains the verified points, or is an uncertified box end."""
    for j, info in enumerate(res.infos):
        k, e = divmod(j, 2)
        assert info.bound == res.bounds[k, e]
        if info.certified:
            if e == 0:
                assert info.bound <= pts[:, k].min() + atol, (info, pts[:, k].min())
            else:
                assert info.bound >= pts[:, k].max() - atol, (info, pts[:, k].max())
        else:
            assert info.bound == box[k, e], info
            assert "no certificate" in info.message
        # never outside the a priori box
        assert box[k, 0] <= info.bound <= box[k, 1]


# ---------------------------------------------------------------------------------------
# containment of the truth and of verified points; nesting
# ---------------------------------------------------------------------------------------

ORDER1_CASES = [(0, 0.005, False), (1, 0.05, False), (2, 0.2, False), (3, 0.05, True)]


@pytest.mark.parametrize("seed,deta,two_level", ORDER1_CASES)
def test_order1_contains_truth_and_every_verified_point(seed, deta, two_level):
    pr, theta, lp, ex, pts = _chapter(seed, deta, two_level)
    res = _order1(seed, deta, two_level)
    assert res.method == "moment" and res.details.order == 1
    assert res.details.solver == "clarabel" and res.details.eliminated in res.param_names
    assert res.contains(theta), (res.bounds, theta)
    assert all(i.certified for i in res.infos), [i.message for i in res.infos]
    assert_sound(res, pts, lp.bounds)
    # the certificate is not vacuous: the moment intervals are tighter than the LP ones
    assert np.sum(res.width) < np.sum(lp.width)
    for j, info in enumerate(res.infos):
        k, e = divmod(j, 2)
        cert = info.certificate
        assert cert.psd_correction >= 0 and cert.residual_correction >= 0
        # the reported bound is the dual value minus the (non-negative) corrections, or
        # the box end when that is tighter
        if e == 0:
            assert info.bound <= cert.dual_value + 1e-12 or info.bound == lp.bounds[k, 0]
        else:
            assert info.bound >= cert.dual_value - 1e-12 or info.bound == lp.bounds[k, 1]


def test_two_level_moment_intervals_inside_independent_ones():
    """Identifying the input errors of a level is a restriction of the relaxation too."""
    pr_t, theta, lp, _, pts_t = _chapter(1, 0.05, True)
    pr_i, _, lp_i, _, _ = _chapter(1, 0.05, False)
    np.testing.assert_array_equal(pr_i.y, pr_t.y)
    r_t, r_i = _order1(1, 0.05, True), _order1(1, 0.05, False)
    assert r_t.contains(theta)
    # two-level verified points belong to the independent set and its moment intervals
    assert_sound(r_i, pts_t, lp_i.bounds)
    assert np.all(r_t.bounds[:, 0] >= r_i.bounds[:, 0] - 1e-6)
    assert np.all(r_t.bounds[:, 1] <= r_i.bounds[:, 1] + 1e-6)
    assert np.sum(r_t.width) < np.sum(r_i.width)


@pytest.mark.parametrize("two_level", [False, True])
def test_order2_is_sound_and_tighter_than_order1(two_level):
    pr, theta = first_order_problem(N=10, deta=0.05, two_level=two_level, seed=1)
    lp = lp_bounds(pr)
    ex = exact_bounds(pr, tol=1e-7)
    pts = np.array([theta] + [i.witness for i in ex.infos])
    assert all(check_theta(pr, t).feasible for t in pts)
    r1 = moment_bounds(pr, order=1, theta_box=lp.bounds)
    r2 = moment_bounds(pr, order=2, theta_box=lp.bounds)
    assert r2.details.order == 2 and r2.details.n_moments > r1.details.n_moments
    for r in (r1, r2):
        assert r.contains(theta)
        assert all(i.certified for i in r.infos)
        assert_sound(r, pts, lp.bounds)
    # the hierarchy is monotone (up to the solver accuracy of the two certificates)
    assert np.all(r2.bounds[:, 0] >= r1.bounds[:, 0] - 1e-6)
    assert np.all(r2.bounds[:, 1] <= r1.bounds[:, 1] + 1e-6)
    # ... and order 2 is (nearly) tight here: it lies within 1e-3 of the exact intervals
    np.testing.assert_allclose(r2.bounds, ex.bounds, atol=1e-3)


def test_default_problem_box_is_used():
    pr, theta = first_order_problem(N=12, deta=0.05, seed=2)
    box = np.array([[-0.9, -0.3], [0.1, 0.7]])
    boxed = pr.with_theta_box(box)
    res = moment_bounds(boxed, order=1)
    assert res.contains(theta)
    assert np.all(res.bounds[:, 0] >= box[:, 0]) and np.all(res.bounds[:, 1] <= box[:, 1])
    # without theta_box the reported bounds are also never wider than the LP bounds (the
    # fallback of on_failure="box"; monotone knowledge)
    lp = lp_bounds(boxed, check_box=False).bounds
    np.testing.assert_allclose(
        res.bounds, moment_bounds(pr, order=1, theta_box=box, fallback=lp).bounds, atol=1e-9)


# ---------------------------------------------------------------------------------------
# the term-sparse order-2 basis (basis="sparse", issue 15 item 5): sound against the exact
# method and the truth with noise exactly at +-D; the full basis stays available and is at
# least as tight
# ---------------------------------------------------------------------------------------


def test_sparse_basis_structure_on_the_chapter_model():
    """na = nb = 2 with input errors: 8 clique variables, 24 x 24 moment matrices (not
    45 x 45), noise boxes on {1, theta} (4 x 4), theta boxes scalar, and the size
    estimate counts exactly what is built."""
    data, _ = chapter_eiv_data(N=8, deta=0.05, dx=0.003, seed=3)
    pr = EIVProblem(**data)
    sp_ = MomentRelaxation(pr, 2, basis="sparse")
    full = MomentRelaxation(pr, 2, basis="full")
    assert set(sp_.psd_sides) == {1, 4, 24} and set(full.psd_sides) == {9, 45}
    assert sp_.psd_sides[24] == len(sp_.pop.cliques) == full.psd_sides[45]
    # one 4 x 4 localizer per noise variable, not one per clique and variable
    n_noise = sp_.pop.n - sp_.pop.q
    assert sp_.psd_sides[4] == n_noise
    assert sp_.data.m < full.data.m / 3 and sp_.n_moments < full.n_moments / 2
    for basis, rel in (("sparse", sp_), ("full", full)):
        est = moment_size.estimate_moment_relaxation(pr, 2, basis=basis)
        assert (est.n_rows, est.n_moments) == (rel.data.m, rel.n_moments), basis
    # every moment of the sparse relaxation is an entry of a moment matrix: theta-degree
    # <= 2 and noise-degree <= 2
    q = sp_.pop.q
    for mono in sp_.index:
        assert sum(v < q for v in mono) <= 2 and sum(v >= q for v in mono) <= 2, mono


@pytest.mark.deep
def test_sparse_order2_equals_exact_on_the_chapter_model():
    """Chapter model (na = nb = 2, input errors, gain equality): every certified end within
    1e-3 of the exact width, every verified feasible point inside."""
    data, theta = chapter_eiv_data(N=8, deta=0.05, dx=0.003, seed=4)
    pr = EIVProblem(**data)
    lp = lp_bounds(pr)
    ex = exact_bounds(pr, tol=1e-6)
    pts = feasible_points(pr, theta, ex, 4, n=20)
    res = moment_bounds(pr, order=2, theta_box=lp.bounds, n_jobs=2)
    assert res.details.basis == "sparse"
    assert all(i.certified for i in res.infos), [i.message for i in res.infos]
    assert res.contains(theta)
    assert_sound(res, pts, lp.bounds)
    w = ex.bounds[:, 1] - ex.bounds[:, 0]
    # outer (up to the exact method's tolerance) and tight
    assert np.all(res.bounds[:, 0] <= ex.bounds[:, 0] + 1e-5)
    assert np.all(res.bounds[:, 1] >= ex.bounds[:, 1] - 1e-5)
    assert np.all(np.abs(res.bounds - ex.bounds) <= 1e-3 * w[:, None]), (res.bounds, ex.bounds)


def test_full_basis_kept_and_at_least_as_tight():
    pr, theta = first_order_problem(N=10, deta=0.05, seed=5)
    lp = lp_bounds(pr)
    ex = exact_bounds(pr, tol=1e-7)
    pts = np.array([theta] + [i.witness for i in ex.infos])
    assert all(check_theta(pr, t).feasible for t in pts)
    rs = moment_bounds(pr, order=2, theta_box=lp.bounds, basis="sparse")
    rf = moment_bounds(pr, order=2, theta_box=lp.bounds, basis="full")
    assert rf.details.basis == "full" and rf.details.n_moments > rs.details.n_moments
    for r in (rs, rf):
        assert all(i.certified for i in r.infos)
        assert r.contains(theta)
        assert_sound(r, pts, lp.bounds)
    # (up to the accuracy of the two certificates)
    assert np.all(rf.bounds[:, 0] >= rs.bounds[:, 0] - 1e-5)
    assert np.all(rf.bounds[:, 1] <= rs.bounds[:, 1] + 1e-5)


# order-2 boundary cases of oracles.boundary_case (the design of test_boundary_stage2.py):
# noise exactly at +-D, scales 1e-2 and 1, with and without the gain equality, via the
# function and the estimator (the cases with input errors take ~30-60 s each under load:
# input errors at +-D are covered by the chapter-model test above, dx at its bound is
# inside the set like any other value)
BOUNDARY_CASES = [7, 48]


@pytest.mark.deep
@pytest.mark.parametrize("i", BOUNDARY_CASES)
def test_sparse_order2_contains_the_truth_with_noise_at_the_bound(i):
    kw, theta, via_estimator = boundary_case(i)
    assert kw["na"] == 2
    pr = EIVProblem(kw["y"], kw["x"], kw["dx"], kw["deta"], 2, 2, steady_state_gain=kw["gain"])
    assert check_theta(pr, theta).feasible
    if via_estimator:
        est = LinearEIVSetEstimator(na=2, nb=2, output_bound=kw["deta"], method="moment",
                                    relaxation_order=2, steady_state_gain=kw["gain"],
                                    theta_box=pr.theta_box, on_failure="box")
        bounds = est.fit(kw["x"], kw["y"], input_bound=kw["dx"]).bounds_
    else:
        lp = lp_bounds(pr, check_box=False).bounds
        bounds = moment_bounds(pr, order=2, theta_box=lp).bounds
    assert np.all(theta >= bounds[:, 0]) and np.all(theta <= bounds[:, 1]), (i, bounds, theta)


def test_bad_basis_raises():
    pr, _ = first_order_problem(N=6)
    with pytest.raises(ParameterValidationError, match="basis"):
        moment_bounds(pr, order=2, basis="dense")
    with pytest.raises(ParameterValidationError, match="basis"):
        MomentRelaxation(pr, 2, basis="dense")


# ---------------------------------------------------------------------------------------
# soundness under an inexact or failing solver
# ---------------------------------------------------------------------------------------

CRIPPLED = [
    ("clarabel", {"max_iter": 3}),
    ("clarabel", {"max_iter": 5}),
    ("clarabel", {"tol_gap_abs": 1e-1, "tol_gap_rel": 1e-1, "tol_feas": 1e-1,
                  "tol_ktratio": 1e-1}),
    ("clarabel", {"max_iter": 8, "static_regularization_constant": 1e-3}),
    ("cvxopt", {"maxiters": 2}),
    ("cvxopt", {"abstol": 1e-1, "reltol": 1e-1, "feastol": 1e-1}),
]


@pytest.mark.parametrize("solver,opts", CRIPPLED)
def test_crippled_solver_never_reports_a_too_tight_bound(solver, opts):
    if solver not in available_solvers():
        pytest.skip(f"{solver} not installed")
    pr, theta, lp, ex, pts = _chapter(1, 0.05, False)
    res = moment_bounds(pr, order=1, theta_box=lp.bounds, solver=solver, solver_options=opts)
    assert_sound(res, pts, lp.bounds)
    it_cap = opts.get("max_iter", opts.get("maxiters"))
    if it_cap is not None:  # the option reached the solver
        for info in res.infos:
            assert info.iterations is not None and info.iterations <= it_cap
        if solver == "clarabel":  # the solve's status, or the LP end where it is not tighter
            for k, info in enumerate(res.infos):
                at_lp = info.bound == lp.bounds[k // 2, k % 2]
                assert info.status in (("relaxation", "box") if at_lp else ("limit", "optimal"))
    try:
        raised = moment_bounds(pr, order=1, theta_box=lp.bounds, solver=solver,
                               solver_options=opts, on_failure="raise")
    except SolverError as exc:
        assert solver in str(exc)
    else:
        assert all(i.certified for i in raised.infos)
        assert_sound(raised, pts, lp.bounds)


def _fake_solve(kind):
    orig = ClarabelConic.solve

    def solve(self, q=None, q0=0.0):
        if kind == "raise":
            raise RuntimeError("simulated solver crash")
        sol = orig(self, q, q0)
        if kind == "no_dual":
            sol.z = None
        elif kind == "nan_dual":
            sol.z = np.full_like(sol.z, np.nan)
        elif kind == "lying":
            # a solver that claims optimality with a dual that is off and a too-good value
            rng = np.random.default_rng(int(1e6 * abs(np.sum(q))) % 2**32)
            sol.z = sol.z * (1 + 0.3 * rng.standard_normal(sol.z.size)) + 0.05 * (
                rng.standard_normal(sol.z.size))
            sol.primal_value = sol.dual_value = sol.primal_value + 1.0
            sol.status, sol.native_status = "optimal", "Solved"
        elif kind == "shifted":
            # dual slightly scaled up: dual value above the optimum, cone/residual errors
            sol.z = 1.05 * sol.z
        return sol

    return solve


@pytest.mark.parametrize("kind", ["raise", "no_dual", "nan_dual"])
def test_failing_solver_reports_box_end_or_raises(monkeypatch, kind):
    pr, theta, lp, ex, pts = _chapter(1, 0.05, False)
    monkeypatch.setattr(ClarabelConic, "solve", _fake_solve(kind))
    res = moment_bounds(pr, order=1, theta_box=lp.bounds)
    assert not any(i.certified for i in res.infos)
    np.testing.assert_array_equal(res.bounds, lp.bounds)
    assert_sound(res, pts, lp.bounds)
    if kind == "raise":
        assert all("simulated solver crash" in i.message for i in res.infos)
    with pytest.raises(SolverError, match="could not certify the min of a1"):
        moment_bounds(pr, order=1, theta_box=lp.bounds, on_failure="raise")


@pytest.mark.parametrize("kind", ["lying", "shifted"])
def test_wrong_dual_from_solver_is_still_sound(monkeypatch, kind):
    pr, theta, lp, ex, pts = _chapter(1, 0.05, False)
    monkeypatch.setattr(ClarabelConic, "solve", _fake_solve(kind))
    res = moment_bounds(pr, order=1, theta_box=lp.bounds)
    assert_sound(res, pts, lp.bounds)
    for info in res.infos:  # the solver's (wrong) value is never what is reported
        assert info.bound != info.solver_value


def test_verified_bound_of_perturbed_duals_stays_below_the_feasible_values():
    """Direct test of the certificate: arbitrary dual vectors never give a too-high bound."""
    pr, theta, lp, ex, pts = _chapter(0, 0.05, False)
    relax = MomentRelaxation(pr, 1, lp.bounds)
    data = relax.data.strip_picos()
    inst = get_solver("clarabel").conic(data, {})
    rng = np.random.default_rng(0)
    for k, sense, q, q0 in relax.objectives():
        target = pts[:, k].min() if sense == "min" else -pts[:, k].max()
        sol = inst.solve(q, q0)
        vb = verified_lower_bound(data, q, sol.z, relax.xub, q0)
        assert vb.bound <= target + ATOL
        assert vb.bound >= target - 0.05  # a useful certificate from a good dual
        assert vb.bound <= vb.dual_value
        for scale in (1e-6, 1e-3, 1e-1, 1.0):
            z = sol.z + scale * np.abs(sol.z).max() * rng.standard_normal(sol.z.size)
            assert verified_lower_bound(data, q, z, relax.xub, q0).bound <= target + ATOL
        for z in (2.0 * sol.z, -sol.z, np.zeros_like(sol.z), rng.standard_normal(sol.z.size)):
            assert verified_lower_bound(data, q, z, relax.xub, q0).bound <= target + ATOL
        assert verified_lower_bound(data, q, sol.z[:-1], relax.xub, q0).bound == -np.inf
        z = sol.z.copy()
        z[0] = np.inf
        assert verified_lower_bound(data, q, z, relax.xub, q0).bound == -np.inf


# ---------------------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("kwargs,exc", [
    (dict(order=0), ParameterValidationError),
    (dict(order=1.5), ParameterValidationError),
    (dict(order=-1), ParameterValidationError),
    (dict(on_failure="ignore"), ParameterValidationError),
    (dict(theta_box=np.zeros((3, 2))), ParameterValidationError),
    (dict(theta_box=np.array([[0.0, -1.0], [0.0, 1.0]])), ParameterValidationError),
    (dict(theta_box=np.array([[np.nan, 1.0], [0.0, 1.0]])), ParameterValidationError),
    (dict(solver="gurobi"), SolverNotAvailableError),
    (dict(solver_options={"max_iterations": 5}), SolverOptionError),
    (dict(solver_options={"max_iter": "five"}), SolverOptionError),
    (dict(solver="cvxopt", solver_options={"max_iter": 5}), SolverOptionError),
])
def test_bad_arguments_raise_typed_errors(kwargs, exc):
    if kwargs.get("solver") == "cvxopt" and "cvxopt" not in available_solvers():
        pytest.skip("cvxopt not installed")
    pr, _ = first_order_problem(N=8)
    box = np.array([[-0.9, -0.3], [0.1, 0.7]])
    kw = dict(order=1, theta_box=box)
    kw.update(kwargs)
    with pytest.raises(exc):
        moment_bounds(pr, **kw)


def test_equality_rows_in_blocks_give_the_same_relaxation(monkeypatch):
    """PICOS indexes a constant's entries with 32 bits, so the equality rows go to it in
    blocks (a SystemError at N = 2000, order 2, before). Blocks of a few rows build the
    same conic rows and the same certified bounds as one block."""
    from hammerbound.relaxations.moment import relaxation as moment_module

    pr, _ = first_order_problem(N=10, dx=0.0)
    one = MomentRelaxation(pr, 1)
    b_one = moment_bounds(pr, order=1).bounds
    monkeypatch.setattr(moment_module, "EQ_BLOCK_ENTRIES", 3 * one.n_moments)
    blocks = MomentRelaxation(pr, 1)
    assert blocks.data.m == one.data.m and blocks.n_moments == one.n_moments
    assert len(blocks.picos_problem.constraints) > len(one.picos_problem.constraints) + 1
    np.testing.assert_allclose(moment_bounds(pr, order=1).bounds, b_one, atol=1e-9)
