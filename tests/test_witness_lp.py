"""The one fixed-theta witness LP (issue 27.5): the branch-and-bound's screen and the
sampler's membership test are the same :class:`WitnessLP`, and what it accepts is what an
independent LP (our own, scipy's ``linprog`` on the equations written out here) accepts.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.signal import lfilter

from hammerbound.modelset import sampling
from hammerbound.relaxations.exact.points import _Pool
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.problem import EIVProblem, check_theta
from hammerbound.relaxations.witness import WitnessLP, fixed_theta_matrix
from hammerbound.tolerances import FEASIBILITY_RTOL

A_TRUE, B_TRUE = [1.0, -0.7], [0.0, 0.4]


def record(at_bound, seed=0, N=40, d=0.03):
    rng = np.random.default_rng(seed)
    x0 = np.where(rng.random(N) < 0.5, 1.0, -1.0)
    w = lfilter(B_TRUE, A_TRUE, x0)
    e = d * rng.choice([-1.0, 1.0], (2, N)) if at_bound else rng.uniform(-d, d, (2, N))
    return EIVProblem(w + e[1], x0 + e[0], d, d, na=1, nb=1), np.array([-0.7, 0.4])


def own_min_violation(x, y, d, theta):
    """Own LP: min s s.t. |y_t - e_t + a (y_{t-1} - e_{t-1}) - b (x_{t-1} - u_{t-1})| <= s,
    |e|, |u| <= d (na = nb = 1, independent errors); variables e (N), u (N), s."""
    a, b = theta
    N = y.size
    rows, rhs = [], []
    for t in range(1, N):
        row = np.zeros(2 * N + 1)
        row[t], row[t - 1], row[N + t - 1] = -1.0, -a, b  # the error terms of equation t
        r = y[t] + a * y[t - 1] - b * x[t - 1]
        rows += [np.r_[row[:-1], -1.0], np.r_[-row[:-1], -1.0]]
        rhs += [-r, r]
    c = np.zeros(2 * N + 1)
    c[-1] = 1.0
    res = linprog(c, A_ub=np.array(rows), b_ub=np.array(rhs),
                  bounds=[(-d, d)] * (2 * N) + [(0, None)], method="highs")
    return res.fun


@pytest.mark.parametrize("at_bound", [False, True], ids=["uniform", "at_bound"])
def test_witness_lp_agrees_with_own_lp_and_check_theta(at_bound):
    pr, theta_true = record(at_bound)
    box = lp_bounds(pr, check_box=False).bounds
    rng = np.random.default_rng(1)
    thetas = [theta_true] + [rng.uniform(box[:, 0], box[:, 1]) for _ in range(30)]
    lp = WitnessLP(pr)
    accepted = 0
    for th in thetas:
        z, rel = lp.witness(th)
        assert np.all(np.abs(z[: pr.N]) <= pr.deta) and np.all(np.abs(z[pr.N:]) <= pr.dx_group)
        # the relative violation is recomputed from the clipped witness, not the LP value
        r = pr.simulate_noise_free(th)
        from hammerbound.relaxations.problem import equation_scale

        assert rel == pytest.approx(
            np.max(np.abs(fixed_theta_matrix(pr, th) @ z - r) / equation_scale(pr, th)))
        own = own_min_violation(pr.x, pr.y, 0.03, th)
        ok = rel <= FEASIBILITY_RTOL
        if ok:  # what the shared LP accepts, check_theta and our own LP accept
            accepted += 1
            assert check_theta(pr, th, witness=(z[: pr.N], z[pr.N:])).feasible
            assert own <= 1e-8
        elif own > 1e-6:  # clearly infeasible by our own LP: rejected by check_theta too
            assert not check_theta(pr, th).feasible
        assert lp.screens(th) == (lp.violation(th) <= lp.tol_at(th))
    assert accepted >= 1  # the truth at least


def test_branch_and_bound_and_sampler_share_the_witness_lp():
    pr, theta_true = record(False)
    pool = _Pool(pr)
    pool._ensure_screen()
    assert type(pool.screen) is WitnessLP
    ver = sampling._Verifier(pr)
    assert type(ver.lp) is WitnessLP
    assert ver(theta_true) is not None and pool.add(theta_true) is not None
    assert not hasattr(sampling, "_WitnessLP")
