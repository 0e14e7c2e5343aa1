"""Plain EIV problems on the user's own data (issue 14): gain default, input delay nk,
errors naming the assumptions, the example record the package writes, and the third-party
LRIC data set (read from ../shared/data/lric/, skipped when absent)."""

from __future__ import annotations

import numpy as np
import pytest
from oracles import eiv_data, explains
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound import EmptyFeasibleSetError, LinearEIVSetEstimator, ParameterValidationError

# the exact answer on the LRIC record (exact method, tol 1e-4; benchmarks/lric.py)
LRIC_EXACT = np.array([[-0.9217, -0.8830], [0.7195, 0.7935], [-0.3227, -0.2428]])


def _direct_term(N=40, seed=5, deta=0.05, dx=0.05, at_bound=True):
    """Own simulation: y = (0.7 + 0.2 q^-1) / (1 - 0.8 q^-1) x (gain 4.5), input and
    output errors exactly at +-bound (random signs) or uniform inside."""
    rng = np.random.default_rng(seed)
    x0 = rng.uniform(-2, 2, N)
    w = lfilter([0.7, 0.2], [1.0, -0.8], x0)

    def err(b):
        return b * (np.where(rng.random(N) < 0.5, 1.0, -1.0) if at_bound
                    else rng.uniform(-1, 1, N))

    return x0 + err(dx), w + err(deta), np.array([-0.8, 0.7, 0.2])


def _delayed(nk, N=60, seed=3, deta=0.02, dx=0.01):
    """y = B/A x with B = 0.6 q^-nk + 0.3 q^-(nk+1), A = 1 - 0.5 q^-1; noise at +-bound."""
    rng = np.random.default_rng(seed)
    x0 = np.where(rng.random(N) < 0.5, 1.0, -1.0)
    B = np.zeros(nk + 2)
    B[nk], B[nk + 1] = 0.6, 0.3
    w = lfilter(B, [1.0, -0.5], x0)
    xm = x0 + dx * np.where(rng.random(N) < 0.5, 1.0, -1.0)     # input errors at +-dx
    y = w + deta * np.where(rng.random(N) < 0.5, 1.0, -1.0)     # output errors at +-deta
    return xm, y, np.array([-0.5, 0.6, 0.3])


def test_plain_eiv_default_has_no_gain_constraint():
    assert LinearEIVSetEstimator().steady_state_gain is None
    u, y, theta = _direct_term()
    est = LinearEIVSetEstimator(na=1, nb=1, nk=0, output_bound=0.05, method="lp")
    est.fit(u, y, input_bound=0.05)
    assert est.param_names_ == ("a1", "b0", "b1") and est.contains(theta)
    # same problem as the deprecated b0 spelling (warns, names nk=0)
    est2 = LinearEIVSetEstimator(na=1, nb=1, b0=True, output_bound=0.05, method="lp")
    with pytest.warns(FutureWarning, match="nk=0"):
        est2.fit(u, y, input_bound=0.05)
    np.testing.assert_array_equal(est2.bounds_, est.bounds_)


def test_gain_constraint_named_in_empty_set_error():
    u, y, _ = _direct_term(at_bound=False)     # gain 4.5: B(1)/A(1) = 1 is falsified
    est = LinearEIVSetEstimator(na=1, nb=1, nk=0, output_bound=0.05, steady_state_gain=1.0,
                                method="lp")
    with pytest.raises(EmptyFeasibleSetError) as info:
        est.fit(u, y, input_bound=0.05)
    msg = str(info.value)
    for part in ("na=1", "nb=1", "nk=0", "B(1)/A(1) = 1", "steady_state_gain=None",
                 "|eta_t| <= 0.05", "|dx_t| <= 0.05", "a priori box"):
        assert part in msg, part


def test_lric_exact_answer_and_independent_lp_check(lric_record):
    u, y = lric_record
    est = LinearEIVSetEstimator(na=1, nb=1, nk=0, output_bound=0.05, method="exact")
    est.fit(u, y, input_bound=0.05)
    np.testing.assert_allclose(est.bounds_, LRIC_EXACT, atol=2e-4)
    # every verified witness is feasible by an independent LP at fixed theta
    for info in est.bound_info_:
        th = info.witness
        assert th is not None and explains(eiv_data(y, u, 0.05, 0.05, 1, 1, nk=0), th)


@pytest.mark.parametrize("noise", ["uniform", "at_bound"])
def test_eiv_example_is_the_system_it_states(tmp_path, noise):
    """The record the docs use: own recursion and error check, CSV round trip, and the
    exact set (witnesses checked by an independent LP) contains the true system."""
    ex = hb.eiv_example(noise=noise, random_state=1)
    a1, b0, b1 = ex.theta
    w = np.zeros(ex.u0.size)
    for t in range(w.size):
        w[t] = b0 * ex.u0[t] + (b1 * ex.u0[t - 1] - a1 * w[t - 1] if t else 0.0)
    np.testing.assert_allclose(ex.w, w, atol=1e-12)
    du, dy = ex.data.u - ex.u0, ex.data.y - w
    assert np.all(np.abs(du) <= 0.05 + 1e-15) and np.all(np.abs(dy) <= 0.05 + 1e-15)
    if noise == "at_bound":
        np.testing.assert_allclose(np.abs(du), 0.05)
        np.testing.assert_allclose(np.abs(dy), 0.05)
    path = tmp_path / "example.csv"
    ex.data.to_csv(path)
    assert path.read_text().splitlines()[0] == "t,u,y"
    back = hb.IOData.from_csv(path)
    assert back.dt == 0.1 and np.array_equal(back.u, ex.data.u) and np.array_equal(back.y, ex.data.y)
    est = LinearEIVSetEstimator(na=1, nb=1, nk=0, output_bound=0.05, method="exact")
    est.fit(back, input_bound=0.05)
    assert est.contains(ex.theta)
    for info in est.bound_info_:
        assert explains(eiv_data(back.y, back.u, 0.05, 0.05, 1, 1, nk=0), info.witness)
    with pytest.raises(ParameterValidationError, match="noise"):
        hb.eiv_example(noise="gaussian")


def test_example_data_path_is_gone_with_a_pointer():
    import hammerbound.data.csv_reader as reader

    with pytest.raises(AttributeError, match="eiv_example"):
        reader.example_data_path  # noqa: B018


@pytest.mark.parametrize("method", ["lp", "moment", "exact"])
@pytest.mark.parametrize("nk", [1, 2, 3])
def test_input_delay_nk(method, nk):
    x, y, theta = _delayed(nk)
    est = LinearEIVSetEstimator(na=1, nb=2, nk=nk, output_bound=0.02, method=method)
    est.fit(x, y, input_bound=0.01)
    assert est.param_names_ == ("a1", f"b{nk}", f"b{nk + 1}")
    assert est.contains(theta), (est.bounds_, theta)
    assert np.all(est.radius_ < 0.2)
    B = est.B_
    assert B.size == nk + 2 and np.all(B[:nk] == 0)
    tf = est.to_transfer_function()
    # the delay shows up as nk poles at z = 0 beyond those of A
    assert np.sum(np.isclose(tf.poles(), 0.0)) >= nk


def test_nk_wrong_delay_is_not_silently_accepted():
    # data with delay 3 fitted with delay 1: the true theta is not in that model class;
    # the set must be empty or not contain the (mis-aligned) truth
    x, y, theta = _delayed(3, deta=0.005, dx=0.0)
    est = LinearEIVSetEstimator(na=1, nb=2, nk=1, output_bound=0.005, method="lp")
    with pytest.raises(EmptyFeasibleSetError, match="nk=1"):
        est.fit(x, y, input_bound=0.0)


@pytest.mark.parametrize("kw, match", [
    (dict(nk=-1), "nk"), (dict(nk=1.5), "nk"), (dict(nk=2, b0=True), "b0=True"),
    (dict(nb=0, nk=1), "nb >= 1"),
])
def test_nk_bad_params(kw, match):
    x, y, _ = _delayed(1)
    with pytest.raises(ParameterValidationError, match=match):
        LinearEIVSetEstimator(method="lp", **kw).fit(x, y)


def test_identifier_imposes_unit_gain_explicitly():
    ex = hb.chapter_example(0.05, N=100, random_state=0)
    lin = LinearEIVSetEstimator(output_bound=0.05, method="lp")
    ident = hb.HammersteinBacklashIdentifier(hb.BacklashSetEstimator(0.05), lin)
    ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    assert lin.steady_state_gain is None               # the user's object is untouched
    assert ident.linear_.steady_state_gain == 1.0
    assert ident.linear_.problem_.gain == 1.0
    bad = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), lin.set_params(steady_state_gain=2.0))
    with pytest.raises(ParameterValidationError, match="unit steady-state gain"):
        bad.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)


def test_unbounded_error_names_assumptions():
    rng = np.random.default_rng(0)
    x = np.zeros(40)                      # almost no excitation: b is not bounded by the data
    x[5] = 1e-6
    y = 0.01 * np.where(rng.random(40) < 0.5, 1.0, -1.0)
    est = LinearEIVSetEstimator(na=1, nb=1, output_bound=0.02, method="lp")
    with pytest.raises(hb.UnboundedSetError) as info:
        est.fit(x, y)
    msg = str(info.value)
    assert "Active assumptions" in msg and "nk=1" in msg and "no steady-state gain" in msg


@pytest.mark.parametrize("nk", [0, 2])
def test_one_step_envelope_with_delay_contains_noise_free_output(nk):
    rng = np.random.default_rng(7)
    N = 60
    x = np.where(rng.random(N) < 0.5, 1.0, -1.0)
    B = np.zeros(nk + 2)
    B[nk], B[nk + 1] = 0.6, 0.3
    w = lfilter(B, [1.0, -0.5], x)
    y = w + 0.02 * np.where(rng.random(N) < 0.5, 1.0, -1.0)
    est = LinearEIVSetEstimator(na=1, nb=2 if nk else 1, nk=nk, output_bound=0.02,
                                method="lp").fit(x, y)
    lo, hi = est.one_step_envelope(x, y)
    n0 = max(1, nk + 1)
    assert np.all(np.isnan(lo[:n0])) and np.all(np.isfinite(lo[n0:]))
    assert np.all((lo[n0:] <= w[n0:]) & (w[n0:] <= hi[n0:]))


def test_version_agrees_with_distribution():
    from importlib.metadata import version

    assert hb.__version__ == version("hammerbound")
