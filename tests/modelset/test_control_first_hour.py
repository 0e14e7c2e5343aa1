"""python-control objects in a new user's first hour (new-user trial): a state-space model
is accepted where a transfer function is, and frequencies above Nyquist are flagged."""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.exceptions import DataWarning, ParameterValidationError

A, B = [1.0, -1.2, 0.5], [0.0, 0.3, 0.2]


@pytest.fixture(scope="module")
def est():
    """Own simulation of B/A with input errors at +-0.02 and output errors at +-0.05."""
    rng = np.random.default_rng(3)
    x0 = np.repeat(rng.uniform(-1, 1, 25), 6)
    w = lfilter(B, A, x0)
    data = hb.IOData(x0 + 0.02 * rng.choice([-1.0, 1.0], x0.size),
                     w + 0.05 * rng.choice([-1.0, 1.0], x0.size), dt=0.05)
    return hb.LinearEIVSetEstimator(na=2, nb=2, output_bound=0.05, method="lp").fit(
        data, input_bound=0.02)


def test_state_space_is_a_model_too(est):
    G = control.tf(B, A, 0.05)
    assert est.contains(G)
    assert est.contains(control.tf2ss(G))
    assert np.allclose(est.theta_of(control.tf2ss(G)), [-1.2, 0.5, 0.3, 0.2], atol=1e-12)
    # a model outside the set stays outside in either form
    far = control.tf([0.0, 0.9, 0.2], A, 0.05)
    assert not est.contains(far) and not est.contains(control.tf2ss(far))


@pytest.mark.parametrize("G, match", [
    (control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]]), "discretise it"),
    (control.ss([[0.5]], [[1.0, 1.0]], [[1.0]], [[0.0, 0.0]], 0.05), "SISO"),
])
def test_bad_state_space(est, G, match):
    with pytest.raises(ParameterValidationError, match=match):
        est.contains(G)


def test_above_nyquist_warns(est):
    nyq = np.pi / 0.05
    with pytest.warns(DataWarning, match="above the Nyquist frequency"):
        est.frequency_response_bounds(np.array([1.0, 2 * nyq]))
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        est.frequency_response_bounds()  # the default grid ends at Nyquist
        est.frequency_response_bounds(np.array([1.0, nyq]))


def test_nyquist_warning_in_rad_per_sample_without_dt():
    rng = np.random.default_rng(3)
    x0 = np.repeat(rng.uniform(-1, 1, 25), 6)
    y = lfilter(B, A, x0) + 0.05 * rng.choice([-1.0, 1.0], x0.size)
    est = hb.LinearEIVSetEstimator(na=2, nb=2, output_bound=0.05, method="lp").fit(
        x0, y)
    with pytest.warns(DataWarning, match=r"4 rad/sample, above the Nyquist frequency pi "
                                         r"rad/sample \(no sampling time\)"):
        est.frequency_response_bounds(np.array([1.0, 4.0]))


def test_the_frequency_envelope_takes_python_control_models(est):
    """Found by a new-user trial: ``frequency_response_bounds().contains(G)`` raised a bare
    TypeError for a TransferFunction."""
    env = est.frequency_response_bounds()
    G = control.tf(B, A, 0.05)
    z = np.exp(1j * env.omega * 0.05)
    own = np.polyval(B[::-1], 1 / z) / np.polyval(A[::-1], 1 / z)  # own evaluation of B/A
    assert np.array_equal(env.contains(G), env.contains(own)) and env.contains(own).all()
    assert env.contains(control.tf2ss(G)).all()
    far = control.tf([0.0, 0.9, 0.2], A, 0.05)
    assert not env.contains(far).all()


@pytest.mark.parametrize("G, match", [
    (control.tf(B, A, 0.1), "sampling time dt = 0.1 differs"),
    (control.tf([1.0], [1.0, 1.0]), "discrete-time"),
    (control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]]), "discretise"),
    (control.tf(B, A, 0.05 * (1 + 1e-7)), "differs"),  # review: np.isclose's default atol
    (control.frd([1.0, 1.0], [1.0, 2.0]), "got a FrequencyResponseData"),
])
def test_the_frequency_envelope_refuses_models_it_cannot_compare(est, G, match):
    with pytest.raises(ParameterValidationError, match=match):
        est.frequency_response_bounds().contains(G)


@pytest.mark.parametrize("dt", [0, 0.0, -1, float("inf"), float("nan"), "0.05"])
def test_a_transfer_function_is_discrete_with_a_positive_sampling_time(est, dt):
    """dt=0 used to give a *continuous-time* transfer function with the discrete
    coefficients, silently (trial 7); other non-sampling times reached python-control's
    own ValueError. to_transfer_functions refuses before it samples the set."""
    with pytest.raises(ParameterValidationError, match="sampling time"):
        est.to_transfer_function(dt=dt)
    with pytest.raises(ParameterValidationError, match="sampling time"):
        est.to_transfer_functions(2, dt=dt)
    with pytest.raises(ParameterValidationError, match="sampling time"):
        hb.HammersteinSystem(hb.Backlash(1.0, 0.1, 1.0, 0.1), (A, B)).to_transfer_function(dt=dt)


def test_a_transfer_function_keeps_true_and_the_data_sampling_time(est):
    assert est.to_transfer_function().dt == 0.05
    assert est.to_transfer_function(dt=True).dt is True
    assert est.to_transfer_function(dt=0.2).dt == 0.2
    assert hb.HammersteinSystem(hb.Backlash(1.0, 0.1, 1.0, 0.1), (A, B)).to_transfer_function().dt is True


def test_a_numerator_without_its_leading_zero_is_explained(est):
    """New-user trial 20 gave B = [b1, b2] for [0, b1, b2] and was told only that the model
    had coefficients outside the structure."""
    with pytest.raises(ParameterValidationError) as err:
        est.contains((A, B[1:]))
    text = str(err.value)
    assert "B[0] is b0, which a delay nk=1 makes 0: B = [0, ..., b1, ...]" in text
    with pytest.raises(ParameterValidationError) as err:  # another cause: no such hint
        est.contains(([1.0, -1.2, 0.5, 0.1], B))
    assert "B[0] is b0" not in str(err.value)
