"""Solver registry, the backends on conic data and verified conic bounds (solvers/)."""

from __future__ import annotations

import importlib.util

import numpy as np
import picos
import pytest
from oracles import chapter_eiv_data

from hammerbound.exceptions import SolverNotAvailableError, SolverOptionError
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.moment.relaxation import moment_bounds
from hammerbound.relaxations.problem import EIVProblem
from hammerbound.solvers import (
    BACKENDS,
    available_solvers,
    extract_conic_data,
    get_solver,
    normalise_status,
    verified_lower_bound,
)
from hammerbound.solvers.clarabel import ClarabelConic
from hammerbound.solvers.conic import best_certificate, repair_dual

HAVE_CVXOPT = importlib.util.find_spec("cvxopt") is not None
needs_cvxopt = pytest.mark.skipif(not HAVE_CVXOPT, reason="cvxopt not installed")

C3 = np.array([[2.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 1.0]])


def lp_problem():
    """max x1 + x2  s.t.  x1 + 2 x2 <= 4, 3 x1 + x2 <= 6, x >= 0  (optimum 2.8 at (1.6, 1.2))."""
    P = picos.Problem()
    x = picos.RealVariable("x", 2)
    c1 = P.add_constraint(picos.Constant([[1, 2], [3, 1]]) * x <= [4, 6])
    c2 = P.add_constraint(x >= 0)
    P.set_objective("max", picos.Constant([1, 1]).T * x)
    return P, x, (c1, c2)


def sdp_problem():
    """min <C, X>  s.t.  trace X = 1, X >= 0  (optimum lambda_min(C))."""
    P = picos.Problem()
    X = picos.SymmetricVariable("X", 3)
    c1 = P.add_constraint(picos.trace(X) == 1)
    c2 = P.add_constraint(X >> 0)
    P.set_objective("min", picos.Constant(C3) | X)
    return P, X, (c1, c2)


def soc_problem():
    """min ||A x - b|| + 0 (least squares through a second-order cone)."""
    rng = np.random.default_rng(0)
    A = rng.standard_normal((6, 3))
    b = rng.standard_normal(6)
    P = picos.Problem()
    x = picos.RealVariable("x", 3)
    t = picos.RealVariable("t")
    c1 = P.add_constraint(abs(picos.Constant(A) * x - picos.Constant(b)) <= t)
    P.set_objective("min", t)
    xs = np.linalg.lstsq(A, b, rcond=None)[0]
    return P, x, (c1,), float(np.linalg.norm(A @ xs - b)), xs


# ---------------------------------------------------------------------------------------
# registry
# ---------------------------------------------------------------------------------------


def test_available_solvers_and_lookup():
    avail = available_solvers()
    assert avail[0] == "clarabel"
    assert ("cvxopt" in avail) == HAVE_CVXOPT
    assert set(avail) <= set(BACKENDS)
    for name in avail:
        b = get_solver(name)
        assert b.name == name and b.available()
    assert get_solver(None).name == "clarabel"
    assert get_solver(" Clarabel ").name == "clarabel"


def test_unknown_solver_lists_the_available_ones():
    with pytest.raises(SolverNotAvailableError) as ei:
        get_solver("gurobi")
    msg = str(ei.value)
    assert "gurobi" in msg
    for name in available_solvers():
        assert name in msg
    assert isinstance(ei.value, ValueError)


def test_mosek_backend_if_installed():
    if "mosek" not in available_solvers():
        with pytest.raises(SolverNotAvailableError) as ei:
            get_solver("mosek")
        assert "clarabel" in str(ei.value)
        pytest.skip("MOSEK not installed/licensed (unavailability is reported correctly)")
    data = extract_conic_data(lp_problem()[0])  # pragma: no cover - only with MOSEK
    sol = get_solver("mosek").conic(data).solve()
    assert -sol.primal_value == pytest.approx(2.8, abs=1e-6)


def test_normalise_status():
    assert normalise_status("clarabel", "Solved") == "optimal"
    assert normalise_status("clarabel", "MaxIterations") == "limit"
    assert normalise_status("cvxopt", "unknown") == "inaccurate"
    assert normalise_status("clarabel", "SomethingNew") == "failed"
    assert normalise_status("nosuch", "optimal") == "failed"


# ---------------------------------------------------------------------------------------
# options
# ---------------------------------------------------------------------------------------

BAD_OPTIONS = [
    ("clarabel", {"max_iterations": 5}),
    ("clarabel", {"max_iter": "ten"}),
    ("clarabel", {"max_iter": 2.5}),
    ("clarabel", {"max_iter": -1}),
    ("clarabel", {"tol_feas": "tight"}),
    ("clarabel", {"verbose": "yes"}),
    ("cvxopt", {"max_iter": 5}),
    ("cvxopt", {"maxiters": "ten"}),
    ("cvxopt", {"abstol": "small"}),
    ("qics", {"max_iter": 5}),
    ("qics", {"max_iterations": "ten"}),
    ("qics", {"qics_params": 3}),
]


@pytest.mark.parametrize("name,opts", BAD_OPTIONS)
def test_bad_options_raise_solver_option_error(name, opts):
    if name not in available_solvers():
        pytest.skip(f"{name} not installed")
    backend = get_solver(name)
    with pytest.raises(SolverOptionError) as ei:
        backend.check_options(opts)
    assert isinstance(ei.value, TypeError)
    assert next(iter(opts)) in str(ei.value)
    data = extract_conic_data(lp_problem()[0])
    with pytest.raises(SolverOptionError):
        backend.conic(data, opts)


def test_valid_options_pass_and_take_effect():
    assert get_solver("clarabel").check_options({"max_iter": 7, "tol_feas": 1e-7}) == {
        "max_iter": 7, "tol_feas": 1e-7}
    P, _, _ = sdp_problem()
    data = extract_conic_data(P)
    sol = ClarabelConic(data, {"max_iter": 1}).solve()
    assert sol.native_status == "MaxIterations" and sol.status == "limit"
    assert sol.iterations <= 1
    full = ClarabelConic(data, {}).solve()
    assert full.status == "optimal" and full.iterations > 1
    if HAVE_CVXOPT:
        sol = get_solver("cvxopt").conic(data, {"maxiters": 1}).solve()
        assert sol.iterations <= 1 and sol.status != "optimal"


# ---------------------------------------------------------------------------------------
# conic layer and verified bounds
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("make", [lp_problem, sdp_problem])
def test_conic_backends_agree_and_certify(make):
    P = make()[0]
    data = extract_conic_data(P)
    sign = 1.0 if data.sense == "min" else -1.0
    opt = 2.8 if make is lp_problem else np.linalg.eigvalsh(C3)[0]
    xub = np.full(data.n, 10.0)  # every feasible point of both problems is inside
    names = available_solvers()  # the PICOS-solved ones too (e.g. QICS)
    for name in names:
        sol = get_solver(name).conic(data, {}).solve()
        assert sol.status == "optimal"
        assert sign * sol.primal_value == pytest.approx(opt, abs=1e-6)
        vb = verified_lower_bound(data, data.q, sol.z, xub, data.q0)
        # a lower bound of the minimisation, i.e. of sign * opt, and a tight one
        assert vb.bound <= sign * opt + 1e-12
        assert vb.bound >= sign * opt - 1e-5


def test_verified_bound_corrects_a_non_psd_dual():
    """An exactly dual-feasible-looking z whose PSD block is indefinite must be corrected.

    For min <C, X>, trace X = 1, X >= 0 the dual is max y s.t. C - y I >= 0; z built
    from y = lambda_min + 0.5 satisfies q + A'z = 0 exactly but claims a value above the
    optimum. The certificate must pay for the negative eigenvalue.
    """
    P = sdp_problem()[0]
    data = extract_conic_data(P)
    assert [k for k, _ in data.cones] == ["z", "s"]
    lam = np.linalg.eigvalsh(C3)[0]
    iu = np.triu_indices(3)
    order = np.lexsort((iu[0], iu[1]))
    r, c = iu[0][order], iu[1][order]

    def z_of(y):
        Z = C3 - y * np.eye(3)
        return np.concatenate([[-y], np.where(r == c, Z[r, c], np.sqrt(2) * Z[r, c])])

    xub = np.full(data.n, 2.0)
    for y in (lam - 0.1, lam, lam + 0.01, lam + 0.5, lam + 5.0):
        z = z_of(y)
        np.testing.assert_allclose(data.q + data.A.T @ z, 0.0, atol=1e-12)
        vb = verified_lower_bound(data, data.q, z, xub, data.q0)
        assert vb.dual_value == pytest.approx(y)
        assert vb.bound <= lam + 1e-12, (y, vb)
        if y > lam:
            assert vb.psd_correction > 0
        else:
            assert vb.bound == pytest.approx(y, abs=1e-9)  # nothing to correct


def test_best_certificate_is_sound_and_beats_the_repair_alone():
    """An interior-point dual that stopped early (the exact dual of min <C, X>, trace X = 1,
    X >= 0, perturbed by 1e-4) has a residual and an indefinite block. Every candidate of
    ``best_certificate`` is a dual vector: its bound stays below lambda_min(C), is at least
    that of the dual and of its repair, and the alternating projections gain on some draws
    (measured: 3 of 5)."""
    data = extract_conic_data(sdp_problem()[0])
    lam = np.linalg.eigvalsh(C3)[0]
    iu = np.triu_indices(3)
    order = np.lexsort((iu[0], iu[1]))
    r, c = iu[0][order], iu[1][order]
    Z = C3 - lam * np.eye(3)
    z_opt = np.concatenate([[-lam], np.where(r == c, Z[r, c], np.sqrt(2) * Z[r, c])])
    xub = np.full(data.n, 2.0)
    rng = np.random.default_rng(0)
    gains = 0
    for _ in range(5):
        z = z_opt + 1e-4 * rng.standard_normal(data.m)
        raw = verified_lower_bound(data, data.q, z, xub, data.q0).bound
        rep = verified_lower_bound(data, data.q, repair_dual(data, data.q, z), xub,
                                   data.q0).bound
        best = best_certificate(data, data.q, z, xub, data.q0).bound
        assert best <= lam + 1e-12
        assert best >= max(raw, rep)
        gains += best > rep + 1e-9
    assert gains >= 1


def test_best_certificate_keeps_the_repair_when_a_projection_fails(monkeypatch):
    """A projection that raises (e.g. eigenvalues that do not converge on a NaN block)
    must not throw away the candidates already certified."""
    from hammerbound.solvers import conic

    data = extract_conic_data(sdp_problem()[0])
    lam = np.linalg.eigvalsh(C3)[0]
    z = np.random.default_rng(1).standard_normal(data.m) * 1e-4
    z[0] = -lam
    xub = np.full(data.n, 2.0)
    rep = verified_lower_bound(data, data.q, repair_dual(data, data.q, z), xub, data.q0)

    def failing(*args, **kwargs):
        raise np.linalg.LinAlgError("Eigenvalues did not converge")

    monkeypatch.setattr(conic, "project_dual", failing)
    assert best_certificate(data, data.q, z, xub, data.q0).bound >= rep.bound


# ---------------------------------------------------------------------------------------
# the moment relaxation on two backends
# ---------------------------------------------------------------------------------------


@needs_cvxopt
def test_moment_order1_clarabel_and_cvxopt_agree():
    data, theta = chapter_eiv_data(N=12, deta=0.05, seed=9)
    pr = EIVProblem(**data)
    box = lp_bounds(pr).bounds
    r_cl = moment_bounds(pr, order=1, theta_box=box, solver="clarabel")
    r_cv = moment_bounds(pr, order=1, theta_box=box, solver="cvxopt")
    assert r_cv.details.solver == "cvxopt"
    for r in (r_cl, r_cv):
        assert r.contains(theta)
        assert all(i.certified for i in r.infos)
    np.testing.assert_allclose(r_cl.bounds, r_cv.bounds, atol=1e-5)
