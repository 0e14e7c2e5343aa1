"""Stage 1 with noise *at* its bound (issue 13): truth inside, never a false "empty".

The bounded-error promise is "if every |eta_s| <= Delta, the true backlash is inside". Real
data sit exactly at the bound (quantised sensors: errors of exactly +-LSB/2) and worst-case
tests put it there on purpose, so every run here uses extremal noise: exactly +-Delta in
alternating, random-sign and constant patterns, and (1 +- 1e-12) Delta, at signal scales
from 1e-6 to 1e6, for both stage-1 methods and for the whole identifier. The truths are
simulated with the small numpy code below (not the package's ``experiments`` module).

Policy under test (docs/tolerances.md): every bound is relaxed outward by a tolerance of
``FEASIBILITY_RTOL`` (1e-9) times the magnitudes of the constraint's terms, so noise at
(1 + 1e-12) Delta is *inside* the tolerance and must be accepted; data are declared
inconsistent only when the violation is certified (exact arithmetic) beyond it.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from oracles import side_widening
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.exceptions import EmptyFeasibleSetError
from hammerbound.tolerances import FEASIBILITY_RTOL

# random slopes: some truths' lines cross inside the tested inputs (the fit warns,
# trial 19; those truths are the play operator max(R, min(L, x)), each side on its line)
pytestmark = pytest.mark.filterwarnings(
    "ignore:the steady-state points reach u:hammerbound.exceptions.DataWarning")

METHODS = ("polygon", "algorithm")
PATTERNS = ("alternating", "random", "constant", "over", "under")
SCALES = (1e-6, 1e-3, 1.0, 1e3, 1e6)
# every (input, output) scale pair the estimator accepts: slopes ~ sy / su >= 1e-9 is the
# data-scale guard of BacklashSetEstimator (DataScaleError below; not a tolerance matter)
SCALE_PAIRS = [(su, sy) for su in SCALES for sy in SCALES if sy / su > 1e-9]


# ----------------------------------------------------------------------------- simulation
def _truth(rng, su, sy, zero_c=False):
    """``(m_l, c_l, m_r, c_r)``: outputs of order ``sy`` for inputs of order ``su``."""
    ml, mr = rng.uniform(0.2, 2.0, 2) * (sy / su)
    cl, cr = (0.0, 0.0) if zero_c else tuple(rng.uniform(0.0, 0.3, 2) * su)
    return np.array([ml, cl, mr, cr])


def _steady(rng, gamma, M, su):
    """Signed amplitudes (M per side, >= 0.2 su apart) and noise-free outputs (22.9)-(22.10)."""
    ml, cl, mr, cr = gamma
    amps = su * np.sort(rng.choice(np.linspace(0.4, 3.0, 14), M, replace=False))
    u = np.concatenate([amps, -amps])
    w = np.where(u > 0, mr * (u - cr), ml * (u + cl))
    return u, w


def _signs(rng, pattern, M):
    """Noise signs of one side (amplitude order) for a pattern."""
    if pattern in ("alternating", "under"):
        start = rng.choice([-1.0, 1.0])
        return start * (-1.0) ** np.arange(M)
    if pattern == "constant":
        return np.full(M, rng.choice([-1.0, 1.0]))
    return rng.choice([-1.0, 1.0], M)  # random, over


def _extremal(rng, pattern, M, D):
    """Noise exactly at +-D (or (1 +- 1e-12) D) for both sides."""
    factor = {"over": 1.0 + 1e-12, "under": 1.0 - 1e-12}.get(pattern, 1.0)
    s = np.concatenate([_signs(rng, pattern, M), _signs(rng, pattern, M)])
    return factor * D * s


def _case(rng, pattern, su, sy, M=None, drel=None):
    M = int(rng.integers(2, 7)) if M is None else M
    drel = 10.0 ** rng.uniform(-9, -2) if drel is None else drel
    gamma = _truth(rng, su, sy, zero_c=rng.random() < 0.1)
    u, w = _steady(rng, gamma, M, su)
    D = drel * sy
    return u, w + _extremal(rng, pattern, M, D), D, gamma


def _assert_inside(est, gamma, what):
    gb = est.gamma_bounds_
    assert np.all(gb[:, 0] <= gamma) and np.all(gamma <= gb[:, 1]), (what, gb, gamma)
    assert est.left_.contains(gamma[:2]) and est.right_.contains(gamma[2:]), what
    # built at the policy's tolerance, without the widened fallback
    assert est.left_.tolerance_factor == est.right_.tolerance_factor == 1.0


# ----------------------------------------------------------------------------- the repro
def _three_point(factor, D=0.02):
    gamma = np.array([0.25, 0.0628, 0.26, 0.0489])  # the chapter's backlash
    a = np.array([0.5, 1.0, 2.0])
    u = np.concatenate([a, -a])
    ml, cl, mr, cr = gamma
    w = np.where(u > 0, mr * (u - cr), ml * (u + cl))
    s = np.array([1.0, -1.0, 1.0, 1.0, -1.0, 1.0])
    return u, w + factor * D * s, D, gamma


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("factor", [1.0, 0.999999999, 1 - 1e-8, 1 + 1e-12, 1 - 1e-12])
def test_issue13_three_point_repro_is_a_point_with_the_truth(method, factor):
    """+D, -D, +D on three amplitudes: the exact set of each side is the single true point.

    It is returned (outward-relaxed, so its vertices nearly coincide) with the truth inside
    and an orthotope whose width is of the order of the tolerance, not of the noise.
    """
    u, y, D, gamma = _three_point(factor)
    est = hb.BacklashSetEstimator(D, method=method).fit(u, y)
    _assert_inside(est, gamma, factor)
    width = est.gamma_bounds_[:, 1] - est.gamma_bounds_[:, 0]
    # a point: the widths come from the tolerance (~1e-9 of the data), far below D = 0.02
    assert np.all(width < 1e-6), width


@pytest.mark.parametrize("method", METHODS)
def test_inconsistent_beyond_the_tolerance_is_certified_empty(method):
    """(1 + 1e-4) D on the +, -, + pattern: no affine line fits the three points (the middle
    one lies 1e-4 D on the wrong side of the chord); that is far beyond the tolerance, so the
    data are reported inconsistent -- and an independent LP agrees."""
    u, y, D, _ = _three_point(1 + 1e-4)
    with pytest.raises(EmptyFeasibleSetError) as info:
        hb.BacklashSetEstimator(D, method=method).fit(u, y)
    side = info.value.side
    sel = u > 0 if side == "right" else u < 0
    # independent: the smallest uniform widening s of every bound that admits a backlash,
    # rows scaled by 1/D so that HiGHS's tolerances are far below the effect
    ys = y[sel]
    excess = side_widening(u[sel], ys, D, side) * D  # in output units
    tol = FEASIBILITY_RTOL * (np.max(np.abs(ys)) * 4 + D)  # generous bound on the tolerance
    assert excess > 10 * tol, (excess, tol)


# ----------------------------------------------------------------------------- the grid
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("pattern", PATTERNS)
def test_extremal_noise_grid_truth_inside_never_empty(method, pattern):
    """110 runs per (pattern, method), 1100 in all: every accepted pair of input/output
    scales in 1e-6..1e6, 2-6 amplitudes per side, Delta from 1e-9 to 1e-2 of the output."""
    rng = np.random.default_rng(10 * METHODS.index(method) + PATTERNS.index(pattern))
    runs = 0
    for su, sy in SCALE_PAIRS:
        for _ in range(5):
            u, y, D, gamma = _case(rng, pattern, su, sy)
            est = hb.BacklashSetEstimator(D, method=method).fit(u, y)
            _assert_inside(est, gamma, (pattern, su, sy, D))
            runs += 1
    assert runs == 110


@pytest.mark.parametrize("pattern", PATTERNS)
def test_both_methods_agree_on_extremal_noise(pattern):
    """Algorithm 22.1 and the half-plane intersection give the same relaxed set."""
    rng = np.random.default_rng(7)
    for su, sy in ((1e-6, 1e6), (1.0, 1.0), (1e6, 1e-2), (1e3, 1e3)):
        for _ in range(3):
            u, y, D, _ = _case(rng, pattern, su, sy)
            a = hb.BacklashSetEstimator(D).fit(u, y)
            b = hb.BacklashSetEstimator(D, method="algorithm").fit(u, y)
            scale = np.abs(a.gamma_bounds_).max(axis=1, keepdims=True)
            np.testing.assert_allclose(a.gamma_bounds_, b.gamma_bounds_, rtol=0,
                                       atol=1e-9 * scale.max())


# ----------------------------------------------------------------------------- hypothesis
@st.composite
def extremal_stage1_data(draw):
    """Steady-state data with extremal noise: (u, y, Delta, true gamma)."""
    M = draw(st.integers(2, 8))
    su, sy = draw(st.sampled_from(SCALE_PAIRS))
    drel = 10.0 ** draw(st.floats(-9.0, -2.0))
    pattern = draw(st.sampled_from(PATTERNS))
    seed = draw(st.integers(0, 2**32 - 1))
    return _case(np.random.default_rng(seed), pattern, su, sy, M=M, drel=drel)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(extremal_stage1_data())
def test_hypothesis_extremal_noise_both_methods(data):
    u, y, D, gamma = data
    for method in METHODS:
        est = hb.BacklashSetEstimator(D, method=method).fit(u, y)
        _assert_inside(est, gamma, method)


# ----------------------------------------------------------------------------- quantised data
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("scale", [2.0**-20, 1e-6, 1.0, 1e6, 2.0**20])
def test_quantised_data_half_step_bound(method, scale):
    """A quantised sensor: y = round(w / q) q, so |y - w| <= q/2 = Delta, often exactly.

    With slope 1, dead zone 1/2 and integer amplitudes the exact outputs are half-integers
    and every reading is off by exactly +-q/2 (round half to even alternates the sign);
    random amplitudes add ordinary quantisation errors."""
    q = scale
    rng = np.random.default_rng(3)
    # every error exactly +-Delta
    k = np.arange(1.0, 9.0)
    u = np.concatenate([k, -k]) * scale
    gamma = np.array([1.0, 0.5 * scale, 1.0, 0.5 * scale])
    w = np.where(u > 0, u - 0.5 * scale, u + 0.5 * scale)
    y = np.round(w / q) * q
    assert np.all(np.abs(np.abs(y - w) - q / 2) <= 1e-15 * np.abs(w))
    est = hb.BacklashSetEstimator(q / 2, method=method).fit(u, y)
    _assert_inside(est, gamma, "half-integers")
    # a random backlash on a 10-bit grid over the output range
    gamma = _truth(rng, scale, scale)
    u, w = _steady(rng, gamma, 12, scale)
    q = (np.max(w) - np.min(w)) / 2**10
    y = np.round(w / q) * q
    est = hb.BacklashSetEstimator(q / 2, method=method).fit(u, y)
    _assert_inside(est, gamma, "10-bit")


# ----------------------------------------------------------------------------- identifier
A_TRUE = np.array([1.0, -0.76, 0.82])
B_TRUE = np.array([0.0, 2.15, -1.09])  # unit DC gain: sum(B) = sum(A) = 1.06


@pytest.mark.parametrize("pattern", ["alternating", "random", "constant", "over"])
@pytest.mark.parametrize("su, sy", [(1e-3, 1e3), (1.0, 1.0), (1e3, 1e-3)])
def test_identifier_extremal_noise_both_stages(pattern, su, sy):
    """Square waves and a PRBS, both with noise at +-Delta, through the whole identifier
    (stage 2 by LP): the true backlash and linear block are inside every interval."""
    rng = np.random.default_rng(int(1e3 * su + sy) % 2**32 + len(pattern))
    gamma = _truth(rng, su, sy)
    u_ss, w_ss = _steady(rng, gamma, 5, su)
    D = 0.01 * sy
    y_ss = w_ss + _extremal(rng, pattern, 5, D)
    # PRBS +-u* between the dead zone and the largest square wave (Result 1)
    u_star = 0.9 * np.max(u_ss)
    N = 80
    u = u_star * rng.choice([-1.0, 1.0], N)
    ml, cl, mr, cr = gamma
    x = np.where(u > 0, mr * (u_star - cr), ml * (-u_star + cl))
    w = lfilter(B_TRUE, A_TRUE, x)
    signs = _signs(rng, pattern, N)
    factor = 1.0 + 1e-12 if pattern == "over" else 1.0
    y = w + factor * D * signs
    ident = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(D),
        hb.LinearEIVSetEstimator(output_bound=D, method="lp"),
    ).fit(u, y, steady_state=(u_ss, y_ss))
    theta = np.r_[A_TRUE[1:], B_TRUE[1:]]
    assert ident.contains(gamma, theta), (ident.gamma_bounds_, ident.theta_bounds_)


# ----------------------------------------------------------------------------- inner signal
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("pattern", ["alternating", "constant", "over"])
def test_inner_signal_bounds_contain_true_levels_at_the_boundary(method, pattern):
    """The inner PRBS levels (22.25)-(22.30) from sets built with noise at +-Delta."""
    rng = np.random.default_rng(11 + PATTERNS.index(pattern))
    for su, sy in ((1e-6, 1.0), (1.0, 1e6), (1e3, 1e-3)):
        for _ in range(5):
            u, y, D, gamma = _case(rng, pattern, su, sy)
            est = hb.BacklashSetEstimator(D, method=method).fit(u, y)
            u_star = 0.9 * np.max(u)
            ib = est.inner_signal_bounds(u_star)
            ml, cl, mr, cr = gamma
            x_hi, x_lo = mr * (u_star - cr), ml * (-u_star + cl)
            assert ib.x_hi[0] <= x_hi <= ib.x_hi[1] and ib.x_lo[0] <= x_lo <= ib.x_lo[1]


# ----------------------------------------------------------------------------- primitives
def test_farkas_certificate_exact():
    from fractions import Fraction

    from hammerbound.stage1.feasible_set import farkas_certificate

    # x <= 0, -x <= -1e-300 (x >= 1e-300), y <= 1: empty by the tiniest margin, exactly
    lam = farkas_certificate([(1.0, 0.0, 0.0), (-1.0, 0.0, -1e-300), (0.0, 1.0, 1.0)])
    assert lam is not None and all(x >= 0 for x in lam)
    # touching (x <= 0, x >= 0): a point, not empty
    assert farkas_certificate([(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 1.0)]) is None
    # three lines through one point, as in the +D, -D, +D repro: not empty
    assert farkas_certificate([(0.5, -1, Fraction(1, 3)), (-1.0, 1, Fraction(-2, 3)),
                               (2.0, -1, Fraction(4, 3))]) is None


def test_polygon_from_halfplanes_degenerate_sets_are_returned():
    from hammerbound.stage1.feasible_set import Constraint, polygon_from_halfplanes

    def box(x0, x1, y0, y1):
        return [Constraint((1.0, 0.0), x1, 0, "+"), Constraint((-1.0, 0.0), -x0, 0, "-"),
                Constraint((0.0, 1.0), y1, 1, "+"), Constraint((0.0, -1.0), -y0, 1, "-")]

    V, E = polygon_from_halfplanes(box(0.0, 1.0, 0.0, 2.0))
    assert len(V) == 4
    V, _ = polygon_from_halfplanes(box(0.5, 0.5, 0.0, 2.0))  # a segment
    assert 1 <= len(V) <= 2 and np.allclose(V[:, 0], 0.5)
    assert np.isclose(V[:, 1].min(), 0.0) and np.isclose(V[:, 1].max(), 2.0)
    V, _ = polygon_from_halfplanes(box(0.5, 0.5, 2.0, 2.0))  # a point
    assert np.allclose(V, [[0.5, 2.0]])
    assert polygon_from_halfplanes(box(0.5, 0.25, 0.0, 2.0)) is None  # empty


def test_intersection_of_nearly_parallel_lines_has_small_residuals():
    from hammerbound.stage1.feasible_set import Constraint, _intersect

    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(2000):
        t = rng.uniform(-1, 1)
        dt = 10.0 ** rng.uniform(-15, -1)
        c1 = Constraint((t, 1.0), rng.uniform(-1, 1), 0, "+")
        c2 = Constraint((t + dt, -1.0 if rng.random() < 0.5 else 1.0), rng.uniform(-1, 1), 1, "+")
        p = _intersect(c1, c2)
        if p is None:
            continue
        for c in (c1, c2):
            r = abs(c.a[0] * p[0] + c.a[1] * p[1] - c.b)
            worst = max(worst, r / ((abs(c.a[0]) + abs(c.a[1])) * np.abs(p).sum() + abs(c.b)))
    assert worst < 1e-15


@pytest.mark.parametrize("su, sy", [(1e-5, 1e-5), (0.1, 10.0), (1e4, 1e-4), (1e-3, 1e3)])
def test_constant_noise_many_amplitudes_pencils_of_lines(su, sy):
    """Noise +Delta on every sample of hundreds of random amplitudes: the lower bounds of
    all measurements pass through the truth (a pencil of ~300 nearly concurrent lines, many
    nearly parallel), the upper ones through a second point; the relaxed polygon has
    rounding-size structure there. Sound and not empty, at the policy's tolerance."""
    rng = np.random.default_rng(int(np.log10(su) * 10 + 100))
    for drel in (1e-9, 1e-6, 1e-3):
        gamma = _truth(rng, su, sy)
        M = 300
        amps = su * rng.uniform(0.4, 3.0, M)
        u = np.concatenate([amps, -amps])
        ml, cl, mr, cr = gamma
        w = np.where(u > 0, mr * (u - cr), ml * (u + cl))
        D = drel * sy
        est = hb.BacklashSetEstimator(D).fit(u, w + D)
        _assert_inside(est, gamma, (su, sy, drel))
