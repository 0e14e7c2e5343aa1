"""The tolerance policy inside the exact (McCormick) and moment relaxations, crossing bounds,
and PRBS samples that sit within rounding of a level (docs/tolerances.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.exceptions import DataValidationError, EmptyFeasibleSetError
from hammerbound.relaxations.exact.mccormick import McCormickRelaxation
from hammerbound.relaxations.problem import EIVProblem, equation_scale, outward_problem
from hammerbound.stage1.estimator import InnerSignalBounds
from hammerbound.tolerances import FEASIBILITY_RTOL


def _problem(gain=None, scale=1.0, seed=0, N=40):
    rng = np.random.default_rng(seed)
    x = scale * np.where(rng.random(N) < 0.5, 1.0, -1.0)
    w = lfilter([0.0, 0.5], [1.0, -0.6], x)
    y = w + scale * 0.02 * np.where(rng.random(N) < 0.5, 1.0, -1.0)  # noise at +-bound
    return EIVProblem(y, x, 0.0, scale * 0.02, na=1, nb=1, steady_state_gain=gain)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_mccormick_rows_are_relaxed_outward_by_the_policy(scale):
    pr = _problem(gain=1.25, scale=scale)  # the true gain 0.5 / (1 - 0.6)
    box = np.array([[-0.9, -0.3], [0.2, 0.8]])
    relax = McCormickRelaxation(pr, box)
    _, yt = pr.regressors()
    m = yt.size
    tau = FEASIBILITY_RTOL * equation_scale(pr, np.max(np.abs(box), axis=1))
    rl, ru = np.asarray(relax.lp.rl[:m]), np.asarray(relax.lp.ru[:m])
    assert np.all(rl < -yt) and np.all(ru > -yt)
    np.testing.assert_allclose(ru - rl, 2 * tau, rtol=1e-6)
    # the gain equality (22.8) has exact coefficients: it stays an equality
    assert relax.lp.rl[m] == relax.lp.ru[m] == pr.gain


def test_outward_problem_widens_each_equation_by_its_scale():
    pr = _problem()
    box = np.array([[-0.9, -0.3], [0.2, 0.8]])
    wide = outward_problem(pr, box)
    cur = pr.eta_index()[:, 0]
    tau = FEASIBILITY_RTOL * equation_scale(pr, np.max(np.abs(box), axis=1))
    np.testing.assert_allclose(wide.deta[cur] - pr.deta[cur], tau, rtol=1e-6)
    assert np.all(wide.deta >= pr.deta)
    # samples that are no equation's current sample keep their bound
    rest = np.setdiff1d(np.arange(pr.N), cur)
    np.testing.assert_array_equal(wide.deta[rest], pr.deta[rest])


@pytest.mark.parametrize("method", ["exact", "moment"])
def test_noise_at_bound_truth_inside_exact_and_moment(method):
    pr = _problem(seed=3, N=30)
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method=method)
    est.fit(pr.x, pr.y)
    assert est.contains([-0.6, 0.5])


def test_crossing_bounds_are_reported_empty(monkeypatch):
    import hammerbound.relaxations.lp as lpmod

    orig = lpmod.lp_bounds

    def crossing(*args, **kwargs):
        import dataclasses

        res = orig(*args, **kwargs)
        bounds = res.bounds.copy()  # results are read-only: build a crossed one
        bounds[0] = [bounds[0, 1] + 0.1, bounds[0, 1]]
        return dataclasses.replace(res, bounds=bounds)

    monkeypatch.setattr(lpmod, "lp_bounds", crossing)
    pr = _problem()
    with pytest.raises(EmptyFeasibleSetError, match="cross"):
        hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp").fit(pr.x, pr.y)


def test_prbs_sample_off_its_level_widens_the_radius():
    ib = InnerSignalBounds(1.0, (0.2, 0.3), (-0.3, -0.2), slope_max=0.5)
    u = np.array([1.0 + 4e-10, -1.0, 1.0])
    xc, dx = ib.transform(u)
    np.testing.assert_allclose(xc, [0.25, -0.25, 0.25])
    assert dx[0] == pytest.approx(0.05 + 0.5 * 4e-10, rel=0, abs=1e-17)
    assert dx[1] == dx[2] == pytest.approx(0.05)
    # without a known slope only exact levels are accepted
    with pytest.raises(DataValidationError):
        InnerSignalBounds(1.0, (0.2, 0.3), (-0.3, -0.2)).transform(u)


def test_stage1_inner_bounds_carry_the_largest_slope():
    rng = np.random.default_rng(1)
    amps = np.linspace(0.3, 2.0, 8)
    u = np.concatenate([amps, -amps])
    ml, cl, mr, cr = 0.25, 0.06, 0.26, 0.05
    y = np.where(u > 0, mr * (u - cr), ml * (u + cl)) + rng.uniform(-0.005, 0.005, u.size)
    est = hb.BacklashSetEstimator(0.005).fit(u, y)
    ib = est.inner_signal_bounds(1.0)
    assert ib.slope_max == pytest.approx(max(est.gamma_bounds_[0, 1], est.gamma_bounds_[2, 1]))
