"""The exact method's witnesses lie inside the set (issue 29, item 9).

A witness accepted by ``check_theta`` holds (22.34) to 1e-9 of the equations' terms, which an
independent check reads as error bounds widened by up to ~1e-6 of Delta eta (small noise,
large outputs). ``local.polish`` moves each witness a little into the set; here an
independent LP (written out equation by equation, rows divided by the magnitudes of their
terms, HiGHS tolerances 1e-10) confirms that the witnesses need no widening beyond
rounding: strictly inside where the set has an interior, the point itself (to ~1e-13) where
it is a single point (noise exactly at the bound on every sample of a two-level record).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import make_eiv_problem, make_two_level
from scipy.optimize import linprog

from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.exact.local import POLISH_RADIUS, polish
from hammerbound.relaxations.exact.points import _Point
from hammerbound.relaxations.problem import check_theta

#: what the independent LP may read as widening for a point exactly on the set's edge
#: (its own rounding; the witnesses before polishing needed up to ~1e-6)
LP_ROUNDING = 1e-10


def error_scale(pr, theta) -> float:
    """Smallest ``s`` such that ``theta`` explains the data with ``|eta| <= s deta`` and
    ``|dx| <= s dx`` (our own LP over the errors)."""
    theta = np.asarray(theta, dtype=float)
    a, b, lags = theta[: pr.na], theta[pr.na :], pr.b_lags
    n, k = pr.N, pr.n_groups
    T = np.arange(pr.n0, pr.N)
    rows, cols, vals = [], [], []
    r, scale = np.empty(T.size), np.empty(T.size)
    for row, t in enumerate(T):
        ylag = pr.y[t - np.arange(1, pr.na + 1)]
        xlag = pr.x[t - lags]
        rows += [row] * (1 + pr.na + lags.size)
        cols += [t, *(t - np.arange(1, pr.na + 1)), *(n + pr.groups[t - lags])]
        vals += [-1.0, *(-a), *b]
        r[row] = -(pr.y[t] + a @ ylag - b @ xlag)
        scale[row] = abs(pr.y[t]) + np.abs(a) @ np.abs(ylag) + np.abs(b) @ np.abs(xlag)
    M = sp.csr_matrix((vals, (rows, cols)), shape=(T.size, n + k))
    bound = np.concatenate([pr.deta, pr.dx_group])
    Ms = sp.diags(1 / scale) @ M @ sp.diags(bound)
    nz = n + k
    eye = sp.identity(nz, format="csr")
    ones = sp.csr_matrix(-np.ones((nz, 1)))
    res = linprog(np.r_[np.zeros(nz), 1.0],
                  A_ub=sp.vstack([sp.hstack([eye, ones]), sp.hstack([-eye, ones])]),
                  b_ub=np.zeros(2 * nz), A_eq=sp.hstack([Ms, sp.csr_matrix((T.size, 1))]),
                  b_eq=r / scale, bounds=[(None, None)] * nz + [(0, None)], method="highs",
                  options={"primal_feasibility_tolerance": 1e-10,
                           "dual_feasibility_tolerance": 1e-10})
    assert res.status == 0, res.message
    return float(res.fun)


CASES = {
    "independent, small noise": lambda: make_eiv_problem(N=40, deta=0.005, seed=1,
                                                         at_bound=True),
    "independent": lambda: make_eiv_problem(N=40, deta=0.05, seed=2, at_bound=True),
    "two-level, small noise": lambda: make_two_level(3, N=40, deta=0.005),
    "two-level": lambda: make_two_level(4, N=40, deta=0.05),
}


@pytest.mark.parametrize("name", list(CASES))
def test_exact_witnesses_need_no_widening(name):
    pr, theta = CASES[name]()
    res = exact_bounds(pr, tol=1e-3)
    assert np.all(res.bounds[:, 0] <= theta) and np.all(theta <= res.bounds[:, 1])
    for info in res.infos:
        assert info.witness is not None
        assert error_scale(pr, info.witness) <= 1.0 + LP_ROUNDING, (name, info.param)
        assert check_theta(pr, info.witness, witness=(info.point.eta, info.point.dx)).feasible


def test_polish_moves_an_edge_witness_inside():
    """A point accepted only within the acceptance tolerance (the truth of two-level data
    with the noise exactly at the bound -- the set is that point -- nudged off it) comes
    back to the set, within POLISH_RADIUS of where it was."""
    pr, theta = make_two_level(5, N=40, deta=0.005)
    rng = np.random.default_rng(0)
    g = pr.gain_row()[0]
    edge = None
    for step in (1e-9, 3e-10, 1e-10, 3e-11):
        for _ in range(5):
            d = rng.normal(size=theta.size)
            d -= (g @ d) / (g @ g) * g  # stay on the gain plane
            th = theta + step * d / np.linalg.norm(d)
            if error_scale(pr, th) > 1 + 1e-8 and check_theta(pr, th).feasible:
                edge = th
                break
        if edge is not None:
            break
    assert edge is not None, "no nudged truth is accepted within the tolerance only"
    chk = check_theta(pr, edge)
    (out,) = polish(pr, [_Point(edge, chk.eta, chk.dx)])
    assert error_scale(pr, out.theta) <= 1.0 + LP_ROUNDING
    assert np.all(np.abs(out.theta - edge) <= POLISH_RADIUS * np.maximum(1.0, np.abs(edge)))
    assert check_theta(pr, out.theta, witness=(out.eta, out.dx)).feasible
