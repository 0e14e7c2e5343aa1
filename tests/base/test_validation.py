"""One validation for every entry point (hammerbound.data.validation): shapes, types, scale.

The data are simulated here (numpy/scipy), not produced by the package's generators.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.data.validation import SCALE_MAX, SCALE_MIN, as_bound, as_real, as_theta, check_scale
from hammerbound.exceptions import DataScaleError, DataValidationError, ParameterValidationError

ROOT = Path(__file__).resolve().parents[2]
ML, CL, MR, CR = 0.25, 0.0628, 0.26, 0.0489
A = np.array([1.0, -0.76, 0.82])
B = np.array([0.0, 2.15, -1.09])  # unit steady-state gain: B(1) = A(1) = 1.06
THETA = np.array([-0.76, 0.82, 2.15, -1.09])


def _steady(delta, seed=0):
    """Steady-state points of the backlash lines with uniform noise inside +-delta."""
    rng = np.random.default_rng(seed)
    amps = np.linspace(0.3, 2.4, 12)
    u = np.concatenate([amps, -amps])
    w = np.where(u > 0, MR * (u - CR), ML * (u + CL))
    return u, w + rng.uniform(-delta, delta, u.size)


def _prbs(n, delta, seed=0):
    """Inner PRBS x (levels of the backlash at u* = +-1) through B/A, noise inside +-delta."""
    rng = np.random.default_rng(seed)
    u = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    x = np.where(u > 0, MR * (1.0 - CR), ML * (-1.0 + CL))
    return u, x, lfilter(B, A, x) + rng.uniform(-delta, delta, n)


def _gamma_in(est, s_u=1.0, s_y=1.0):
    # y = m (u - c): scaling u by s_u and y by s_y maps m -> m s_y / s_u and c -> c s_u
    g = np.array([ML * s_y / s_u, CL * s_u, MR * s_y / s_u, CR * s_u])
    return bool(np.all((g >= est.gamma_bounds_[:, 0]) & (g <= est.gamma_bounds_[:, 1])))


# ------------------------------------------------------------------ shapes and types
def test_noise_bound_column_vector_is_accepted_like_a_vector():
    u, y = _steady(0.02)
    d = np.full(u.size, 0.02)
    a = hb.BacklashSetEstimator(d).fit(u, y)
    b = hb.BacklashSetEstimator(d[:, None]).fit(u, y)
    np.testing.assert_array_equal(a.gamma_bounds_, b.gamma_bounds_)
    _, x, yp = _prbs(60, 0.02)
    d = np.full(60, 0.02)
    a = hb.LinearEIVSetEstimator(output_bound=d, method="lp").fit(x, yp)
    b = hb.LinearEIVSetEstimator(output_bound=d[:, None], method="lp").fit(x, yp,
                                                                       input_bound=np.zeros((60, 1)))
    np.testing.assert_array_equal(a.bounds_, b.bounds_)
    assert b.contains(THETA)


@pytest.mark.parametrize("bad", [True, np.bool_(True), "0.05", np.array([True] * 24)])
def test_boolean_and_text_noise_bounds_are_refused(bad):
    u, y = _steady(0.02)
    with pytest.raises(ParameterValidationError, match="output_bound"):
        hb.BacklashSetEstimator(bad).fit(u, y)


def test_scalars_accept_numpy_numbers_and_refuse_text_bool_nan():
    assert as_real("margin", np.float32(0.5), lo=0.0, hi=1.0) == 0.5
    assert as_real("g", np.array(2.0), nonzero=True) == 2.0
    assert as_real("g", None, or_none=True) is None
    for bad, match in [("1.0", "without quotes"), (True, "boolean"), (np.nan, "finite"),
                       ([1.0], "list"), (1 + 0j, "complex")]:
        with pytest.raises(ParameterValidationError, match=match):
            as_real("g", bad)
    assert as_bound("d", np.int64(2), 3).tolist() == [2.0, 2.0, 2.0]
    with pytest.raises(DataValidationError, match=r"shape \(3,\) or \(3, 1\)"):
        as_bound("d", np.ones((3, 2)), 3)
    with pytest.raises(ParameterValidationError, match=">= 0"):
        as_bound("d", [0.0, -1.0, 0.0], 3, allow_zero=True)


def test_check_prbs_level_and_margin_refuse_text_but_take_numbers():
    u, y = _steady(0.02)
    est = hb.BacklashSetEstimator(0.02).fit(u, y)
    est.check_prbs_level(np.float64(1.0))  # admissible: no error
    with pytest.raises(ParameterValidationError, match="without quotes"):
        est.check_prbs_level("1.0")
    with pytest.raises(ParameterValidationError, match="without quotes"):
        est.suggest_prbs_level(margin="0.5")
    lo, hi = est.admissible_prbs_range()
    assert lo < est.suggest_prbs_level(margin=np.float64(0.5)) < hi


@pytest.mark.parametrize("flag", ["no", 0, 1, None])
def test_well_posed_on_data_must_be_a_boolean(flag):
    u, y = _steady(0.02)
    with pytest.raises(ParameterValidationError, match="True or False"):
        hb.BacklashSetEstimator(0.02, well_posed_on_data=flag).fit(u, y)


def test_steady_state_gain_true_is_refused_numpy_gain_accepted():
    _, x, y = _prbs(60, 0.02)
    with pytest.raises(ParameterValidationError, match="True is not taken as 1"):
        hb.LinearEIVSetEstimator(steady_state_gain=True, output_bound=0.02, method="lp").fit(x, y)
    est = hb.LinearEIVSetEstimator(steady_state_gain=np.float64(1.0), output_bound=0.02,
                                   method="lp").fit(x, y)
    assert est.contains(THETA)


def test_every_contains_refuses_nan_parameters():
    u, y = _steady(0.02)
    s1 = hb.BacklashSetEstimator(0.02).fit(u, y)
    assert s1.left_.contains([ML, CL]) and s1.right_.contains([MR, CR])
    for fs in (s1.left_, s1.right_):
        with pytest.raises(DataValidationError, match="NaN"):
            fs.contains([np.nan, 0.05])
        with pytest.raises(DataValidationError, match="NaN"):
            hb.FeasibleSet.contains(fs, [0.25, np.nan])  # the orthotope test too
    _, x, yp = _prbs(60, 0.02)
    s2 = hb.LinearEIVSetEstimator(output_bound=0.02, method="lp").fit(x, yp)
    assert s2.contains(THETA)
    with pytest.raises(DataValidationError, match="a2"):
        s2.contains([-0.76, np.nan, 2.15, -1.09])
    with pytest.raises(DataValidationError, match="in order"):
        s2.contains([-0.76, 0.82, 2.15])


def test_all_zero_output_with_prbs_input_is_refused():
    u, x, _ = _prbs(60, 0.02)
    with pytest.raises(DataValidationError, match="no information about the dynamics"):
        hb.LinearEIVSetEstimator(output_bound=0.02, method="lp").fit(x, np.zeros(60))
    us, ys = _steady(0.02)
    ident = hb.HammersteinBacklashIdentifier(hb.BacklashSetEstimator(0.02),
                                             hb.LinearEIVSetEstimator(output_bound=0.02,
                                                                      method="lp"))
    with pytest.raises(DataValidationError, match="no information about the dynamics"):
        ident.fit(u, np.zeros(60), steady_state=(us, ys))
    with pytest.raises(DataValidationError, match="identically zero"):
        hb.LinearEIVSetEstimator(output_bound=0.02, method="lp").fit(np.zeros(60), x)


# ------------------------------------------------------------------ scale (issue 20)
@pytest.mark.parametrize("s", [1e300, 1e-300])
def test_extreme_scales_get_a_scale_error_in_both_stages(s):
    u, y = _steady(0.02)
    with pytest.raises(DataScaleError, match="Rescale") as ei:
        hb.BacklashSetEstimator(0.02 * s).fit(u * s, y * s)
    assert isinstance(ei.value, DataValidationError)
    _, x, yp = _prbs(60, 0.02)
    with pytest.raises(DataScaleError, match="leaves theta unchanged"):
        hb.LinearEIVSetEstimator(output_bound=0.02 * s, method="lp").fit(x * s, yp * s)
    up, _, _ = _prbs(60, 0.02)
    with pytest.raises(DataScaleError):
        hb.HammersteinBacklashIdentifier(
            hb.BacklashSetEstimator(0.02 * s),
            hb.LinearEIVSetEstimator(output_bound=0.02 * s, method="lp")).fit(
                up * s, yp * s, steady_state=(u * s, y * s))
    from hammerbound.discrepancy import diagnose

    with pytest.raises(DataScaleError):
        diagnose(hb.HammersteinSystem(hb.Backlash(ML, CL, MR, CR), (A, B)),
                 up * s, yp * s, 0.02 * s)


@pytest.mark.parametrize("top", [SCALE_MIN, SCALE_MAX])
def test_the_edges_of_the_range_are_accepted_and_sound(top):
    """At the documented edges both stages run and contain the truth (independent check
    of the range stated in check_scale's docstring)."""
    pick = min if top == SCALE_MIN else max  # the signal that sits on the edge
    u, y = _steady(0.02)
    s = top / pick(np.abs(u).max(), np.abs(y).max())
    est = hb.BacklashSetEstimator(0.02 * s).fit(u * s, y * s)
    assert _gamma_in(est, s, s)
    _, x, yp = _prbs(80, 0.02)
    s = top / pick(np.abs(x).max(), np.abs(yp).max())
    est = hb.LinearEIVSetEstimator(output_bound=0.02 * s, method="lp").fit(x * s, yp * s)
    assert est.contains(THETA)
    out = s * (0.5 if top == SCALE_MIN else 2.0)  # just outside the range
    with pytest.raises(DataScaleError):
        hb.LinearEIVSetEstimator(output_bound=0.02 * out, method="lp").fit(x * out, yp * out)


def test_slope_ratio_and_huge_bounds_are_refused():
    u, y = _steady(0.02)
    with pytest.raises(DataScaleError, match="slopes are too small"):
        hb.BacklashSetEstimator(0.02e-6).fit(u * 1e3, y * 1e-6)
    # independent scales of u and y inside the range are fine (m and c map exactly)
    est = hb.BacklashSetEstimator(0.02e-3).fit(u * 10, y * 1e-3)
    assert _gamma_in(est, 10.0, 1e-3)
    with pytest.raises(DataScaleError, match="output_bound"):
        check_scale("f", {"y": y}, {"output_bound": np.full(y.size, 1e12)})


def test_cli_identify_refuses_extreme_scale_before_the_work(tmp_path):
    u, y = _steady(0.02)
    up, _, yp = _prbs(60, 0.02)
    s = 1e300
    (tmp_path / "ss.csv").write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in
                                                     zip(u * s, y * s, strict=True)))
    (tmp_path / "pr.csv").write_text("u,y\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in
                                                     zip(up * s, yp * s, strict=True)))
    r = subprocess.run(
        [sys.executable, "-m", "hammerbound", "identify", "--steady", str(tmp_path / "ss.csv"),
         "--prbs", str(tmp_path / "pr.csv"), "--steady-output-bound", "2e298", "--output-bound", "2e298",
         "--method", "lp"],
        capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert r.returncode == 2, r.stderr
    assert "DataScaleError" in r.stderr and "Rescale" in r.stderr
    assert "Traceback" not in r.stderr and r.stdout == ""


def test_as_theta_names_the_bad_entry():
    with pytest.raises(DataValidationError, match="b1"):
        as_theta([0.1, np.inf], 2, ("a1", "b1"))
    with pytest.raises(DataValidationError, match="2 numbers"):
        as_theta("ab", 2, ("a1", "b1"))
