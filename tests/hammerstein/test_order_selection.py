"""Order selection never picks a falsified order (issue 29, item 8).

The records are simulated here (scipy's zero-order-hold discretisation and lfilter), with
errors on input and output uniform inside or exactly at +-bound. Cross-validation alone
(GridSearchCV with the LP method) picked na=2, nb=1 on a second-order plant, an order the
whole record falsifies; OrderSelectionCV discards every order certified inconsistent on
the whole record, then takes the most parsimonious of the rest.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from oracles import error_scale, two_level_data
from scipy.signal import cont2discrete, lfilter

import hammerbound as hb
from hammerbound import EmptyFeasibleSetError, IOData, ParameterValidationError
from hammerbound.relaxations import EIVProblem, consistency

GRID = {"na": [1, 2, 3], "nb": [1, 2]}
# continuous plants of the issue, zero-order hold at dt = 0.01
PLANTS = {1: ([2.0], [0.1, 1.0]), 2: ([400.0], [1.0, 12.0, 400.0])}
TRUE_ORDER = {1: {"na": 1, "nb": 1}, 2: {"na": 2, "nb": 2}}


def record(order, seed, noise, N=150, hold=6, bound=0.02):
    """Input levels held ``hold`` samples through the ZOH plant; input and output errors
    uniform in +-bound or exactly +-bound. Returns (u, y, theta_true)."""
    num, den = PLANTS[order]
    bd, ad, _ = cont2discrete((num, den), 0.01, method="zoh")
    b = np.ravel(bd)
    rng = np.random.default_rng(seed)
    u0 = np.repeat(rng.uniform(-1, 1, N // hold + 1), hold)[:N]
    w = lfilter(b, ad, u0)

    def err():
        return bound * (rng.choice([-1.0, 1.0], N) if noise == "at_bound"
                        else rng.uniform(-1.0, 1.0, N))

    theta = np.concatenate([ad[1:], b[1:order + 1]])  # b[0] = 0 after the hold
    return u0 + err(), w + err(), theta


def select(u, y=None, **kw):
    est = hb.LinearEIVSetEstimator(output_bound=0.02, method="lp")
    return hb.OrderSelectionCV(est, GRID, **kw).fit(u, y, input_bound=0.02)


@pytest.mark.parametrize("noise", ["uniform", "at_bound"])
@pytest.mark.parametrize("order", [1, 2])
def test_picks_the_true_order_and_never_a_falsified_one(order, noise):
    u, y, theta = record(order, seed=3, noise=noise)
    sel = select(u, y)
    assert sel.best_params_ == TRUE_ORDER[order]
    res = sel.cv_results_
    k = sel.best_index_
    assert res["consistency"][k] == "consistent" and res["rank_selection"][k] == 1
    # the selected model is the whole-record fit and holds the true system
    assert sel.best_estimator_.contains(theta)
    assert sel.best_estimator_.n_samples_ == u.size
    # the true order is never called empty, and no empty order is cross-validated
    for params, status, mean in zip(res["params"], res["consistency"],
                                    res["mean_test_score"], strict=True):
        if params == TRUE_ORDER[order]:
            assert status == "consistent"
        if status == "empty":
            assert np.isnan(mean)
    # the most parsimonious rule: nothing with fewer parameters survived
    fewer = res["n_parameters"] < res["n_parameters"][k]
    assert set(res["consistency"][fewer]) <= {"empty"}
    assert "<- selected" in sel.summary().splitlines()[k + 1]


@pytest.mark.deep
@pytest.mark.parametrize("noise", ["uniform", "at_bound"])
@pytest.mark.parametrize("order", [1, 2])
def test_true_order_over_seeds(order, noise):
    """Six records per case (GridSearchCV with the LP picked a larger order on 7 of these
    24): the selected order is the true one and contains the true system."""
    for seed in range(6):
        u, y, theta = record(order, seed, noise)
        sel = select(u, y)
        assert sel.best_params_ == TRUE_ORDER[order], (seed, sel.summary())
        assert sel.best_estimator_.contains(theta)


def test_issue_record_lp_cannot_falsify_but_the_whole_record_does():
    """The issue's second-order record (seed 42): na=2, nb=1 passes the LP on the whole
    record, so cross-validation may rank it first; the exact machinery certifies it empty."""
    N, hold = 150, 6
    bd, ad, _ = cont2discrete(PLANTS[2], 0.01, method="zoh")
    rng = np.random.default_rng(42)
    u0 = np.repeat(rng.uniform(-1, 1, N // hold + 1), hold)[:N]
    y0 = lfilter(np.ravel(bd), ad, u0)
    u = u0 + rng.uniform(-0.02, 0.02, N)
    y = y0 + rng.uniform(-0.02, 0.02, N)
    lp21 = hb.LinearEIVSetEstimator(2, 1, output_bound=0.02, method="lp").fit(
        u, y, input_bound=0.02)                       # no error: the LP cannot falsify it
    assert consistency(lp21.problem_).status == "empty"
    sel = select(u, y)
    res = sel.cv_results_
    k21 = [p == {"na": 2, "nb": 1} for p in res["params"]].index(True)
    assert res["consistency"][k21] == "empty" and res["certified_by"][k21] != "fit"
    assert sel.best_params_ == {"na": 2, "nb": 2}
    # the same with an IOData and rule="score": still never the falsified order
    sel = select(IOData(u, y, dt=0.01), rule="score")
    assert sel.best_params_ != {"na": 2, "nb": 1}
    assert sel.cv_results_["consistency"][sel.best_index_] == "consistent"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_consistency_of_a_single_point_set_and_of_a_wrong_order(seed):
    """Noise exactly at +-bound on every sample: the true order's set is one point, which
    must be found (never "empty"); its witness passes an independent LP."""
    data, theta = two_level_data(seed)
    pr = EIVProblem(**data)
    assert error_scale(pr, theta) <= 1 + 1e-7          # the truth explains the data
    dec = consistency(pr, time_limit=60)
    assert dec.status == "consistent" and dec.by == "witness"
    assert error_scale(pr, dec.witness) <= 1 + 1e-6
    # one pole fewer cannot explain the chapter's second-order block
    wrong = EIVProblem(pr.y, pr.x, pr.dx, pr.deta, 1, 2, gain=1.0, groups=pr.groups)
    assert consistency(wrong, time_limit=60).status == "empty"


def test_identifier_grid_over_the_linear_order():
    ex = hb.chapter_example(0.02, N=100, random_state=0)
    ident = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.02), hb.LinearEIVSetEstimator(output_bound=0.02, method="lp"))
    sel = hb.OrderSelectionCV(ident, {"linear__na": [1, 2, 3]})
    sel.fit(IOData(ex.prbs.u, ex.prbs.y), steady_state={"u": ex.steady.u, "y": ex.steady.y})
    assert sel.best_params_ == {"linear__na": 2}
    assert list(sel.cv_results_["consistency"]) == ["empty", "consistent", "consistent"]
    assert sel.best_estimator_.contains(ex.gamma_true, ex.theta_true)
    assert np.isfinite(sel.score(IOData(ex.prbs.u, ex.prbs.y)))


def test_no_consistent_order_names_every_candidate():
    u, y, _ = record(2, seed=0, noise="uniform")
    est = hb.LinearEIVSetEstimator(output_bound=1e-4, method="lp")   # far below the truth
    with pytest.raises(EmptyFeasibleSetError, match="na=1 nb=1: empty") as err:
        hb.OrderSelectionCV(est, GRID).fit(u, y, input_bound=1e-4)
    assert "na=3 nb=2" in str(err.value) and "output_bound" in str(err.value)


def test_undecided_orders_are_kept_after_certified_ones(monkeypatch):
    """Selection logic: an undecided order is not discarded (it is not certified
    inconsistent), ranks after a certified-consistent one of the same size, and a
    selected undecided order warns."""
    import hammerbound.model_selection as ms

    real = ms.consistency

    class Undecided:
        status, by = "undecided", "limit"

    monkeypatch.setattr(ms, "consistency", lambda pr, time_limit: Undecided() if pr.na == 1
                        else real(pr, time_limit=time_limit))
    u, y, _ = record(1, seed=3, noise="uniform")
    with pytest.warns(hb.SearchLimitWarning, match="neither certified consistent"):
        sel = select(u, y)
    assert sel.best_params_ == {"na": 1, "nb": 1}
    assert sel.cv_results_["consistency"][sel.best_index_] == "undecided"


def test_parameters_are_checked():
    u, y, _ = record(1, seed=0, noise="uniform")
    est = hb.LinearEIVSetEstimator(output_bound=0.02, method="lp")
    with pytest.raises(ParameterValidationError, match="rule"):
        hb.OrderSelectionCV(est, GRID, rule="best").fit(u, y)
    with pytest.raises(ParameterValidationError, match="time_limit"):
        hb.OrderSelectionCV(est, GRID, time_limit=0).fit(u, y)
    from sklearn.linear_model import LinearRegression

    with pytest.raises(ParameterValidationError, match="linear=LinearEIVSetEstimator"):
        hb.OrderSelectionCV(hb.HammersteinBacklashIdentifier(), {"linear__na": [1]}).fit(u, y)
    with pytest.raises(ParameterValidationError, match="LinearEIVSetEstimator"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            hb.OrderSelectionCV(LinearRegression(), {"fit_intercept": [True]}).fit(
                u.reshape(-1, 1), y)


@pytest.mark.deep  # 11 s (lp) and 17 s (exact): one-record fits of every fold
@pytest.mark.parametrize("method", ["lp", "exact"])
def test_a_one_record_identifier_is_decided_by_its_verified_points(method):
    """New-user trial 22: the stage-2 consistency test was run on a one-record fit's joint
    problem and crashed (AttributeError). Its ends' verified points certify consistency
    (method 'exact'); the relaxation's bounds alone leave it undecided, said so."""
    from oracles import play, random_steps
    from sklearn.model_selection import TimeSeriesSplit

    rng = np.random.default_rng(3)
    u = random_steps(60, rng)
    y = lfilter([0.0, 0.5], [1.0, -0.5], play(u, 1.0, 0.2, 1.0, 0.2))
    y = y + rng.uniform(-0.02, 0.02, u.size)
    ident = hb.HammersteinBacklashIdentifier(linear=hb.LinearEIVSetEstimator(
        na=1, nb=1, output_bound=0.02, method=method, total_time_limit=10),
        procedure="one-record")
    sel = hb.OrderSelectionCV(ident, {"linear__nb": [1]}, cv=TimeSeriesSplit(2),
                              time_limit=5)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        sel.fit(u, y)
    status = sel.cv_results_["consistency"][0]
    if method == "exact":
        assert status == "consistent"
    else:
        assert status == "undecided"
        assert any("method='exact' certifies it by its ends' points" in str(w.message)
                   for w in seen)
