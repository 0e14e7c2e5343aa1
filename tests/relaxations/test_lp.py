"""Polytopic LP bounds (lp.py), the EIV problem (22.34) and check_theta (problem.py)."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from oracles import chapter_eiv_data
from scipy.optimize import linprog

from hammerbound.exceptions import (
    DataValidationError,
    EmptyFeasibleSetError,
    HammerboundError,
    ParameterValidationError,
    UnboundedSetError,
)
from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.problem import EIVProblem, check_theta

# check_theta accepts an equation violation up to 1e-9 * (1 + max|y|); a point accepted
# with such a violation may sit that far (in theta) outside the exact set, so sound bounds
# are compared against verified points with this absolute slack.
ATOL = 1e-7


@functools.cache
def _exact(seed, deta, two_level, N=30):
    data, _ = chapter_eiv_data(N=N, deta=deta, two_level=two_level, seed=seed)
    pr = EIVProblem(**data)
    return exact_bounds(pr, tol=1e-3)


def verified_points(problem, theta_true, exact, seed=0, n_random=120):
    """Points of (22.34) verified by check_theta: witnesses, theta_true, samples."""
    rng = np.random.default_rng(seed)
    wit = [i.witness for i in exact.infos if i.witness is not None]
    cands = [theta_true, *wit]
    W = np.array(wit)
    for _ in range(n_random // 2):  # convex combinations of witnesses
        lam = rng.dirichlet(np.ones(len(W)))
        cands.append(lam @ W)
    box = exact.bounds
    g = problem.gain_row()
    for _ in range(n_random // 2):  # random points of the exact box on the gain plane
        th = rng.uniform(box[:, 0], box[:, 1])
        if g is not None:
            th[-1] = (g[1] - g[0][:-1] @ th[:-1]) / g[0][-1]
        cands.append(th)
    pts = [th for th in cands if check_theta(problem, th).feasible]
    return np.array(pts)


def assert_contains(bounds, pts, atol=ATOL, what="bounds"):
    bounds = np.asarray(bounds)
    for th in np.atleast_2d(pts):
        below = th < bounds[:, 0] - atol
        above = th > bounds[:, 1] + atol
        assert not (below.any() or above.any()), (
            f"{what} exclude the verified-feasible point {th!r}: bounds {bounds!r}")


# ---------------------------------------------------------------------------------------
# the true parameter and the fixture
# ---------------------------------------------------------------------------------------

LP_CASES = [
    (0, 0.005, False), (1, 0.05, False), (2, 0.2, False), (3, 0.05, True), (4, 0.2, True),
    (5, 0.1, True),
]


@pytest.mark.parametrize("seed,deta,two_level", LP_CASES)
def test_true_theta_inside_lp_intervals(seed, deta, two_level):
    data, theta = chapter_eiv_data(N=40, deta=deta, two_level=two_level, seed=seed)
    pr = EIVProblem(**data)
    assert check_theta(pr, theta).feasible  # the fixture really is consistent
    res = lp_bounds(pr)
    assert res.method == "lp"
    assert res.bounds.shape == (4, 2)
    assert np.all(res.bounds[:, 0] < res.bounds[:, 1])
    assert res.contains(theta), (res.bounds, theta)
    # strictly inside the a priori box (otherwise UnboundedSetError would have been raised)
    assert np.all(res.bounds[:, 0] > pr.theta_box[:, 0])
    assert np.all(res.bounds[:, 1] < pr.theta_box[:, 1])
    assert res.param_names == ("a1", "a2", "b1", "b2")
    assert len(res.infos) == 8
    for j, info in enumerate(res.infos):
        k, e = divmod(j, 2)
        assert info.param == res.param_names[k]
        assert info.sense == ("min", "max")[e]
        assert info.bound == res.bounds[k, e]
        assert info.certified
        # the certified bound is never tighter than the solver's value
        if e == 0:
            assert info.bound <= info.solver_value + 1e-12
        else:
            assert info.bound >= info.solver_value - 1e-12


def test_lp_intervals_shrink_with_the_noise_bound():
    """Same data, larger deta: the outer set grows, so the LP intervals must be nested."""
    data, theta = chapter_eiv_data(N=40, deta=0.05, seed=7)
    pr = EIVProblem(**data)
    big = _like(pr, output_bound=2 * pr.deta)
    r_small, r_big = lp_bounds(pr), lp_bounds(big)
    assert r_big.contains(theta)
    assert np.all(r_small.bounds[:, 0] >= r_big.bounds[:, 0] - 1e-9)
    assert np.all(r_small.bounds[:, 1] <= r_big.bounds[:, 1] + 1e-9)
    assert np.sum(r_small.width) < np.sum(r_big.width)


# ---------------------------------------------------------------------------------------
# soundness against verified-feasible points (exact witnesses and samples)
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed,deta,two_level", [(0, 0.05, False), (1, 0.1, False),
                                                 (2, 0.05, True)])
def test_lp_contains_every_verified_feasible_point(seed, deta, two_level):
    data, theta = chapter_eiv_data(N=30, deta=deta, two_level=two_level, seed=seed)
    pr = EIVProblem(**data)
    ex = _exact(seed, deta, two_level)
    pts = verified_points(pr, theta, ex, seed=seed)
    assert len(pts) >= 2 * pr.p + 10  # witnesses + theta_true + a good share of samples
    res = lp_bounds(pr)
    assert_contains(res.bounds, pts, what="LP intervals")
    # every point lies in (at least) one of the reported orthant polytopes
    polys = res.polytopes
    assert 1 <= len(polys) == res.details.n_feasible_orthants <= res.details.n_orthants
    for th in pts:
        slack = [np.max(P.A @ th - P.b) for P in polys]
        assert min(slack) <= 1e-7, (th, slack)


def test_lp_bounds_match_the_reported_polytopes():
    """Re-optimise over the reported polytopes with scipy: the bounds are outer and tight."""
    data, _ = chapter_eiv_data(N=30, deta=0.1, seed=11)
    pr = EIVProblem(**data)
    res = lp_bounds(pr)
    p = pr.p
    lo = np.full(p, np.inf)
    hi = np.full(p, -np.inf)
    for P in res.polytopes:
        assert set(np.unique(P.signs).tolist()) <= {-1, 1}
        for k in range(p):
            c = np.zeros(p)
            c[k] = 1.0
            for s in (1.0, -1.0):
                r = linprog(s * c, A_ub=P.A, b_ub=P.b, bounds=[(None, None)] * p,
                            method="highs")
                if r.status == 2:
                    continue
                assert r.status == 0
                if s > 0:
                    lo[k] = min(lo[k], r.fun)
                else:
                    hi[k] = max(hi[k], -r.fun)
    np.testing.assert_array_less(res.bounds[:, 0] - 1e-9, lo)  # outer ...
    np.testing.assert_array_less(hi, res.bounds[:, 1] + 1e-9)
    np.testing.assert_allclose(res.bounds[:, 0], lo, atol=1e-6)  # ... and not loose
    np.testing.assert_allclose(res.bounds[:, 1], hi, atol=1e-6)


def test_two_level_lp_intervals_inside_independent_ones():
    data, theta = chapter_eiv_data(N=40, deta=0.05, two_level=False, seed=21)
    pr_i = EIVProblem(**data)
    data, _ = chapter_eiv_data(N=40, deta=0.05, two_level=True, seed=21)
    pr_t = EIVProblem(**data)
    np.testing.assert_array_equal(pr_i.y, pr_t.y)  # same data
    assert pr_t.n_groups == 2 and pr_i.n_groups == 40
    r_i, r_t = lp_bounds(pr_i), lp_bounds(pr_t)
    assert r_t.contains(theta)
    assert np.all(r_t.bounds[:, 0] >= r_i.bounds[:, 0] - 1e-12)
    assert np.all(r_t.bounds[:, 1] <= r_i.bounds[:, 1] + 1e-12)


# ---------------------------------------------------------------------------------------
# check_theta
# ---------------------------------------------------------------------------------------


def test_check_theta_accepts_truth_and_rejects_outside_points():
    data, theta = chapter_eiv_data(N=30, deta=0.05, seed=2)
    pr = EIVProblem(**data)
    chk = check_theta(pr, theta)
    assert chk.feasible
    assert chk.eta.shape == (pr.N,) and chk.dx.shape == (pr.n_groups,)
    assert np.all(np.abs(chk.eta) <= pr.deta)  # the witness is inside the boxes exactly
    assert np.all(np.abs(chk.dx) <= pr.dx_group)
    lp = lp_bounds(pr)
    # a point outside the (outer) LP box cannot be feasible
    far = theta.copy()
    far[0] = lp.bounds[0, 1] + 0.05
    far[-1] = 1.0 * (1 + far[0] + far[1]) - far[2]  # keep the gain equality
    bad = check_theta(pr, far)
    assert not bad.feasible and bad.max_violation > 1e-6
    # the gain equality is enforced
    assert not check_theta(pr, theta + np.array([0, 0, 0, 1e-3])).feasible
    # outside the a priori box
    boxed = pr.with_theta_box(np.column_stack([theta + 0.01, theta + 0.02]))
    assert not check_theta(boxed, theta).feasible
    with pytest.raises(ParameterValidationError):
        check_theta(pr, theta[:3])


# ---------------------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------------------


def _like(pr, **kw):
    d = dict(y=pr.y, x=pr.x, input_bound=pr.input_bound, output_bound=pr.output_bound,
             na=pr.na, nb=pr.nb, steady_state_gain=pr.steady_state_gain)
    d.update(kw)
    return EIVProblem(**d)


def test_shifted_output_is_inconsistent_and_the_equation_is_named():
    data, _ = chapter_eiv_data(N=40, deta=0.05, seed=3)
    pr = EIVProblem(**data)
    y = pr.y.copy()
    y[25:] += 1.0
    with pytest.raises(EmptyFeasibleSetError) as ei:
        lp_bounds(_like(pr, y=y))
    err = ei.value
    assert isinstance(err, ValueError)
    assert err.first_index is not None and 25 <= err.first_index < 40
    assert f"t = {err.first_index}" in str(err)
    # the truncated data set up to (excluding) that equation is still consistent
    t = err.first_index
    lp_bounds(_like(pr, y=y[:t], x=pr.x[:t], input_bound=pr.input_bound[:t],
                    output_bound=pr.output_bound[:t]))


def test_single_outlier_is_located():
    data, _ = chapter_eiv_data(N=40, deta=0.05, seed=4)
    pr = EIVProblem(**data)
    y = pr.y.copy()
    y[20] += 1.5
    with pytest.raises(EmptyFeasibleSetError, match="equation t = ") as ei:
        lp_bounds(_like(pr, y=y))
    # y_20 enters the equations t = 20, 21, 22 only
    assert 20 <= ei.value.first_index <= 22


def test_too_small_noise_bound_is_inconsistent():
    data, _ = chapter_eiv_data(N=40, deta=0.05, seed=5)
    pr = EIVProblem(**data)
    with pytest.raises(EmptyFeasibleSetError) as ei:
        lp_bounds(_like(pr, output_bound=1e-4))
    assert ei.value.first_index is not None
    assert str(ei.value.first_index) in str(ei.value)


def test_box_incompatible_with_gain_is_empty():
    data, _ = chapter_eiv_data(N=20, deta=0.05, seed=5)
    pr = EIVProblem(**data)
    # b1 + b2 = 1 + a1 + a2 >= 1 - 2 - 1 but the box forces b1 + b2 <= -10
    box = np.array([[-2, 2], [-1, 1], [-20, -5], [-20, -5.0]])
    with pytest.raises(EmptyFeasibleSetError, match="gain"):
        lp_bounds(pr.with_theta_box(box))


def test_constant_input_is_unbounded():
    data, _ = chapter_eiv_data(N=40, deta=0.05, seed=6)
    pr = EIVProblem(**data)
    with pytest.raises(UnboundedSetError) as ei:
        lp_bounds(_like(pr, x=np.full(pr.N, 0.5)))
    assert "b1" in str(ei.value) and "theta_box" in str(ei.value)
    assert isinstance(ei.value, ValueError)
    # check_box=False returns the (box-touching) bounds instead of raising
    res = lp_bounds(_like(pr, x=np.full(pr.N, 0.5)), check_box=False)
    assert np.isclose(res.bounds[2, 0], pr.theta_box[2, 0]) or np.isclose(
        res.bounds[2, 1], pr.theta_box[2, 1])


def test_too_few_samples_is_unbounded():
    data, _ = chapter_eiv_data(N=40, deta=0.05, seed=6)
    pr = EIVProblem(**data)
    n = 4  # two equations for three free parameters
    with pytest.raises(UnboundedSetError):
        lp_bounds(_like(pr, y=pr.y[:n], x=pr.x[:n], input_bound=pr.dx[:n],
                            output_bound=pr.deta[:n]))


Y = np.linspace(-1, 1, 12)
X = np.where(np.arange(12) % 3 == 0, 1.0, -1.0)


def _bad(**kw):
    d = dict(y=Y, x=X, input_bound=0.01, output_bound=0.05, na=2, nb=2)
    d.update(kw)
    return d


@pytest.mark.parametrize("kwargs,exc", [
    (_bad(y=np.where(np.arange(12) == 3, np.nan, Y)), DataValidationError),
    (_bad(x=np.where(np.arange(12) == 3, np.inf, X)), DataValidationError),
    (_bad(x=X[:-1]), DataValidationError),
    (_bad(y=np.c_[Y, Y]), DataValidationError),
    (_bad(y=["a"] * 12), DataValidationError),
    (_bad(output_bound=np.full(11, 0.05)), DataValidationError),
    (_bad(output_bound=-0.05), ParameterValidationError),
    (_bad(output_bound=0.0), ParameterValidationError),
    (_bad(input_bound=-0.01), ParameterValidationError),
    (_bad(input_bound=np.nan), DataValidationError),
    (_bad(na=-1), ParameterValidationError),
    (_bad(nb=0), ParameterValidationError),
    (_bad(y=Y[:2], x=X[:2]), DataValidationError),
    (_bad(groups=np.zeros(11, dtype=int)), DataValidationError),
    (_bad(groups=np.zeros(12)), DataValidationError),
    (_bad(groups=-np.ones(12, dtype=int)), DataValidationError),
    (_bad(groups=np.zeros(12, dtype=int)), DataValidationError),  # x differs in a group
    (_bad(theta_box=np.ones((3, 2))), ParameterValidationError),
    (_bad(theta_box=np.array([[1, -1], [0, 1], [0, 1], [0, 1.0]])), ParameterValidationError),
    (_bad(theta_box=np.array([[0, np.inf], [0, 1], [0, 1], [0, 1.0]])),
     ParameterValidationError),
    (_bad(steady_state_gain=0.0), ParameterValidationError),
    (_bad(steady_state_gain=np.nan), ParameterValidationError),
])
def test_bad_problem_construction_raises_typed_errors(kwargs, exc):
    with pytest.raises(exc) as ei:
        EIVProblem(**kwargs)
    assert isinstance(ei.value, HammerboundError) and isinstance(ei.value, ValueError)
    assert str(ei.value)  # a message saying what to change


def test_valid_variants_are_accepted():
    groups = (X > 0).astype(int)
    pr = EIVProblem(Y, X, 0.01, 0.05, 2, 2, groups=groups)
    assert pr.n_groups == 2 and pr.p == 4
    pr = EIVProblem(Y, X, 0.01, 0.05, 0, 1, nk=0)  # FIR with b0
    assert pr.param_names == ["b0", "b1"] and pr.n0 == 1
