"""scikit-learn semantics for time series (issue 14, item 5) and the IOData object (item 2)."""

from __future__ import annotations

import warnings

import control
import numpy as np
import pytest
from scipy.signal import lfilter
from sklearn.model_selection import GridSearchCV, KFold, TimeSeriesSplit, cross_val_score

import hammerbound as hb
from hammerbound import DataValidationError, IOData, ParameterValidationError
from hammerbound.timeseries import simulate_from_measured


def _first_order(N=80, seed=0, deta=0.02):
    rng = np.random.default_rng(seed)
    x = np.where(rng.random(N) < 0.5, 1.0, -1.0)
    y = lfilter([0, 0.5], [1, -0.7], x) + deta * np.where(rng.random(N) < 0.5, 1.0, -1.0)
    return x, y


# ---------------------------------------------------------------- IOData
def test_iodata_basics_and_contiguous_cuts():
    d = IOData(np.arange(6.0), np.ones(6), dt=0.5, input_name="V", input_unit="volt", t0=2.0)
    assert repr(d) == "IOData(N=6, dt=0.5, input='V' [volt], output='y')"
    np.testing.assert_allclose(d.time, 2.0 + 0.5 * np.arange(6))
    seg = d[2:5]
    assert seg.N == 3 and seg.dt == 0.5 and seg.is_contiguous()
    np.testing.assert_allclose(seg.time, [3.0, 3.5, 4.0])
    assert seg.sample_index.tolist() == [2, 3, 4]
    with pytest.raises(DataValidationError, match="TimeSeriesSplit"):
        d[[0, 1, 3]]
    with pytest.raises(DataValidationError, match="same number"):
        IOData(np.ones(3), np.ones(4))
    with pytest.raises(ParameterValidationError, match="dt"):
        IOData(np.ones(3), np.ones(3), dt=0.0)
    assert IOData(np.ones(3), np.ones(3)).tf_dt is True


def test_iodata_from_csv_time_column(tmp_path):
    p = tmp_path / "r.csv"
    p.write_text("t,volt,speed\n1.0,1,2\n1.2,3,4\n1.4,5,6\n")
    d = IOData.from_csv(p, u="volt", y="speed")
    assert d.dt == pytest.approx(0.2) and d.t0 == 1.0
    assert (d.input_name, d.output_name) == ("volt", "speed")
    assert d.u.tolist() == [1, 3, 5]
    assert IOData.from_csv(p, u="volt", y="speed", t=None, dt=None).dt is None
    with pytest.raises(DataValidationError, match="step 0.2 but dt=0.1"):
        IOData.from_csv(p, u="volt", y="speed", dt=0.1)


def test_dt_and_names_flow_into_transfer_functions():
    x, y = _first_order()
    data = IOData(x, y, dt=0.1, input_name="force", output_name="position")
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp").fit(data)
    tf = est.to_transfer_function()
    assert tf.dt == 0.1
    assert tf.input_labels == ["force"] and tf.output_labels == ["position"]
    assert est.to_transfer_function(dt=0.5).dt == 0.5
    plain = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp").fit(x, y)
    assert plain.to_transfer_function().dt is True          # python-control: not given
    # a HammersteinSystem built from a TF keeps its dt
    G = control.tf([0, 0.5], [1, -0.7], 0.1)
    s = hb.HammersteinSystem(hb.Backlash(1, 0.1, 1, 0.1), G)
    assert s.dt == 0.1 and s.to_transfer_function().dt == 0.1
    assert hb.HammersteinSystem(hb.Backlash(1, 0.1, 1, 0.1), ([1, -0.7], [0, 0.5])) \
        .to_transfer_function().dt is True


def test_identifier_dt_contains_system_and_tables():
    ex = hb.chapter_example(0.05, N=100, random_state=0)
    ident = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="lp"))
    ident.fit(IOData(ex.prbs.u, ex.prbs.y, dt=0.01), steady_state=ex.steady)
    assert ident.system_.to_transfer_function().dt == 0.01
    truth = hb.HammersteinSystem(hb.Backlash(*ex.gamma_true),
                                 control.tf(*ex.system.to_transfer_function().num[0] +
                                            ex.system.to_transfer_function().den[0], 0.01))
    assert ident.contains(truth)
    assert ident.contains(ex.gamma_true, ex.theta_true)
    frame = ident.to_frame()
    names = list(frame["parameter"])
    assert names == ["ml", "cl", "mr", "cr", "a1", "a2", "b1", "b2"]
    np.testing.assert_allclose(frame["lower"], ident.bounds_[:, 0])
    np.testing.assert_allclose(frame["half_width"], ident.radius_)
    text = ident.summary()
    assert "dt = 0.01" in text and all(f"\n{n} " in text for n in names)


def test_to_frame_fields_and_feasible_set_repr():
    x, y = _first_order()
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp").fit(x, y)
    fr = est.to_frame()
    try:
        import pandas  # noqa: F401
    except ImportError:
        assert isinstance(fr, np.ndarray)
        assert fr.dtype.names == ("parameter", "lower", "centre", "upper", "half_width",
                                  "status")
    assert list(fr["parameter"]) == ["a1", "b1"]
    np.testing.assert_allclose(fr["centre"], est.center_)
    r = repr(est.feasible_set_)
    assert r.startswith("FeasibleSet(a1 in [") and len(r) < 200 and "\n" not in r


def test_contains_transfer_function_and_structure_check():
    x, y = _first_order()
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="exact")
    est.fit(IOData(x, y, dt=0.1))
    assert est.contains(control.tf([0.5], [1, -0.7], 0.1))        # = 0.5 z^-1/(1-0.7z^-1)
    assert not est.contains(control.tf([0.6], [1, -0.7], 0.1))
    with pytest.raises(ParameterValidationError, match="dt=0.2"):
        est.contains(control.tf([0.5], [1, -0.7], 0.2))
    with pytest.raises(ParameterValidationError, match="outside this structure"):
        est.contains(control.tf([0.5, 0.1], [1, -0.7, 0.1], 0.1))


# ---------------------------------------------------------------- held-out segments
def test_simulation_from_measured_initial_conditions_own_loop():
    rng = np.random.default_rng(4)
    A, B = np.array([1.0, -0.76, 0.82]), np.array([0.0, 2.15, -1.09]) / 1.06
    x = rng.uniform(-1, 1, 50)
    y = rng.normal(size=50)
    w = simulate_from_measured(A, B, x, y, 2)
    own = y.copy()
    for t in range(2, 50):
        own[t] = -A[1] * own[t - 1] - A[2] * own[t - 2] + B[1] * x[t - 1] + B[2] * x[t - 2]
    np.testing.assert_allclose(w, own, atol=1e-12)


def test_score_of_a_held_out_segment_starts_from_measured_outputs():
    x, y0 = _first_order(N=200, deta=0.0)
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=1e-3, method="lp").fit(
        x[:100], y0[:100])
    # the centre is close to the truth: on a mid-record noise-free segment the simulated
    # score is ~1, while a simulation from rest would pay the initial transient
    seg = slice(150, 160)
    assert est.score(x[seg], y0[seg]) > 0.999
    from sklearn.metrics import r2_score
    assert r2_score(y0[seg], est.predict(x[seg])) < 0.99
    np.testing.assert_allclose(est.predict(IOData(x[seg], y0[seg]))[0], y0[150])


# ---------------------------------------------------------------- scikit-learn CV
@pytest.fixture(scope="module")
def chapter():
    return hb.chapter_example(0.02, N=100, random_state=0)


def _ident(deta=0.02):
    return hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(deta), hb.LinearEIVSetEstimator(output_bound=deta, method="lp"))


def test_kfold_raises_a_clear_error(chapter):
    data = IOData(chapter.prbs.u, chapter.prbs.y)
    with pytest.raises(DataValidationError, match="TimeSeriesSplit"):
        cross_val_score(_ident(), data, cv=KFold(5), params={"steady_state": chapter.steady})
    # a non-contiguous IOData reaching fit directly (built by hand) is refused too
    bad = IOData(data.u[:50], data.y[:50], sample_index=np.r_[0:25, 30:55])
    with pytest.raises(DataValidationError, match="not consecutive"):
        _ident().fit(bad, steady_state=chapter.steady)


def test_grid_search_time_series_split_picks_true_order(chapter):
    grid = GridSearchCV(_ident(), {"linear__na": [1, 2, 3]}, cv=TimeSeriesSplit(n_splits=3),
                        error_score=-np.inf)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # na = 1 is falsified on every fold (empty set)
        grid.fit(IOData(chapter.prbs.u, chapter.prbs.y), steady_state=chapter.steady)
    assert grid.best_params_ == {"linear__na": 2}
    scores = grid.cv_results_["mean_test_score"]
    assert scores[0] == -np.inf and np.all(np.isfinite(scores[1:]))


def test_sample_aligned_bounds_survive_cv(chapter):
    N = chapter.prbs.u.size
    deta = np.full(N, 0.02)
    deta[::7] = 0.03                      # genuinely per-sample
    cv = TimeSeriesSplit(n_splits=3)
    scores = cross_val_score(_ident(), IOData(chapter.prbs.u, chapter.prbs.y), cv=cv,
                             params={"steady_state": chapter.steady, "output_bound": deta},
                             error_score="raise")
    assert np.all(scores > 0.9)
    # the stage-2 estimator alone with per-sample input and output bounds
    x, y = _first_order(N=90)
    dx = np.full(90, 1e-3)
    est = hb.LinearEIVSetEstimator(na=1, nb=1, method="lp")
    s = cross_val_score(est, x, y, cv=cv, params={"input_bound": dx,
                                                  "output_bound": np.full(90, 0.02)},
                        error_score="raise")
    assert np.all(s > 0.9)
    # a per-sample output_bound in the constructor cannot be split: the error says why
    bad = hb.LinearEIVSetEstimator(na=1, nb=1, method="lp", output_bound=np.full(90, 0.02))
    with pytest.raises(DataValidationError, match="output_bound"):
        cross_val_score(bad, x, y, cv=cv, error_score="raise")


def test_groups_renamed_input_groups():
    x, y = _first_order()
    lab = (x < 0).astype(int)
    a = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp").fit(
        x, y, input_bound=0.01, input_groups=lab)
    with pytest.warns(FutureWarning, match="input_groups"):
        b = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp").fit(
            x, y, input_bound=0.01, groups=lab)
    np.testing.assert_array_equal(a.bounds_, b.bounds_)


def test_iodata_from_frame_and_backlash_tables():
    frame = {"time": np.array([0.0, 0.5, 1.0, 1.5]), "in": np.arange(4.0), "out": np.ones(4)}
    d = IOData.from_frame(frame, u="in", y="out", t="time", input_unit="V")
    assert d.dt == 0.5 and d.input_name == "in" and d.input_unit == "V"
    with pytest.raises(DataValidationError, match="not found"):
        IOData.from_frame(frame, u="volt", y="out")
    ex = hb.chapter_example(0.05, N=40, random_state=0)
    bl = hb.BacklashSetEstimator(0.05).fit(ex.steady.u, ex.steady.y)
    fr = bl.to_frame()
    assert list(fr["parameter"]) == ["ml", "cl", "mr", "cr"]
    np.testing.assert_allclose(fr["upper"], bl.gamma_bounds_[:, 1])
    lines = bl.summary().splitlines()
    assert lines[1].startswith("parameter") and lines[2].startswith("ml ")
    assert lines[6] == "assumptions:"
    assert lines[7].startswith("  - output error bound |eta| <= 0.05 (the data allow no bound")


def test_plain_array_kfold_splice_message_names_the_cause():
    """Plain arrays carry no sample index: the splice is found as an inconsistency, and the
    message says that a cross-validation cut is the likely cause."""
    from hammerbound.exceptions import EmptyFeasibleSetError

    ex = hb.chapter_example(0.05, N=200, random_state=0)
    keep = np.r_[0:40, 80:200]  # what KFold(5)'s second training set looks like
    est = hb.LinearEIVSetEstimator(output_bound=0.05, method="lp", steady_state_gain=1.0)
    with pytest.raises(EmptyFeasibleSetError, match="TimeSeriesSplit"):
        est.fit(ex.prbs.x[keep], ex.prbs.y[keep], input_bound=1e-9)
    # the same record, not cut, is consistent
    est.fit(ex.prbs.x, ex.prbs.y, input_bound=1e-9)


def test_scaler_in_a_pipeline_with_iodata_says_what_to_pass():
    """Issue 29 item 5: a scikit-learn transformer cannot scale an IOData (the bounds would
    keep their old units); the typed error says how to scale, and that recipe is right."""
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    x, y = _first_order(N=80, seed=3)
    data = IOData(x, y, dt=0.1)
    est = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp")
    with pytest.raises(DataValidationError, match="StandardScaler") as err:
        make_pipeline(StandardScaler(), est).fit(data)
    assert "output bound by sy" in str(err.value)
    with pytest.raises(DataValidationError, match="not a feature matrix"):
        np.asarray(data)
    # the recipe of the message: scaled data with scaled bounds give the scaled set
    su, sy = 2.0, 10.0
    plain = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp").fit(
        data, input_bound=0.01)
    scaled = hb.LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02 / sy, method="lp").fit(
        IOData(x / su, y / sy, dt=0.1), input_bound=0.01 / su)
    assert plain.contains([-0.7, 0.5]) and scaled.contains([-0.7, 0.5 * su / sy])
    np.testing.assert_allclose(scaled.bounds_[0], plain.bounds_[0], atol=1e-6)
    np.testing.assert_allclose(scaled.bounds_[1], plain.bounds_[1] * su / sy, atol=1e-6)
