"""The one fixed-theta witness LP (issue 27.5): the branch-and-bound's screen and the
sampler's membership test are the same :class:`WitnessLP`, and what it accepts is what an
independent LP (``oracles.error_scale``: scipy's ``linprog`` on the equations) accepts.
"""

from __future__ import annotations

import numpy as np
import pytest
from oracles import eiv_data, error_scale
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
        own = error_scale(eiv_data(pr.y, pr.x, 0.03, 0.03, 1, 1), th)
        ok = rel <= FEASIBILITY_RTOL
        if ok:  # what the shared LP accepts, check_theta and our own LP accept
            accepted += 1
            assert check_theta(pr, th, witness=(z[: pr.N], z[pr.N:])).feasible
            assert own <= 1 + 1e-6
        elif own > 1 + 1e-5:  # clearly infeasible by our own LP: rejected by check_theta too
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
