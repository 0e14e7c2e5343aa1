"""``FrequencyEnvelope.contains`` compares the phase modulo 2 pi (new-user trial 12: with a
relative phase range reaching past +-pi it compared the principal value only and rejected
box models that lie inside the envelope). The responses are computed here, not by the
package."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

import hammerbound as hb


def _wide_set(bound=0.5):
    rng = np.random.default_rng(1)
    u = np.repeat(rng.choice([-1.0, 1.0], 21), 4)[:80]
    y = lfilter([0, 1.0, 0.5], [1, -1.5, 0.7], u) + rng.uniform(-bound, bound, 80)
    est = hb.LinearEIVSetEstimator(na=2, nb=2, output_bound=bound, method="lp").fit(u, y)
    omega = np.linspace(0, np.pi, 400)
    return est, omega, est.frequency_response_bounds(omega, dt=1.0)


def _response(theta, omega):
    zi = np.exp(-1j * omega)
    return (theta[2] * zi + theta[3] * zi**2) / (1 + theta[0] * zi + theta[1] * zi**2)


def test_every_box_model_is_inside_its_envelope():
    est, omega, env = _wide_set()
    lo, hi = est.bounds_.T
    rel = env.phase_upper - env.phase_lower
    assert np.nanmax(rel) > np.pi  # the case of the finding: a range wider than pi
    rng = np.random.default_rng(0)
    corners = np.array(np.meshgrid(*est.bounds_)).reshape(4, -1).T
    points = np.vstack([corners, lo + (hi - lo) * rng.random((600, 4))])
    for theta in points:
        assert env.contains(_response(theta, omega)).all(), theta


def test_a_model_outside_in_phase_or_magnitude_is_rejected():
    est, omega, env = _wide_set(0.05)
    g0 = _response(est.center_, omega)
    assert env.contains(g0).all()
    assert not env.contains(100.0 * g0).all()  # magnitude far above
    narrow = env.phase_bounded & (env.phase_upper - env.phase_lower < np.pi / 2)
    assert narrow.any()
    flipped = env.contains(-g0)  # same magnitude, phase turned by pi
    assert not flipped[narrow].any()


def test_a_negative_rtol_is_refused():
    """rtol widens the bounds; a negative one narrowed them without a word (review)."""
    import pytest

    from hammerbound.exceptions import ParameterValidationError

    est, omega, env = _wide_set(0.05)
    g0 = _response(est.center_, omega)
    for bad in (-1e-3, float("nan"), "0.1"):
        with pytest.raises(ParameterValidationError, match="rtol must be"):
            env.contains(g0, rtol=bad)
    assert env.contains(g0, rtol=1e-3).all()
