"""LinearEIVSetEstimator: soundness, conventions, errors."""

from __future__ import annotations

import pickle
import re

import control
import numpy as np
import pytest
from oracles import chapter_eiv_data
from scipy.signal import lfilter
from sklearn.base import clone

from hammerbound import (
    DataValidationError,
    EmptyFeasibleSetError,
    LinearEIVSetEstimator,
    ParameterValidationError,
    SolverNotAvailableError,
    SolverOptionError,
    UnboundedSetError,
    check_theta,
)


def _data(N=60, deta=0.05, dx=0.003, two_level=False, seed=0):
    data, theta = chapter_eiv_data(N=N, deta=deta, dx=dx, two_level=two_level, seed=seed)
    return data["x"], data["y"], theta, data["groups"]


@pytest.mark.parametrize("method", ["lp", "moment", "exact"])
def test_true_theta_inside_and_witnesses_inside(method):
    x, y, theta, _ = _data(N=50, deta=0.05)
    est = LinearEIVSetEstimator(output_bound=0.05, method=method).fit(x, y, input_bound=0.003)
    assert est.bounds_.shape == (4, 2)
    assert est.contains(theta)
    assert est.param_names_ == ("a1", "a2", "b1", "b2")
    assert len(est.bound_info_) == 8
    assert all(info.certified for info in est.bound_info_)
    # a verified-feasible point (exact witnesses) must lie inside every method's intervals
    ex = LinearEIVSetEstimator(output_bound=0.05, method="exact").fit(x, y, input_bound=0.003)
    for info in ex.bound_info_:
        assert check_theta(est.problem_, info.witness).feasible
        assert est.contains(info.witness, tol=1e-9)


def test_methods_nest_lp_moment_exact():
    x, y, _, _ = _data(N=60, deta=0.02, seed=3)
    res = {m: LinearEIVSetEstimator(output_bound=0.02, method=m).fit(x, y, input_bound=0.003)
           for m in ("lp", "moment", "exact")}
    inner = res["exact"].result_.inner  # verified-feasible extreme values
    for m in ("lp", "moment"):
        assert np.all(res[m].bounds_[:, 0] <= inner[:, 0] + 1e-12)
        assert np.all(res[m].bounds_[:, 1] >= inner[:, 1] - 1e-12)
    w = {m: r.bounds_[:, 1] - r.bounds_[:, 0] for m, r in res.items()}
    assert np.all(w["lp"] >= w["moment"] - 1e-9)
    assert np.all(w["moment"] >= w["exact"] - 1e-6)


def test_two_level_groups_tighter_and_sound():
    x, y, theta, groups = _data(N=60, deta=0.05, two_level=True, seed=1)
    indep = LinearEIVSetEstimator(output_bound=0.05, method="exact").fit(x, y, input_bound=0.003)
    two = LinearEIVSetEstimator(output_bound=0.05, method="exact").fit(
        x, y, input_bound=0.003, input_groups=groups)
    assert two.contains(theta) and indep.contains(theta)
    assert np.all(two.bounds_[:, 0] >= indep.bounds_[:, 0] - 1e-6)
    assert np.all(two.bounds_[:, 1] <= indep.bounds_[:, 1] + 1e-6)
    assert np.sum(two.radius_) < 0.8 * np.sum(indep.radius_)


def test_predict_score_transfer_function():
    x, y, theta, _ = _data(N=80, deta=0.01)
    est = LinearEIVSetEstimator(output_bound=0.01, method="exact").fit(x, y, input_bound=0.003)
    tf = est.to_transfer_function()
    assert isinstance(tf, control.TransferFunction) and tf.dt == 1.0
    _, yt = control.forced_response(tf, U=x)
    np.testing.assert_allclose(yt, est.predict(x), atol=1e-10)
    np.testing.assert_allclose(est.predict(x), lfilter(est.B_, est.A_, x))
    assert est.score(x, y) > 0.99
    # the centre of the orthotope need not satisfy (22.8) exactly, but nearly does
    assert abs(est.B_.sum() / est.A_.sum() - 1.0) < 0.01


def test_one_step_envelope_contains_noise_free_output():
    data, theta = chapter_eiv_data(N=80, deta=0.05, dx=0.003, seed=2)
    xc, y = data["x"], data["y"]
    est = LinearEIVSetEstimator(output_bound=0.05, method="lp").fit(xc, y, input_bound=0.003)
    lo, hi = est.one_step_envelope(xc, y, input_bound=0.003)
    # the noise-free output with the true theta: regenerate as in chapter_eiv_data
    rng = np.random.default_rng(2)
    N = 80
    u = np.where(rng.random(N) < 0.5, 2.0, -2.0)
    g = (2.15 - 1.09) / (1 - 0.76 + 0.82)
    x = np.where(u > 0, 0.26 * (2 - 0.0489), 0.25 * (-2 + 0.0628)) * g
    w = lfilter(np.array([0, 2.15, -1.09]) / g, [1, -0.76, 0.82], x)
    ok = ~np.isnan(lo)
    assert ok.sum() == N - 2
    assert np.all((w[ok] >= lo[ok]) & (w[ok] <= hi[ok]))
    assert np.all(hi[ok] - lo[ok] < 1.0)


def test_sklearn_conventions():
    x, y, _, _ = _data(N=40, deta=0.05)
    est = LinearEIVSetEstimator(na=2, nb=2, output_bound=0.05, method="lp")
    c = clone(est).set_params(method="exact", tol=1e-3)
    assert est.method == "lp" and c.method == "exact"
    est.fit(x.reshape(-1, 1), y, input_bound=0.003)
    est2 = pickle.loads(pickle.dumps(est))
    np.testing.assert_array_equal(est2.bounds_, est.bounds_)
    np.testing.assert_array_equal(est2.predict(x), est.predict(x))
    assert est.n_features_in_ == 1


def test_per_sample_bounds_and_deterministic():
    x, y, theta, _ = _data(N=50, deta=0.05)
    deta = np.full(50, 0.05)
    dx = np.full(50, 0.003)
    a = LinearEIVSetEstimator(output_bound=deta, method="lp").fit(x, y, input_bound=dx)
    b = LinearEIVSetEstimator(output_bound=0.05, method="lp").fit(x, y, input_bound=0.003)
    np.testing.assert_array_equal(a.bounds_, b.bounds_)
    assert a.contains(theta)


def test_stability_box_is_a_reported_prior():
    # with large noise the LP bound on a2 is set by the stability box |a2| <= 1 (A1)
    x, y, theta, _ = _data(N=60, deta=0.3, seed=0)
    est = LinearEIVSetEstimator(output_bound=0.3, method="lp").fit(x, y, input_bound=0.003)
    assert est.contains(theta)
    assert all(s.startswith("a") for s in est.box_limited_)


BAD = [
    (dict(), dict(X=[1.0, np.nan] * 10, y=[0.0] * 20), DataValidationError, "NaN"),
    (dict(), dict(X=[1.0] * 20, y=[0.0] * 19), DataValidationError, "same number"),
    (dict(), dict(X=np.ones((20, 2)), y=[0.0] * 20), DataValidationError, "1-D"),
    (dict(), dict(X=[], y=[]), DataValidationError, "empty"),
    (dict(), dict(X=["a"] * 20, y=[0.0] * 20), DataValidationError, "real numbers"),
    (dict(), dict(X=[1, -1, 1], y=[0.0, 0.1, 0.2]), DataValidationError, "samples"),
    (dict(output_bound=0.0), {}, ParameterValidationError, "> 0"),
    (dict(output_bound=-1.0), {}, ParameterValidationError, "> 0"),
    (dict(output_bound=np.ones(3)), {}, DataValidationError, "one value per sample"),
    (dict(), dict(input_bound=-0.1), ParameterValidationError, ">= 0"),
    (dict(na=-1), {}, ParameterValidationError, "na"),
    (dict(nb=1.5), {}, ParameterValidationError, "nb"),
    (dict(nb=0), {}, ParameterValidationError, "nb >= 1 or nk=0"),
    (dict(output_bound=None), {}, ParameterValidationError, "output_bound is not set"),
    (dict(method="simplex"), {}, ParameterValidationError, "method must be one of"),
    (dict(relaxation_order=0), {}, ParameterValidationError, "relaxation_order"),
    (dict(steady_state_gain=0.0), {}, ParameterValidationError, "steady_state_gain"),
    (dict(method="moment", solver="gurobi"), {}, SolverNotAvailableError, "clarabel"),
    (dict(method="moment", solver_options="fast"), {}, SolverOptionError, "dict"),
    (dict(method="moment", solver_options={"no_such_option": 1}), {}, SolverOptionError,
     "no_such_option"),
]


@pytest.mark.parametrize("params, data, err, match", BAD)
def test_bad_input(params, data, err, match):
    x, y, _, _ = _data(N=20)
    kw = dict(X=x, y=y, input_bound=0.003)
    kw.update(data)
    with pytest.raises(err, match=match):
        LinearEIVSetEstimator(**{"method": "lp", "output_bound": 0.05, **params}).fit(**kw)


def test_inconsistent_data_names_the_equation():
    x, y, _, _ = _data(N=40, deta=0.01)
    y = y.copy()
    y[25] += 1.0  # an outlier no model explains
    with pytest.raises(EmptyFeasibleSetError) as ei:
        LinearEIVSetEstimator(output_bound=0.01, method="lp").fit(x, y, input_bound=0.003)
    assert ei.value.first_index is not None and 25 <= ei.value.first_index <= 27
    assert "t =" in str(ei.value)


def test_unexciting_input_is_unbounded():
    rng = np.random.default_rng(0)
    x = np.ones(40)  # constant input: b1, b2 are not separately identifiable
    y = np.ones(40) + rng.uniform(-0.01, 0.01, 40)
    with pytest.raises(UnboundedSetError, match="b"):
        LinearEIVSetEstimator(output_bound=0.01, method="lp").fit(x, y, input_bound=0.0)


def test_exact_progress_bar_and_limits():
    x, y, theta, _ = _data(N=40, deta=0.05)
    est = LinearEIVSetEstimator(output_bound=0.05, method="exact", progress=True, max_nodes=2)
    est.fit(x, y, input_bound=0.003)
    assert est.contains(theta)
    limited = [i for i in est.bound_info_ if i.status == "limit"]
    for info in limited:  # a stopped search still reports a valid outer bound and says so
        assert "limit" in info.message and info.gap is not None and info.gap >= 0


def _progress_gaps(x, y, scale, capsys):
    """The gaps of the exact method's final progress lines (stderr is not a terminal) on
    the input in units ``scale`` times smaller."""
    capsys.readouterr()
    LinearEIVSetEstimator(output_bound=0.05, method="exact", progress=True, max_nodes=2,
                          n_jobs=1).fit(x / scale, y, input_bound=0.003 / scale)
    out = capsys.readouterr()
    assert out.out == ""  # stdout belongs to the program
    # the last line of each end: "finished" or "stopped by ..." (max_nodes=2)
    lines = [ln for ln in out.err.splitlines()
             if ln.startswith("exact ") and ("finished" in ln or "stopped by" in ln)]
    return {ln.split(":")[0]: float(re.search(r"(?:, gap|box width) ([^,) ]+)", ln).group(1))
            for ln in lines}


def test_exact_progress_shows_the_gap_in_the_units_of_the_data(capsys):
    """The input in units 1024 times smaller (b_j 1024 times larger; a power of two, so the
    search runs the same path in its own units): the b_j gaps shown are 1024 times larger,
    the a_i gaps the same (before, the search's units were shown: the same gaps)."""
    x, y, _, _ = _data(N=40, deta=0.05)
    ref = _progress_gaps(x, y, 1.0, capsys)
    big = _progress_gaps(x, y, 1024.0, capsys)
    assert len(ref) == 8 and ref.keys() == big.keys()
    for label, g in ref.items():
        want = g * 1024.0 if " b" in label else g
        assert big[label] == pytest.approx(want, rel=2e-3), label  # 3 digits shown


def test_the_large_relaxation_warning_points_at_the_caller(monkeypatch):
    """The moment method's size warning names the user's line, not the library's (it
    pointed inside stage2/fitting.py after fit was split)."""
    from hammerbound.relaxations.moment import size

    monkeypatch.setattr(size, "MOMENT_WARN_WORK", 0.0)
    x, y, _, _ = _data(N=20, deta=0.05)
    with pytest.warns(RuntimeWarning) as caught:
        LinearEIVSetEstimator(output_bound=0.05, method="moment").fit(x, y, input_bound=0.003)
    assert [w.filename for w in caught if "relaxation" in str(w.message)][:1] == [__file__]
