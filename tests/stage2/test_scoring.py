"""Scores and scikit-learn's scorers on IOData (new-user trial: ``scoring="r2"`` crashed
cross-validation on IOData, and the relation of ``score`` to ``predict`` was undocumented)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter
from sklearn.metrics import r2_score
from sklearn.model_selection import TimeSeriesSplit, cross_val_score

import hammerbound as hb
from hammerbound.exceptions import DataValidationError


def _data(N=120, seed=2):
    """Own simulation: y = 0.5 q^-1 / (1 - 0.8 q^-1) x, input errors at +-0.02 and
    output errors at +-0.05 (random signs)."""
    rng = np.random.default_rng(seed)
    x0 = np.repeat(rng.uniform(-1, 1, N // 6), 6)
    w = lfilter([0.0, 0.5], [1.0, -0.8], x0)
    return hb.IOData(x0 + 0.02 * rng.choice([-1.0, 1.0], N),
                     w + 0.05 * rng.choice([-1.0, 1.0], N))


def _est():
    return hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.05, method="lp")


def test_score_is_r2_of_predict_after_the_first_measured_outputs():
    data = _data()
    est = _est().fit(data, input_bound=0.02)
    n0 = 1
    assert est.score(data) == pytest.approx(r2_score(data.y[n0:], est.predict(data)[n0:]),
                                            rel=1e-12)


@pytest.mark.parametrize("scoring", ["r2", "neg_mean_squared_error"])
def test_sklearn_scorers_with_iodata_and_its_output(scoring):
    data = _data()
    cv = TimeSeriesSplit(n_splits=3)
    scores = cross_val_score(_est(), data, data.y, cv=cv, scoring=scoring,
                             params={"input_bound": 0.02}, error_score="raise")
    assert np.all(np.isfinite(scores))
    if scoring == "r2":
        own = cross_val_score(_est(), data, cv=cv, params={"input_bound": 0.02},
                              error_score="raise")
        # the same simulation; the scorer also counts the fold's first measured sample
        assert np.allclose(scores, own, atol=0.01)


def test_a_different_y_with_iodata_is_refused():
    data = _data()
    with pytest.raises(DataValidationError, match=r"or with y = X\.y"):
        _est().fit(data, data.y + 1.0, input_bound=0.02)
    with pytest.raises(DataValidationError, match=r"or with y = X\.y"):
        _est().fit(data, data.y[:-1], input_bound=0.02)
