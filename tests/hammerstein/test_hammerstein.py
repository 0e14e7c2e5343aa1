"""HammersteinBacklashIdentifier: the two stages composed, inside scikit-learn utilities."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV, TimeSeriesSplit

from hammerbound import (
    BacklashSetEstimator,
    DataValidationError,
    HammersteinBacklashIdentifier,
    LinearEIVSetEstimator,
    ParameterValidationError,
    ResultOneViolationError,
    chapter_example,
    prbs_experiment,
)
from hammerbound.systems.experiments import CHAPTER_NOISE_LEVELS


def _ident(deta, method="lp", inner="independent", **kw):
    return HammersteinBacklashIdentifier(
        BacklashSetEstimator(deta),
        LinearEIVSetEstimator(output_bound=deta, method=method, **kw),
        inner_signal=inner,
    )


@pytest.mark.parametrize("N", [100, 300])
@pytest.mark.parametrize("deta", CHAPTER_NOISE_LEVELS)
def test_chapter_example_all_noise_levels_lp(deta, N):
    ex = chapter_example(deta, N=N)
    ident = _ident(deta).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    assert ident.contains(ex.gamma_true, ex.theta_true)
    assert ident.bounds_.shape == (8, 2)
    assert ident.u_star_ == 1.0
    # the inner signal truly lies in the stage-1 band used by stage 2 (22.31)
    assert np.all(np.abs(ex.prbs.x - ident.xc_) <= ident.dx_ + 1e-12)


@pytest.mark.parametrize("deta", [0.005, 0.05])
def test_chapter_example_exact_two_level_inside_independent(deta):
    ex = chapter_example(deta, N=100, random_state=1)
    ind = _ident(deta, "exact").fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    two = _ident(deta, "exact", "two-level").fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    for r in (ind, two):
        assert r.contains(ex.gamma_true, ex.theta_true)
    assert np.all(two.theta_bounds_[:, 0] >= ind.theta_bounds_[:, 0] - 1e-6)
    assert np.all(two.theta_bounds_[:, 1] <= ind.theta_bounds_[:, 1] + 1e-6)
    assert np.all(two.linear_.radius_ < ind.linear_.radius_)


@pytest.mark.parametrize("deta", [0.02, 0.3])
def test_moment_order1_on_chapter_example(deta):
    ex = chapter_example(deta, N=100, random_state=2)
    ident = _ident(deta, "moment").fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    lp = _ident(deta, "lp").fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    assert ident.contains(ex.gamma_true, ex.theta_true)
    assert all(i.certified for i in ident.linear_.bound_info_)
    # the LP intervals contain the moment intervals on the same data
    assert np.all(lp.theta_bounds_[:, 0] <= ident.theta_bounds_[:, 0] + 1e-12)
    assert np.all(lp.theta_bounds_[:, 1] >= ident.theta_bounds_[:, 1] - 1e-12)


def test_nested_params_clone_pickle():
    ident = _ident(0.05)
    params = ident.get_params()
    assert params["linear__output_bound"] == 0.05
    assert params["backlash__method"] == "polygon"
    ident.set_params(linear__relaxation_order=2, linear__method="moment")
    assert ident.linear.relaxation_order == 2
    c = clone(ident)
    assert c.get_params()["linear__relaxation_order"] == 2
    ex = chapter_example(0.05, N=60)
    fitted = _ident(0.05).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    again = pickle.loads(pickle.dumps(fitted))
    np.testing.assert_array_equal(again.bounds_, fitted.bounds_)
    np.testing.assert_allclose(again.predict(ex.prbs.u), fitted.predict(ex.prbs.u))
    # the user's sub-estimators are not modified by fit
    assert not hasattr(ident.linear, "bounds_")


def test_predict_score_envelope():
    ex = chapter_example(0.02, N=100)
    ident = _ident(0.02, "exact", "two-level").fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    yhat = ident.predict(ex.prbs.u)
    assert yhat.shape == ex.prbs.y.shape
    assert np.max(np.abs(yhat - ex.prbs.w)) < 0.1
    assert ident.score(ex.prbs.u, ex.prbs.y) > 0.99
    lo, hi = ident.output_envelope(ex.prbs.u, ex.prbs.y)
    ok = ~np.isnan(lo)
    assert np.all((ex.prbs.w[ok] >= lo[ok]) & (ex.prbs.w[ok] <= hi[ok]))


def test_grid_search_over_orders_time_ordered():
    ex = chapter_example(0.02, N=120)
    base = HammersteinBacklashIdentifier(
        BacklashSetEstimator(0.02),
        LinearEIVSetEstimator(output_bound=0.02, method="lp", theta_box=None))
    grid = GridSearchCV(base, {"linear__na": [2, 3], "linear__nb": [2]},
                        cv=TimeSeriesSplit(n_splits=2), error_score="raise")
    grid.fit(ex.prbs.u, ex.prbs.y, steady_state={"u": ex.steady.u, "y": ex.steady.y})
    assert grid.best_params_["linear__nb"] == 2
    assert np.all(np.isfinite(grid.cv_results_["mean_test_score"]))
    best = grid.best_estimator_
    th = ex.theta_true
    if grid.best_params_["linear__na"] == 3:  # the true system is in the larger class, a3 = 0
        th = np.r_[th[:2], 0.0, th[2:]]
    assert best.contains(ex.gamma_true, th)


def test_prbs_level_past_crossing_refused():
    ex = chapter_example(0.05, N=60)
    data = prbs_experiment(ex.system, 60, 2.8, 0.05, random_state=0)  # near the crossing
    with pytest.raises(ResultOneViolationError, match="cross"):
        _ident(0.05).fit(data.u, data.y, steady_state=ex.steady)


def test_prbs_level_in_dead_zone_refused():
    ex = chapter_example(0.05, N=60)
    u = np.where(np.arange(60) % 3 == 0, 0.03, -0.03)
    with pytest.raises(ResultOneViolationError, match="dead zone"):
        _ident(0.05).fit(u, np.zeros(60), steady_state=ex.steady)


@pytest.mark.parametrize(
    "kwargs, err, match",
    [
        (dict(steady_state=None), DataValidationError, "steady-state"),
        (dict(steady_state={"u": [1.0]}), DataValidationError, "'u' and 'y'"),
        (dict(steady_state=5), DataValidationError, "pair"),
        (dict(X=np.r_[np.ones(30), -np.ones(29), 0.5]), DataValidationError, "two values"),
        (dict(y=np.zeros(10)), DataValidationError, "same number"),
    ],
)
def test_bad_input(kwargs, err, match):
    ex = chapter_example(0.05, N=60)
    call = dict(X=ex.prbs.u, y=ex.prbs.y, steady_state=ex.steady)
    call.update(kwargs)
    # the two-stage procedure: without steady-state data (or with a PRBS that is not
    # two-level) the default procedure="auto" identifies from the one record instead
    with pytest.raises(err, match=match):
        _ident(0.05).set_params(procedure="two-stage").fit(call.pop("X"), call.pop("y"), **call)


def test_bad_inner_signal_and_components():
    ex = chapter_example(0.05, N=60)
    with pytest.raises(ParameterValidationError, match="inner_signal"):
        HammersteinBacklashIdentifier(inner_signal="three-level").fit(
            ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    with pytest.raises(ParameterValidationError, match="BacklashSetEstimator"):
        HammersteinBacklashIdentifier(backlash=LinearEIVSetEstimator()).fit(
            ex.prbs.u, ex.prbs.y, steady_state=ex.steady)


def test_output_envelope_takes_iodata():
    """Found by a new-user trial: output_envelope(IOData) raised an error about scikit-learn
    transformers; fit, predict and score take an IOData."""
    import hammerbound as hb

    ex = hb.chapter_example(0.05, N=120, random_state=1)
    ident = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05),
        hb.LinearEIVSetEstimator(output_bound=0.05, method="lp"))
    ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    data = hb.IOData(ex.prbs.u, ex.prbs.y)
    a = ident.output_envelope(ex.prbs.u, ex.prbs.y)
    b = ident.output_envelope(data)
    assert np.array_equal(a.lower, b.lower, equal_nan=True)
    assert np.array_equal(a.upper, b.upper, equal_nan=True)
    c = ident.linear_.one_step_envelope(hb.IOData(ident.linear_.problem_.x,
                                                  ident.linear_.problem_.y))
    assert np.isfinite(c.lower).any()
    with pytest.raises(DataValidationError, match="output_envelope requires y"):
        ident.output_envelope(ex.prbs.u)
