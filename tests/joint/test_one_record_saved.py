"""A fitted one-record identifier can be saved and used again, and a reverse-acting plant
is named in the empty verdict (found by a new-user trial: ``pickle.dumps`` of a one-record
fit raised "Can't pickle local object ... sampler"; a plant of negative gain got only the
generic "empty" message)."""

from __future__ import annotations

import io
import pickle
import warnings

import joblib
import numpy as np
import pytest
from oracles import play, random_steps  # the tests' own play operator and input
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.exceptions import EmptyFeasibleSetError, NotIdentifiedWarning

GAMMA = (0.8, 0.15, 0.9, 0.1)


def _record(sign=1.0, N=160, deta=0.02, seed=3):
    rng = np.random.default_rng(seed)
    u = random_steps(N, rng)
    w = lfilter([0.0, 0.5, 0.3], [1.0, -0.7, 0.0], play(u, *GAMMA))
    return u, sign * w + rng.uniform(-deta, deta, N)


def _identifier(**kw):
    return hb.HammersteinBacklashIdentifier(linear=hb.LinearEIVSetEstimator(
        na=1, nb=2, nk=1, output_bound=0.02, method="lp", total_time_limit=120, **kw))


@pytest.fixture(scope="module")
def fitted():
    u, y = _record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotIdentifiedWarning)
        return _identifier().fit(u, y), u, y


@pytest.mark.parametrize("how", ["pickle", "joblib"])
def test_a_fitted_one_record_identifier_is_saved_and_used_again(fitted, how):
    f, u, y = fitted
    if how == "pickle":
        again = pickle.loads(pickle.dumps(f))
    else:
        buf = io.BytesIO()
        joblib.dump(f, buf)
        buf.seek(0)
        again = joblib.load(buf)
    assert again.summary() == f.summary()
    np.testing.assert_array_equal(again.bounds_, f.bounds_)
    np.testing.assert_array_equal(again.predict(u), f.predict(u))
    # the samplers of the model set work after loading, and give the same draws
    a, b = again.linear_.sample(5, random_state=0), f.linear_.sample(5, random_state=0)
    np.testing.assert_array_equal(a.theta, b.theta)
    np.testing.assert_array_equal(a.gamma, b.gamma)


def test_one_record_samples_carry_the_model_sets_fields_and_check_out(fitted):
    """New-user trial 20: the model set's docs read max_violation, tol and eta, which a
    one-record fit's samples lacked. Each row is checked here with the tests' own play
    operator and recursion: its inner signal, errors within the bound, equations met."""
    f, u, y = fitted
    gamma_s, theta_s = f.sample(4, random_state=1)
    assert gamma_s is theta_s and len(theta_s) == 4
    assert theta_s.param_names == ("a1", "b1", "b2")
    assert np.all(theta_s.max_violation <= theta_s.tol) and theta_s.dx.shape == (4, 0)
    for th, g, z0, x, eta in zip(theta_s.theta, theta_s.gamma, theta_s.z0, theta_s.x,
                                 theta_s.eta, strict=True):
        np.testing.assert_allclose(x, play(u, *g, x0=z0), rtol=0, atol=1e-12)
        assert np.max(np.abs(eta)) <= 0.02 * (1 + 1e-9)
        w = y - eta  # (y_t - eta_t) + a1 (y_{t-1} - eta_{t-1}) = b1 x_{t-1} + b2 x_{t-2}
        res = w[2:] + th[0] * w[1:-1] - th[1] * x[1:-1] - th[2] * x[:-2]
        assert np.max(np.abs(res)) <= 1e-6
    np.testing.assert_allclose(theta_s.gain_residual,
                               np.abs(theta_s.theta[:, 1:].sum(1) - 1 - theta_s.theta[:, 0]),
                               rtol=0, atol=1e-12)


def test_a_reverse_acting_plant_is_named_in_the_one_record_empty_verdict():
    u, y = _record(sign=-1.0)
    with pytest.raises(EmptyFeasibleSetError) as err:
        _identifier().fit(u, y)
    msg = str(err.value)
    assert "least-squares gain is negative" in msg and "fit the negated output (-y)" in msg


def test_the_same_plant_of_positive_gain_gets_no_sign_hint():
    """The hint comes from the data, not with every empty verdict: the positive plant at
    a bound below its noise is empty without it."""
    u, y = _record(N=120)
    y = y + 0.2 * np.sign(np.sin(np.arange(u.size)))  # +-0.2 errors, bound 0.02
    with pytest.raises(EmptyFeasibleSetError) as err:
        _identifier().fit(u, y)
    assert "negative" not in str(err.value)


def test_a_reverse_acting_plant_is_named_in_the_stage_one_verdict():
    amps = np.array([0.5, 1.0, 1.5, 2.0])
    u = np.concatenate([amps, -amps])
    y = -np.concatenate([0.9 * (amps - 0.1), 0.8 * (-amps + 0.15)])  # own lines, negated
    with pytest.raises(EmptyFeasibleSetError) as err:
        hb.BacklashSetEstimator(output_bound=0.01).fit(u.reshape(-1, 1), y)
    assert "steady-state slope (output against input) is negative" in str(err.value)
    hb.BacklashSetEstimator(output_bound=0.01).fit(u.reshape(-1, 1), -y)  # fits


def test_settled_steady_states_are_an_assumption_of_the_two_stage_fit():
    """Unsettled steady-state points gave intervals without the truth in the trial (a
    transient of 1.7 % left at the end of each hold): settling is said in the summary."""
    ex = hb.chapter_example(output_bound=0.05, N=100)
    ident = hb.HammersteinBacklashIdentifier(
        backlash=hb.BacklashSetEstimator(output_bound=0.05),
        linear=hb.LinearEIVSetEstimator(na=2, nb=2, output_bound=0.05, method="lp")).fit(ex.prbs.u, ex.prbs.y,
                                                           steady_state=ex.steady)
    assert "settled: a transient left counts against" in ident.summary()
    assert any("settled: a transient left counts against the steady-state output bound" in a
               for a in ident.assumptions_)
    assert "samples are settled" in ident.backlash_.summary()


def test_no_central_model_names_the_time_limit_when_it_stopped_the_fit():
    """New-user trial 22: after a fit stopped by its time limit, predict() said that "the
    record does not bound every parameter" and advised another record."""
    from hammerbound.exceptions import UnboundedSetError

    u, y = _record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        f = hb.HammersteinBacklashIdentifier(linear=hb.LinearEIVSetEstimator(
            na=1, nb=2, nk=1, output_bound=0.02, method="exact",
            total_time_limit=0.5)).fit(u, y)
    assert f.one_record_.result.details.stopped_by_time
    if f.system_ is not None:
        pytest.skip("this machine bounded every parameter within the limit")
    with pytest.raises(UnboundedSetError, match="the time limit stopped the search before "
                                                "every parameter was bounded"):
        f.predict(u)


def test_a_held_out_segment_is_scored_from_its_best_matched_backlash_state(fitted):
    """New-user trial 22: a held-out fold was simulated with the backlash at 0, so its
    score measured where the fold's backlash state happened to be (R^2 0.988 against
    0.9997 from its true state). The state is now matched to the segment, as the linear
    block's is by its measured outputs."""
    from sklearn.metrics import r2_score

    from hammerbound.timeseries import simulate_from_measured

    f, _, _ = fitted
    rng = np.random.default_rng(12)
    u = np.r_[np.full(30, 0.05), random_steps(90, rng)]  # a hold first: the state lingers
    x = play(u, *GAMMA, x0=GAMMA[0] * (u[0] + GAMMA[1]))  # the top of its first band
    y = lfilter([0.0, 0.5, 0.3], [1.0, -0.7, 0.0], x) + rng.uniform(-0.02, 0.02, u.size)
    data = hb.IOData(u, y)
    n0 = f.linear_._n0()
    s = f.system_
    from_zero = r2_score(y[n0:], simulate_from_measured(s.A, s.B, s.inner(u), y, n0)[n0:])
    score = f.score(data)
    assert score > 0.999 and score > from_zero + 0.005  # 0.99995 against 0.987
    assert score == pytest.approx(r2_score(y[n0:], f.predict(data)[n0:]), abs=1e-12)


def test_the_matched_backlash_start_is_the_least_squares_one_not_a_local_one():
    """Recheck 52b: the error is piecewise quadratic in the start, and a bounded search
    over the band stopped in a local minimum (R^2 0.896 where 0.942 was there)."""
    from hammerbound.systems.models import Backlash, HammersteinSystem
    from hammerbound.timeseries import simulate_from_measured, simulate_matched

    a = np.array([1.0, -1.2, 0.72])
    b = np.array([0.0, 0.3, 0.22]) * a.sum() / 0.52
    rng = np.random.default_rng(210)
    u = np.concatenate([np.zeros(1), np.repeat(rng.uniform(-1.5, 1.5, 6),
                                               rng.integers(2, 6))])[:20]
    y = lfilter(b, a, play(u, 1.0, 0.8, 1.0, 0.8, x0=rng.uniform(-0.8, 0.8)))
    y = y + rng.normal(0, 0.05, u.size)
    bl = Backlash(1.0, 0.8, 1.0, 0.8)
    w = simulate_matched(HammersteinSystem(bl, (a, b)), u, y, 2)
    grid = np.linspace(-0.8, 0.8, 2001)  # the first band at u = 0
    best = min(np.sum((y[2:] - simulate_from_measured(a, b, bl.simulate(u, x0=g), y, 2)[2:])
                      ** 2) for g in grid)
    assert np.sum((y[2:] - w[2:]) ** 2) <= best + 1e-9


def test_no_central_model_blames_an_input_that_never_reverses_even_at_the_limit():
    """Recheck 52b: a never-reversing input cannot bound the dead band whatever the time,
    but a fit stopped by its limit was told to raise total_time_limit."""
    from hammerbound.exceptions import UnboundedSetError

    u = np.linspace(-1.0, 1.0, 80)  # never reverses
    y = lfilter([0.0, 0.5, 0.3], [1.0, -0.7, 0.0], play(u, *GAMMA))
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        f = hb.HammersteinBacklashIdentifier(linear=hb.LinearEIVSetEstimator(
            na=1, nb=2, nk=1, output_bound=0.02, method="exact",
            total_time_limit=0.5)).fit(u, y)
    said = [str(w.message) for w in seen if issubclass(w.category, NotIdentifiedWarning)
            and "never reverses" in str(w.message)]
    # the warning too, where the time limit had been named as the cause
    assert said and said[0].startswith("the record does not bound")
    assert "Give more time" not in said[0]
    if f.system_ is not None:
        pytest.skip("every parameter bounded")  # not expected: c cannot be bounded
    with pytest.raises(UnboundedSetError, match="the record does not bound every parameter"):
        f.predict(u)
