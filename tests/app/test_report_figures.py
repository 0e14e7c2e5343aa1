"""Report and figures (issue 14, item 6): band fraction over banded samples, intervals in
their own units without a true value, the backlash characteristic with its band."""

from __future__ import annotations

import re

import matplotlib
import numpy as np
import pytest

import hammerbound as hb
from hammerbound.plotting import backlash_band, plot_backlash, plot_intervals

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


@pytest.fixture(scope="module")
def fitted():
    ex = hb.chapter_example(0.05, N=100, random_state=0)
    ident = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05), hb.LinearEIVSetEstimator(output_bound=0.05, method="lp"))
    ident.fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    return ex, ident


def test_report_fraction_over_banded_samples_and_figures(fitted, tmp_path):
    from hammerbound.app.report import write_report

    ex, ident = fitted
    path = write_report(ident, ex.steady.u, ex.steady.y, ex.prbs.u, ex.prbs.y, tmp_path)
    text = path.read_text()
    m = re.search(r"within band \+- output bound: ([0-9.]+) \(over the (\d+) samples", text)
    assert m, text
    # own count: the guaranteed band +- the bound contains every measurement
    lo, hi = ident.output_envelope(ex.prbs.u, ex.prbs.y)
    ok = np.isfinite(lo)
    assert int(m.group(2)) == ok.sum() == ex.prbs.u.size - 2
    assert float(m.group(1)) == 1.0
    for fig in ("backlash_characteristic.png", "intervals.png", "envelope.png"):
        assert (tmp_path / fig).stat().st_size > 1000
    assert "| ml |" in text and "m_l" not in text


def test_intervals_without_truth_in_own_units(fitted):
    _, ident = fitted
    fig, ax = plt.subplots()
    b = ident.theta_bounds_
    plot_intervals(b, list(ident.linear_.param_names_), ax)
    lo, hi = ax.get_xlim()
    assert lo <= b[:, 0].min() and hi >= b[:, 1].max()
    assert ax.get_xlabel() == "value"
    segs = ax.collections[0].get_segments()
    np.testing.assert_allclose([s[0][0] for s in segs], b[:, 0])
    np.testing.assert_allclose([s[1][0] for s in segs], b[:, 1])
    plt.close(fig)
    # with a true value: normalised as before
    fig, ax = plt.subplots()
    plot_intervals(b, list(ident.linear_.param_names_), ax, true_values=b.mean(axis=1))
    assert ax.get_xlabel().startswith("(bound - true)")
    plt.close(fig)


def test_backlash_band_is_exact_over_the_vertices(fitted):
    ex, ident = fitted
    bl = ident.backlash_
    u = np.linspace(-2.5, 2.5, 11)
    llo, lhi, rlo, rhi = backlash_band(bl, u)
    # own computation from the (m, c) vertices: line values at every vertex
    for fs, lo, hi, sign in ((bl.left_, llo, lhi, 1.0), (bl.right_, rlo, rhi, -1.0)):
        m, c = fs.vertices[:, 0], fs.vertices[:, 1]
        vals = m[:, None] * (u[None, :] + sign * c[:, None])
        np.testing.assert_allclose(lo, vals.min(axis=0), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(hi, vals.max(axis=0), rtol=1e-9, atol=1e-12)
    # the true lines lie in the band
    ml, cl, mr, cr = ex.gamma_true
    assert np.all((llo <= ml * (u + cl) + 1e-12) & (ml * (u + cl) <= lhi + 1e-12))
    assert np.all((rlo <= mr * (u - cr) + 1e-12) & (mr * (u - cr) <= rhi + 1e-12))
    fig, ax = plt.subplots()
    plot_backlash(bl, ex.steady.u, ex.steady.y, ax, output_bound=0.05, u_star=ident.u_star_,
                  inner_bounds=ident.inner_bounds_, true_backlash=ex.gamma_true)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "steady-state points" in labels and "left line band" in labels
    plt.close(fig)
