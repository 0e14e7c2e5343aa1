"""One name per concept (issue 27.3), no default for the bound a guarantee rests on (29.6)
and the guards that refuse at once (29.4).

The old names keep working for one release: each warns (FutureWarning naming the new name
and the removal version) and gives exactly what the new name gives. Data are simulated
here with scipy's ``lfilter`` and the tests' own play operator (``oracles.play``).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from oracles import play
from scipy.signal import lfilter
from sklearn.base import clone

import hammerbound as hb
from hammerbound.exceptions import DataValidationError, ParameterValidationError
from hammerbound.relaxations.problem import EIVProblem

A, B = [1.0, -0.6, 0.2], [0.0, 0.5, 0.1]  # a stable second-order block, gain 1.0


def _record(n=60, bound=0.05, seed=0):
    """PRBS through B/A with output noise exactly at +-bound (random signs)."""
    rng = np.random.default_rng(seed)
    x = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    y = lfilter(B, A, x) + bound * rng.choice([-1.0, 1.0], n)
    return x, y


def _steady(bound=0.02, seed=1):
    """Steady-state points of a backlash (own play operator), noise at +-bound."""
    rng = np.random.default_rng(seed)
    amps = np.linspace(0.5, 3.0, 12)
    u = np.concatenate([amps, -amps])
    # at steady state the play operator sits on the line the last move pushed it to
    x = np.array([play([v], 0.8, 0.1, 0.84, 0.12)[0] for v in u])
    return u, x + bound * rng.choice([-1.0, 1.0], u.size)


def _renamed(record, new):
    """The FutureWarnings of a call: exactly one, naming ``new`` and 0.3.0."""
    msgs = [str(w.message) for w in record if issubclass(w.category, FutureWarning)]
    assert msgs and all(new in m and "0.3.0" in m for m in msgs), msgs


# ---------------------------------------------------------------------- deprecations
def test_stage2_noise_bound_is_output_bound_with_a_warning():
    x, y = _record()
    new = hb.LinearEIVSetEstimator(2, 2, output_bound=0.05, method="lp").fit(x, y)
    old = hb.LinearEIVSetEstimator(2, 2, noise_bound=0.05, method="lp")
    with pytest.warns(FutureWarning) as rec:
        old.fit(x, y)
    _renamed(rec, "output_bound")
    np.testing.assert_array_equal(old.bounds_, new.bounds_)
    assert new.contains(np.r_[A[1:], B[1:]])
    np.testing.assert_array_equal(new.output_bound_, np.full(x.size, 0.05))


def test_giving_both_names_is_refused():
    x, y = _record()
    with pytest.raises(ParameterValidationError, match="pass only output_bound"), \
            pytest.warns(FutureWarning):
        hb.LinearEIVSetEstimator(output_bound=0.05, noise_bound=0.05, method="lp").fit(x, y)
    u, ys = _steady()
    with pytest.raises(ParameterValidationError, match="pass only output_bound"), \
            pytest.warns(FutureWarning):
        hb.BacklashSetEstimator(0.02, noise_bound=0.02).fit(u, ys)


def test_b0_is_nk_0_with_a_warning():
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, 50)
    y = lfilter([0.4, 0.3], [1.0, -0.5], x) + 0.01 * rng.choice([-1.0, 1.0], 50)
    new = hb.LinearEIVSetEstimator(1, 1, nk=0, output_bound=0.01, method="lp").fit(x, y)
    old = hb.LinearEIVSetEstimator(1, 1, b0=True, output_bound=0.01, method="lp")
    with pytest.warns(FutureWarning) as rec:
        old.fit(x, y)
    _renamed(rec, "nk=0")
    assert old.param_names_ == new.param_names_ == ("a1", "b0", "b1")
    np.testing.assert_array_equal(old.bounds_, new.bounds_)
    assert new.contains([-0.5, 0.4, 0.3])


def test_stage1_noise_bound_is_output_bound_with_a_warning():
    u, y = _steady()
    new = hb.BacklashSetEstimator(output_bound=0.02).fit(u, y)
    with pytest.warns(FutureWarning) as rec:
        old = hb.BacklashSetEstimator(noise_bound=0.02).fit(u, y)
    _renamed(rec, "output_bound")
    np.testing.assert_array_equal(old.gamma_bounds_, new.gamma_bounds_)
    g = np.array([0.8, 0.1, 0.84, 0.12])
    assert np.all((new.gamma_bounds_[:, 0] <= g) & (g <= new.gamma_bounds_[:, 1]))


def test_eiv_problem_old_field_names():
    x, y = _record(30)
    new = EIVProblem(y, x, input_bound=0.01, output_bound=0.05, na=2, nb=2,
                     steady_state_gain=1.0)
    with pytest.warns(FutureWarning) as rec:
        old = EIVProblem(y, x, dx=0.01, deta=0.05, na=2, nb=2, gain=1.0)
    assert len(rec) == 3
    for w, name in zip(rec, ("input_bound", "output_bound", "steady_state_gain"), strict=True):
        assert name in str(w.message) and "0.3.0" in str(w.message)
    for f in ("input_bound", "output_bound", "groups", "theta_box"):
        np.testing.assert_array_equal(getattr(old, f), getattr(new, f))
    assert old.steady_state_gain == new.steady_state_gain == new.gain == 1.0
    # the chapter notation stays readable (the relaxations use it)
    np.testing.assert_array_equal(new.deta, new.output_bound)
    np.testing.assert_array_equal(new.dx, new.input_bound)
    with pytest.raises(ParameterValidationError, match="only output_bound"), \
            pytest.warns(FutureWarning):
        EIVProblem(y, x, 0.0, 0.05, 2, 2, deta=0.05)
    with pytest.warns(FutureWarning, match="nk=0"):
        assert EIVProblem(y, x, 0.0, 0.05, 1, 1, b0=True).param_names == ["a1", "b0", "b1"]


def test_eiv_problem_has_no_default_gain_constraint_and_needs_both_bounds():
    x, y = _record(30)
    assert EIVProblem(y, x, 0.0, 0.05, 2, 2).gain_row() is None
    with pytest.raises(ParameterValidationError, match="output_bound"):
        EIVProblem(y, x, input_bound=0.0, na=2, nb=2)


def test_experiments_and_their_data():
    with pytest.warns(FutureWarning) as rec:
        old = hb.chapter_example(noise_bound=0.1, N=40, random_state=3)
    _renamed(rec, "output_bound")
    new = hb.chapter_example(output_bound=0.1, N=40, random_state=3)
    np.testing.assert_array_equal(old.prbs.y, new.prbs.y)
    assert new.output_bound == 0.1 and np.all(new.steady.output_bound == 0.1)
    for obj in (new, new.steady, new.prbs):
        with pytest.warns(FutureWarning, match="output_bound"):
            np.testing.assert_array_equal(obj.noise_bound, obj.output_bound)
    sysm = new.system
    with pytest.warns(FutureWarning, match="output_bound"):
        a = hb.prbs_experiment(sysm, 20, 2.0, noise_bound=0.1, random_state=0)
    b = hb.prbs_experiment(sysm, 20, 2.0, output_bound=0.1, random_state=0)
    np.testing.assert_array_equal(a.y, b.y)
    with pytest.raises(ParameterValidationError, match="output_bound"):
        hb.square_wave_experiment(sysm, [1.0, 2.0])


def test_diagnose_and_locate_old_keyword():
    from hammerbound.discrepancy import diagnose, locate

    rng = np.random.default_rng(5)
    u = np.repeat(rng.uniform(-1, 1, 20), 5)
    y = lfilter([0.0, 0.5], [1.0, -0.5], u) + 0.01 * rng.choice([-1.0, 1.0], u.size)
    import control

    G = control.tf([0.5], [1.0, -0.5], True)
    new = diagnose(G, u, y, output_bound=0.01, candidates=["offset"])
    with pytest.warns(FutureWarning) as rec:
        old = diagnose(G, u, y, noise_bound=0.01, candidates=["offset"])
    _renamed(rec, "output_bound")
    assert old.output_bound == new.output_bound == 0.01
    assert old.consistent_before and new.consistent_before
    with pytest.warns(FutureWarning, match="DiagnosisReport.output_bound"):
        assert new.noise_bound == 0.01
    assert "output_bound" in new.to_dict()
    with pytest.warns(FutureWarning, match="output_bound"):
        dis = locate(G, u, y, noise_bound=0.01)
    assert dis.gap == locate(G, u, y, output_bound=0.01).gap


def test_two_backlash_classes_have_two_names():
    from hammerbound.discrepancy import effects

    assert effects.REGISTRY["backlash"].__class__.__name__ == "SymmetricBacklash"
    with pytest.warns(FutureWarning, match="SymmetricBacklash"):
        old = effects.Backlash
    assert old is effects.REGISTRY["backlash"].__class__
    assert old is not hb.Backlash


def test_plot_backlash_old_keyword():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from hammerbound.plotting import plot_backlash

    u, y = _steady()
    bl = hb.BacklashSetEstimator(0.02).fit(u, y)
    with pytest.warns(FutureWarning, match="output_bound"):
        ax = plot_backlash(bl, u, y, noise_bound=0.02)
    plt.close(ax.figure)


# ---------------------------------------------------------------------- no default bound
def test_no_output_bound_no_fit():
    x, y = _record()
    est = hb.LinearEIVSetEstimator(method="lp")
    assert clone(est).output_bound is None  # constructible, as scikit-learn needs
    with pytest.raises(ParameterValidationError, match="rest on the bound") as ei:
        est.fit(x, y)
    assert "LinearEIVSetEstimator(output_bound=" in str(ei.value)
    assert not hasattr(est, "bounds_")
    # the per-fit bound is enough
    assert est.fit(x, y, output_bound=0.05).contains(np.r_[A[1:], B[1:]])
    u, ys = _steady()
    with pytest.raises(ParameterValidationError, match="BacklashSetEstimator\\(output_bound="):
        hb.BacklashSetEstimator().fit(u, ys)


def test_identifier_refuses_missing_bounds_and_wrong_components_before_any_work():
    ex = hb.chapter_example(0.05, N=40)
    calls = []

    class Spy(hb.BacklashSetEstimator):
        def fit(self, X, y):
            calls.append(1)
            return super().fit(X, y)

    cases = [
        (dict(), "stage-1 estimator has no output_bound"),
        (dict(backlash=Spy()), "stage-1 estimator has no output_bound"),
        (dict(backlash=Spy(0.05)), "stage-2 estimator has no output_bound"),
        (dict(backlash="polygon", linear=hb.LinearEIVSetEstimator(output_bound=0.05)),
         "got the string 'polygon'"),
        (dict(backlash=Spy(0.05), linear=hb.LinearEIVSetEstimator),
         "got the class LinearEIVSetEstimator itself"),
        (dict(backlash=hb.BacklashSetEstimator, linear=hb.LinearEIVSetEstimator()),
         "got the class BacklashSetEstimator itself"),
    ]
    for kw, match in cases:
        with pytest.raises(ParameterValidationError, match=match) as ei:
            hb.HammersteinBacklashIdentifier(**kw).fit(ex.prbs.u, ex.prbs.y,
                                                       steady_state=ex.steady)
        assert not isinstance(ei.value, TypeError)  # not scikit-learn's untyped error
    assert not calls  # refused before stage 1 ran
    ident = hb.HammersteinBacklashIdentifier(Spy(0.05), hb.LinearEIVSetEstimator(method="lp"))
    ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady, output_bound=0.05)
    assert calls and ident.contains(ex.gamma_true, ex.theta_true)


# ---------------------------------------------------------------------- order guard
def _no_lp(monkeypatch):
    import hammerbound.relaxations.lp as lp

    def forbidden(*a, **k):
        raise AssertionError("an LP was built although the orders are refused")

    monkeypatch.setattr(lp, "lp_bounds", forbidden)


@pytest.mark.parametrize("method", ["lp", "moment", "exact"])
def test_orders_beyond_the_lp_orthants_are_refused_before_any_lp(monkeypatch, method):
    _no_lp(monkeypatch)
    x, y = _record(60)
    est = hb.LinearEIVSetEstimator(na=40, nb=40, output_bound=0.05, method=method)
    with pytest.raises(ParameterValidationError, match="2\\^80") as ei:
        est.fit(x, y)
    assert "orders up to na = nb = 6" in str(ei.value)


def test_short_record_is_refused_and_the_suggested_order_works(monkeypatch):
    from hammerbound.stage2.orders import check_orders, largest_order

    x, y = _record(8)
    with monkeypatch.context() as m:
        _no_lp(m)
        with pytest.raises(DataValidationError, match="orders up to na = nb = 2") as ei:
            hb.LinearEIVSetEstimator(3, 3, output_bound=0.05, method="lp").fit(x, y)
    assert "N >= 9" in str(ei.value)
    k = largest_order(1, 8)
    check_orders(k, k, 1, 8)
    with pytest.raises(DataValidationError):
        check_orders(k + 1, k + 1, 1, 8)
    est = hb.LinearEIVSetEstimator(k, k, output_bound=0.05, method="lp").fit(x, y)
    assert est.contains(np.r_[A[1:], B[1:]])


def test_no_warning_from_the_new_names():
    x, y = _record()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hb.LinearEIVSetEstimator(output_bound=0.05, nk=1, method="lp").fit(x, y)
        EIVProblem(y, x, 0.0, 0.05, 2, 2, steady_state_gain=None, nk=1)
