"""Stage 1 at every scale (issue 19): the polygon's orthotope against an independent LP.

Noise strictly inside its bound (uniform in +-0.999 Delta) must never give "empty", and
the orthotope of the relaxed polygon must be what scipy's ``linprog`` finds on the same
(relaxed) constraints -- to a relative 1e-9 -- and contain what it finds on the measured
constraints without the tolerance. The LPs are solved in their own centred and scaled
variables (least-squares centre, widths of order Delta), rows divided by their bounds, so
HiGHS's tolerances sit far below the set's size: ``m`` bounds are plain LPs, ``c = beta/m``
bounds are linear-fractional programs solved through the Charnes-Cooper substitution
``(c, tau = 1/m)``: ``a_0 m + a_1 beta <= b  <=>  a_0 + a_1 c <= b tau``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

import hammerbound as hb
from hammerbound.exceptions import UnboundedSetError

# random slopes: some truths' lines cross inside the tested inputs (warned, trial 19)
pytestmark = pytest.mark.filterwarnings(
    "ignore:the steady-state points reach u:hammerbound.exceptions.DataWarning")

HIGHS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


def _data(rng, M, drel, scale=1.0):
    """Issue-19-like data: slopes ~1.6, amplitudes 0.25..2.5 (times ``scale``)."""
    ml, mr = rng.uniform(1.55, 1.7, 2)
    cl, cr = rng.uniform(0.01, 0.2, 2) * scale
    amps = scale * np.sort(rng.uniform(0.25, 2.5, M))
    amps[:2] = scale * np.array([0.25, 2.5])  # M = 2: two distinct amplitudes
    u = np.concatenate([amps, -amps])
    w = np.where(u > 0, mr * (u - cr), ml * (u + cl))
    D = drel * 1.6 * scale  # relative to the output signal
    return u, w + rng.uniform(-0.999 * D, 0.999 * D, u.size), D, np.array([ml, cl, mr, cr])


def _side_rows(fs, relaxed=True):
    """Data constraints ``a . (m, beta) <= b`` of a fitted side, with or without the tolerance."""
    rows = [c for c in fs.constraints if c.index is not None]
    A = np.array([c.a for c in rows], dtype=float)
    b = np.array([c.b - (0.0 if relaxed else c.slack) for c in rows], dtype=float)
    s = np.array([c.slack for c in rows], dtype=float)
    return A, b, s


def _lp_bounds(fs, D, relaxed=True):
    """``[[m_min, m_max], [c_min, c_max]]`` (m_min may be 0 with c unbounded) by LP."""
    A, b, slack = _side_rows(fs, relaxed)
    u = A[:, 0]
    # an independent centre: least squares of the bounds' midpoints is the data itself
    x_hat, *_ = np.linalg.lstsq(A[::2], 0.5 * (b[::2] - b[1::2]), rcond=None)
    m_hat, b_hat = x_hat
    du = np.ptp(np.abs(u))
    sm = D / du
    sb = D + sm * np.max(np.abs(u))
    w = D + slack  # row scale
    # m and beta: plain LPs in xi = ((m, beta) - x_hat) / (sm, sb)
    Ax = np.column_stack([A[:, 0] * sm, A[:, 1] * sb]) / w[:, None]
    bx = (b - A @ np.array([m_hat, b_hat])) / w
    bnd = [(-m_hat / sm, None), (-b_hat / sb, None)]  # m >= 0, beta >= 0
    mb = np.zeros((2, 2))
    for k, (hat, scl) in enumerate(((m_hat, sm), (b_hat, sb))):
        for j, sgn in ((0, 1.0), (1, -1.0)):
            cost = [0.0, 0.0]
            cost[k] = sgn
            r = linprog(cost, A_ub=Ax, b_ub=bx, bounds=bnd, method="highs", options=HIGHS)
            assert r.status == 0, r.message
            mb[k, j] = hat + scl * r.x[k]
    out = np.zeros((2, 2))
    out[0] = mb[0]
    (m_lo, m_hi), (b_lo, b_hi) = mb
    if m_lo <= 1e-9 * m_hi:
        out[1] = (0.0, np.inf)
        return out
    # c: Charnes-Cooper in (c, tau = 1/m), centred and scaled by the box of the m, beta LPs
    c_hat, t_hat = 0.5 * (b_lo / m_hi + b_hi / m_lo), 0.5 * (1 / m_hi + 1 / m_lo)
    sc = b_hi / m_lo - b_lo / m_hi + 1e-300
    st = 1 / m_lo - 1 / m_hi + 1e-300
    wc = w * t_hat
    Ac = np.column_stack([A[:, 1] * sc, -b * st]) / wc[:, None]
    bc = (-A[:, 0] - A[:, 1] * c_hat + b * t_hat) / wc
    bnd = [(-c_hat / sc, None), (-t_hat / st, None)]  # c >= 0, tau >= 0
    for j, sgn in ((0, 1.0), (1, -1.0)):
        r = linprog([sgn, 0.0], A_ub=Ac, b_ub=bc, bounds=bnd, method="highs", options=HIGHS)
        assert r.status == 0, r.message
        out[1, j] = c_hat + sc * r.x[0]
    return out


def _check_side(fs, D, gamma_side):
    assert fs.tolerance_factor == 1.0
    poly = fs.orthotope
    lp = _lp_bounds(fs, D, relaxed=True)
    exact = _lp_bounds(fs, D, relaxed=False)
    # same constraints: the same orthotope, to a relative 1e-9 (plus LP accuracy on widths)
    width = np.maximum(lp[:, 1] - lp[:, 0], 0.0)
    tol = 1e-9 * np.abs(lp) + 1e-6 * width[:, None]
    np.testing.assert_array_less(np.abs(poly - lp), tol + 1e-300)
    # the tolerance only ever widens: the measured set's orthotope is inside ...
    assert np.all(poly[:, 0] <= exact[:, 0] + 1e-6 * width)
    assert np.all(poly[:, 1] >= exact[:, 1] - 1e-6 * width)
    # ... and by less than 1e-9 of the parameters' scales (ARITHMETIC_RTOL = 1e-11 of the
    # terms): m relative to itself, the dead zone c relative to the input amplitudes (c is
    # a small difference of large terms when c << u, and the data's own rounding is
    # eps |u| there)
    u_max = max(abs(c.a[0]) for c in fs.constraints)
    scale = np.array([[np.abs(exact[0]).max()], [u_max]])
    finite = np.isfinite(exact)
    np.testing.assert_array_less(np.abs(poly - exact)[finite],
                                 (1e-9 * scale + 1e-6 * width[:, None] + 0 * exact)[finite]
                                 + 1e-300)
    # and the truth is inside
    assert poly[0, 0] <= gamma_side[0] <= poly[0, 1]
    assert poly[1, 0] <= gamma_side[1] <= poly[1, 1]


@pytest.mark.parametrize("drel", [1e-9, 1e-6, 1e-3, 1e-1, 1.0, 1e2])
@pytest.mark.parametrize("M", [2, 10, 500])
def test_orthotope_matches_independent_lp(M, drel):
    rng = np.random.default_rng(M + int(-np.log10(drel) * 7 + 100))
    for scale in (1e-6, 1.0, 1e6):
        u, y, D, gamma = _data(rng, M, drel, scale)
        try:
            est = hb.BacklashSetEstimator(D).fit(u, y)
        except UnboundedSetError:
            # only when the data really let m reach 0 (large noise): the LP agrees
            assert drel >= 1.0
            continue
        for fs, g in ((est.left_, gamma[:2]), (est.right_, gamma[2:])):
            _check_side(fs, D, g)


def test_issue19_repro_fine_scale_both_methods():
    """500 amplitudes, slopes ~1.6, uniform noise in +-0.999 Delta, Delta = 1e-6."""
    for seed in (1, 5, 8):  # seeds where the old construction declared a side empty
        rng = np.random.default_rng(seed)
        a = np.sort(rng.uniform(0.1, 5.0, 500))
        u = np.concatenate([a, -a])
        ml, mr = rng.uniform(1.5, 1.7, 2)
        cl, cr = rng.uniform(0.01, 0.3, 2)
        D = 1e-6
        w = np.where(u > 0, mr * (u - cr), ml * (u + cl))
        y = w + rng.uniform(-0.999 * D, 0.999 * D, u.size)
        gamma = np.array([ml, cl, mr, cr])
        for method in ("polygon", "algorithm"):
            est = hb.BacklashSetEstimator(D, method=method).fit(u, y)
            gb = est.gamma_bounds_
            assert np.all(gb[:, 0] <= gamma) and np.all(gamma <= gb[:, 1])
        for fs, g in ((est.left_, gamma[:2]), (est.right_, gamma[2:])):
            _check_side(fs, D, g)


@pytest.mark.deep
def test_orthotope_matches_lp_with_1e5_amplitudes():
    rng = np.random.default_rng(2)
    u, y, D, gamma = _data(rng, 100_000, 1e-6)
    est = hb.BacklashSetEstimator(D).fit(u, y)
    for fs, g in ((est.left_, gamma[:2]), (est.right_, gamma[2:])):
        _check_side(fs, D, g)
