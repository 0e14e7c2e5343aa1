"""The report of a one-record fit (``hammerbound.app.record_report``), on records simulated
here (the tests' own play operator and scipy's lfilter)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from oracles import play
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.app.record_report import RecordReport, line_bands, write_record_report
from hammerbound.exceptions import ParameterValidationError

GAMMA = (0.25, 0.06, 0.26, 0.05)


def _fit(u, y):
    ident = hb.HammersteinBacklashIdentifier(
        linear=hb.LinearEIVSetEstimator(na=1, nb=1, nk=1, output_bound=0.02, method="lp"),
        procedure="one-record")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ident.fit(u, y)


def test_an_input_that_never_reverses_gives_a_report_without_a_band(tmp_path):
    """A ramp leaves the left line unidentified: the report says there is no envelope and
    no characteristic band instead of drawing one it cannot stand behind."""
    u = np.linspace(-2.0, 2.0, 40)
    y = lfilter([0.0, 0.5], [1.0, -0.5], play(u, *GAMMA))
    y = y + 0.02 * np.random.default_rng(0).uniform(-1, 1, u.size)
    ident = _fit(u, y)
    assert not np.all(np.isfinite(ident.gamma_bounds_))
    path = write_record_report(ident, u, y, tmp_path / "rep")
    text = path.read_text()
    assert "No envelope: an interval is infinite" in text
    assert "| cl |" in text and "inf" in text
    assert (tmp_path / "rep" / "envelope.png").exists()
    rep = RecordReport.build(ident, u, y)
    assert rep.to_dict()["envelope"] is None


def test_the_line_bands_hold_every_line_of_the_box():
    """The band of each line over the box (its corners) holds the line of any point of the
    box (sampled here)."""
    box = np.array([[0.2, 0.3], [0.0, 0.1], [0.25, 0.27], [0.04, 0.08]])
    u = np.linspace(-2, 2, 41)
    llo, lhi, rlo, rhi = line_bands(box, u)
    rng = np.random.default_rng(1)
    for ml, cl, mr, cr in rng.uniform(box[:, 0], box[:, 1], (500, 4)):
        assert np.all((llo - 1e-12 <= ml * (u + cl)) & (ml * (u + cl) <= lhi + 1e-12))
        assert np.all((rlo - 1e-12 <= mr * (u - cr)) & (mr * (u - cr) <= rhi + 1e-12))


def test_a_two_stage_fit_is_refused_with_the_other_report_named():
    ident = hb.HammersteinBacklashIdentifier()
    ident.procedure_ = "two-stage"
    with pytest.raises(ParameterValidationError, match="IdentificationReport"):
        RecordReport.build(ident, np.zeros(3), np.zeros(3))


def test_relative_intervals_show_narrow_intervals_of_large_values():
    """Trial 15: in their own units, intervals 0.01 wide next to values of 1 were
    invisible. Relative to their centres (per cent of |centre|) each bar shows its width;
    an infinite interval is named."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from hammerbound.plotting import plot_relative_intervals

    bounds = np.array([[0.99, 1.01], [-2.2, -1.8], [-0.05, 0.05], [0.0, np.inf]])
    fig, ax = plt.subplots()
    plot_relative_intervals(bounds, ["a", "b", "z", "c"], ax,
                            true_values=[1.0, -2.1, 0.01, 0.5])
    (bars,) = ax.collections
    segs = bars.get_segments()
    # an interval about 0 is scaled by its half-width (it was divided by 1e-300, review)
    np.testing.assert_allclose([s[:, 0] for s in segs],
                               [[-1.0, 1.0], [-10.0, 10.0], [-100.0, 100.0]], atol=1e-9)
    assert [t.get_text() for t in ax.texts] == ["not bounded"]
    plt.close(fig)


def test_the_envelope_is_drawn_over_time_when_the_sampling_time_is_known():
    """Trial 15: the report's envelope had its x axis in samples although the record gave
    its sampling time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(-2, 2, 12), 8)
    y = lfilter([0.0, 0.5], [1.0, -0.5], play(u, *GAMMA)) + 0.02 * rng.uniform(-1, 1, u.size)
    ident = _fit(hb.IOData(u, y, dt=0.5, time_unit="s"), None)
    assert np.all(np.isfinite(ident.bounds_))
    rep = RecordReport.build(ident, u, y)
    fig, ax = plt.subplots()
    rep._draw_envelope(ax)
    assert ax.get_xlabel() == "time s"
    assert ax.dataLim.x1 == pytest.approx(0.5 * (u.size - 1), rel=0.02)
    plt.close(fig)
    fig, ax = plt.subplots()  # without a sampling time: samples, as before
    rep.envelope.plot(ax)
    assert ax.get_xlabel() == "sample t"
    plt.close(fig)
