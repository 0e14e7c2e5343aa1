"""Issue 29 items 7 (model-set part) and 12: frequency methods use the fitted sampling
time (or say rad/sample), names and units reach the model and the plots, and the Bode
envelope's magnitude axis stays readable when a lower bound is 0.

Responses are checked against scipy.signal.freqz of the central polynomials; data are
simulated here with scipy.signal.lfilter.
"""

from __future__ import annotations

import warnings

import matplotlib
import numpy as np
import pytest
from scipy.signal import freqz, lfilter

import hammerbound as hb
from hammerbound.modelset.frequency import frequency_envelope

matplotlib.use("Agg")

A = np.array([1.0, -1.5, 0.7])
B = np.array([0.0, 0.1, 0.09])  # zero at z = -0.9: near Nyquist


def record(N=120, seed=3, at_bound=True):
    rng = np.random.default_rng(seed)
    x = np.repeat(rng.uniform(-1, 1, N // 4 + 1), 4)[:N]
    e = 0.005 * (rng.choice([-1.0, 1.0], N) if at_bound else rng.uniform(-1, 1, N))
    return x, lfilter(B, A, x) + e


def fit(data, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return hb.LinearEIVSetEstimator(2, 2, output_bound=0.005, method="exact").fit(
            data, input_bound=0.0, **kw)


@pytest.fixture(scope="module")
def fitted():
    x, y = record()
    data = hb.IOData(x, y, dt=0.1, input_name="force", input_unit="N",
                     output_name="position", output_unit="mm")
    return fit(data), fit(x, y=y)


def test_fitted_dt_sets_the_frequency_axis(fitted):
    est, _ = fitted
    env = est.frequency_response_bounds()
    assert env.omega[-1] == pytest.approx(10 * np.pi) and env.frequency_unit == "rad/s"
    # the response at omega is G(e^{j omega dt}) with dt = 0.1 (independent freqz)
    _, h = freqz(est.B_, est.A_, worN=env.omega * 0.1)
    np.testing.assert_allclose(env.central, h, rtol=1e-9)
    uw = est.uncertainty_weight(order=1)
    assert uw.W.dt == 0.1 and uw.central.dt == 0.1 and uw.frequency_unit == "rad/s"
    assert uw.omega[-1] == pytest.approx(10 * np.pi)
    assert uw.certificate.omega[-1] == pytest.approx(10 * np.pi)
    # an explicit dt still wins
    env2 = est.frequency_response_bounds(dt=0.2)
    assert env2.omega[-1] == pytest.approx(5 * np.pi)
    np.testing.assert_allclose(env2.mag_upper, env.mag_upper, rtol=1e-8)  # same z grid


def test_no_sampling_time_means_rad_per_sample(fitted):
    _, est = fitted
    assert est.dt_ is None
    env = est.frequency_response_bounds()
    assert env.omega[-1] == pytest.approx(np.pi) and env.frequency_unit == "rad/sample"
    fig = env.plot()
    assert fig.axes[1].get_xlabel() == "frequency [rad/sample]"
    uw = est.uncertainty_weight(order=1)
    assert uw.W.dt is True and uw.central.dt is True and uw.frequency_unit == "rad/sample"
    for dt in (True, None):
        assert est.frequency_response_bounds(dt=dt).frequency_unit == "rad/sample"
    import matplotlib.pyplot as plt

    plt.close("all")


def test_identifier_uses_its_fitted_dt():
    ex = hb.chapter_example(0.05, N=60, random_state=0)
    data = hb.IOData(ex.prbs.u, ex.prbs.y, dt=0.1)
    idf = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="exact"),
    ).fit(data, steady_state=ex.steady)
    env = idf.frequency_response_bounds()
    assert env.omega[-1] == pytest.approx(10 * np.pi) and env.frequency_unit == "rad/s"
    assert idf.uncertainty_weight(order=1).W.dt == 0.1
    assert idf.frequency_response_bounds(dt=0.5).omega[-1] == pytest.approx(2 * np.pi)
    idf2 = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="exact"),
    ).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    assert idf2.frequency_response_bounds().frequency_unit == "rad/sample"


def test_names_and_units_reach_the_model_and_the_plot(fitted):
    import matplotlib.pyplot as plt

    est, _ = fitted
    assert est.signal_names_ == ("force", "position")
    assert est.signal_units_ == ("N", "mm") and est.time_unit_ == ""
    G = est.to_transfer_function()
    assert G.input_labels == ["force"] and G.output_labels == ["position"]
    assert "signals: force [N] -> position [mm]" in est.summary()
    env = est.frequency_response_bounds()
    assert env.signal_names == ("force", "position") and env.signal_units == ("N", "mm")
    assert env.refine(rtol=0.5, max_points=600).signal_units == ("N", "mm")
    fig = env.plot()
    assert fig.axes[0].get_title() == "force [N] -> position [mm]"
    assert fig.axes[0].get_ylabel() == "magnitude [dB re 1 mm/N]"
    assert fig.axes[1].get_xlabel() == "frequency [rad/s]"
    plt.close("all")


def test_time_unit_of_the_data_labels_the_frequency():
    x, y = record(at_bound=False)
    est = fit(hb.IOData(x, y, dt=2.0, time_unit="ms"))
    env = est.frequency_response_bounds()
    assert env.frequency_unit == "rad/ms" and env.omega[-1] == pytest.approx(np.pi / 2)
    assert "dt = 2 ms" in est.summary()


# ----------------------------------------------------------------------------- item 12
def band_extremes(fig, w):
    """Lowest and highest y of the envelope polygon at each frequency of ``w``."""
    path = fig.axes[0].collections[0].get_paths()[0]
    v = path.vertices
    lo = np.array([v[np.isclose(v[:, 0], wi, rtol=1e-12), 1].min() for wi in w])
    hi = np.array([v[np.isclose(v[:, 0], wi, rtol=1e-12), 1].max() for wi in w])
    return lo, hi


def test_zero_lower_bound_does_not_collapse_the_axis():
    """B's box contains b1 = b2, so B(-1) = 0 is possible: |G| >= 0 only, at Nyquist.
    The axis used to reach about -6000 dB."""
    import matplotlib.pyplot as plt

    bounds = np.array([[-1.52, -1.48], [0.68, 0.72], [0.08, 0.12], [0.08, 0.11]])
    w = np.linspace(0.01, np.pi, 400)
    env = frequency_envelope(bounds, 2, [1, 2], w)
    assert env.mag_lower[-1] == 0.0
    fig = env.plot()
    bottom, top = fig.axes[0].get_ylim()
    up_db = 20 * np.log10(env.mag_upper)
    assert top >= up_db.max() and bottom >= up_db.max() - 120 - 1e-9 and bottom > -200
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any("lower bound 0" in t and "bottom edge" in t for t in texts)
    # never a wrong bound: the band covers [lower, upper] wherever they are on the axis,
    # and where the lower bound is off the axis the band runs off it too
    lo, hi = band_extremes(fig, w)
    with np.errstate(divide="ignore"):
        lo_db = 20 * np.log10(env.mag_lower)
    shown = lo_db >= bottom
    np.testing.assert_allclose(lo[shown], lo_db[shown], rtol=1e-12)
    assert np.all(lo[~shown] < bottom) and (~shown).any()
    np.testing.assert_allclose(hi, up_db, rtol=1e-12)
    # linear axes: 0 is an ordinary value
    fig2 = env.plot(db=False)
    assert fig2.axes[0].get_ylim()[0] <= 0.0
    plt.close("all")


def test_axis_shows_every_bound_when_they_fit():
    import matplotlib.pyplot as plt

    bounds = np.array([[-0.52, -0.48], [0.9, 1.1]])
    w = np.logspace(-2, np.log10(np.pi), 100)
    env = frequency_envelope(bounds, 1, [1], w)
    fig = env.plot(mag_range_db=120.0)
    bottom, top = fig.axes[0].get_ylim()
    assert bottom <= 20 * np.log10(env.mag_lower.min()) and top >= 20 * np.log10(
        env.mag_upper.max())
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert not any("edge" in t for t in texts)
    plt.close("all")
