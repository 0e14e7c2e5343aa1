"""Issue 16: certified samples, frequency envelope, uncertainty weights, backlash inverse.

Every check here is against code the package did not produce: own simulations (numpy /
scipy.signal), own feasibility LP (``oracles.explains``), brute-force responses of
orthotope vertices and random points, and an own play-operator simulation.
"""

from __future__ import annotations

import itertools

import matplotlib
import numpy as np
import pytest
from oracles import A_TRUE, B_TRUE, eiv_data, explains, frequency_response, play
from scipy.optimize import minimize
from scipy.signal import lfilter

import hammerbound as hb
from hammerbound.exceptions import (
    DataValidationError,
    IllPosedBacklashError,
    ParameterValidationError,
    UnboundedSetError,
)
from hammerbound.modelset.frequency import denominators_stable
from hammerbound.modelset.uncertainty import certify_weight, deviation_bound, fit_weight
from hammerbound.modelset.zonotope import Zonotopes

matplotlib.use("Agg")

DX = 0.005


# ----------------------------------------------------------------------------- helpers
def box_points(bounds, n_random, seed=0):
    v = np.array(list(itertools.product(*bounds)))
    r = np.random.default_rng(seed).uniform(bounds[:, 0], bounds[:, 1], (n_random, len(bounds)))
    return v, r


def chapter_like_data(N=80, deta=0.05, seed=1):
    """Second-order chapter plant, PRBS input, noise exactly at +-deta (vertices of the box)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, N)
    g = B_TRUE.sum() / A_TRUE.sum()
    w = lfilter(B_TRUE / g, A_TRUE, x)
    # uniform noise, two samples exactly at +deta and -deta (more would pin the output-
    # error set down to nearly a point: the true trajectory touches the tube there)
    eta = rng.uniform(-deta, deta, N)
    eta[N // 3], eta[2 * N // 3] = deta, -deta
    return x, w + eta, np.concatenate([A_TRUE[1:], B_TRUE[1:] / g])


@pytest.fixture(scope="module")
def chapter_fit():
    x, y, theta = chapter_like_data()
    est = hb.LinearEIVSetEstimator(2, 2, output_bound=0.05, steady_state_gain=1.0,
                                   method="exact").fit(
        x, y, input_bound=DX)
    return est, x, y, theta


@pytest.fixture(scope="module")
def chapter_samples(chapter_fit):
    return chapter_fit[0].sample(40, random_state=0)


@pytest.fixture(scope="module")
def lric_fit(lric_record):
    u, y = lric_record          # ../shared/data/lric/ (skips when absent)
    est = hb.LinearEIVSetEstimator(1, 1, nk=0, output_bound=0.05, steady_state_gain=None,
                                   method="exact").fit(u, y, input_bound=0.05)
    return est, u, y


# ----------------------------------------------------------------------------- zonotopes
def test_zonotope_extremes_match_brute_force():
    rng = np.random.default_rng(3)
    for _ in range(12):
        k = rng.integers(1, 5)
        c = complex(*rng.normal(0, 1, 2))
        g = rng.normal(0, 0.6, k) + 1j * rng.normal(0, 0.6, k)
        Z = Zonotopes([c], g[None, :])
        corners = c + np.array([np.dot(s, g) for s in itertools.product([-1, 1], repeat=k)])
        assert Z.max_abs()[0] >= np.max(np.abs(corners))
        assert Z.max_abs()[0] <= np.max(np.abs(corners)) * (1 + 1e-9)
        # own convex QP for the distance from 0
        def f(s, c=c, g=g):
            return abs(c + np.dot(s, g)) ** 2
        best = min(minimize(f, s0, bounds=[(-1, 1)] * k, method="L-BFGS-B").fun
                   for s0 in rng.uniform(-1, 1, (3, k)))
        dist = np.sqrt(best)
        assert Z.min_abs()[0] <= dist + 1e-9
        assert Z.min_abs()[0] >= dist - 1e-4  # L-BFGS-B accuracy


def test_zonotope_degenerate_segment_containing_and_missing_zero():
    # real segments (w = 0 or Nyquist): [-1, 3] contains 0, [1, 3] does not
    assert Zonotopes([1.0], [[2.0]]).min_abs()[0] == 0.0
    assert Zonotopes([2.0], [[1.0]]).min_abs()[0] == pytest.approx(1.0, rel=1e-9)
    assert Zonotopes([2.0], np.zeros((1, 0))).min_abs()[0] == pytest.approx(2.0)


# ----------------------------------------------------------------------------- samples
def test_samples_are_feasible_by_an_independent_lp(chapter_fit, chapter_samples):
    est, x, y, _ = chapter_fit
    S = chapter_samples
    assert S.theta.shape == (40, 4)
    assert np.all(S.max_violation <= S.tol)
    assert np.unique(S.theta, axis=0).shape[0] == 40
    assert np.all(S.theta >= est.bounds_[:, 0]) and np.all(S.theta <= est.bounds_[:, 1])
    for th in S.theta:
        assert explains(eiv_data(y, x, DX, 0.05, 2, 2, steady_state_gain=1.0), th)


def test_sample_certificates_reproduce_the_equations(chapter_fit, chapter_samples):
    est, x, y, _ = chapter_fit
    S = chapter_samples
    assert np.all(np.abs(S.eta) <= 0.05)
    for th, eta, dxv in zip(S.theta, S.eta, S.dx, strict=True):
        a, b = th[:2], th[2:]
        w = y - eta
        xt = x - dxv
        assert np.all(np.abs(dxv) <= DX)
        res = w[2:] + a[0] * w[1:-1] + a[1] * w[:-2] - b[0] * xt[1:-1] - b[1] * xt[:-2]
        assert np.max(np.abs(res)) <= 1e-8


def test_sampler_spreads_over_the_set(chapter_fit, chapter_samples):
    est = chapter_fit[0]
    span = np.ptp(chapter_samples.theta, axis=0) / (2 * est.radius_)
    assert np.all(span > 0.5)


def test_samples_when_every_error_is_at_the_bound():
    """Noise exactly at +-deta everywhere: a thin set; samples stay certified."""
    rng = np.random.default_rng(9)
    x, y, theta = chapter_like_data(N=40, seed=9)
    g = B_TRUE.sum() / A_TRUE.sum()
    y = lfilter(B_TRUE / g, A_TRUE, x) + 0.05 * np.where(rng.random(40) < 0.5, 1.0, -1.0)
    est = hb.LinearEIVSetEstimator(2, 2, output_bound=0.05, steady_state_gain=1.0,
                                   method="exact").fit(x, y)
    S = est.sample(6, random_state=0)
    for th in S.theta:
        assert explains(eiv_data(y, x, 0.0, 0.05, 2, 2, steady_state_gain=1.0), th)
    w = np.linspace(0, np.pi, 256)
    assert np.all(est.frequency_response_bounds(w).contains(frequency_response(theta, w, 2, [1, 2])))


def test_infeasible_points_are_rejected_by_own_lp(chapter_fit):
    est, x, y, _ = chapter_fit
    out = est.bounds_[:, 1] + 0.05 * (est.bounds_[:, 1] - est.bounds_[:, 0]) + 1e-3
    assert not explains(eiv_data(y, x, DX, 0.05, 2, 2), out)


def test_to_transfer_functions(chapter_fit):
    import control

    tfs = chapter_fit[0].to_transfer_functions(3, dt=0.5, random_state=1)
    assert len(tfs) == 3 and all(isinstance(t, control.TransferFunction) for t in tfs)
    assert all(t.dt == 0.5 for t in tfs)


def test_sample_validates_n(chapter_fit):
    with pytest.raises(ParameterValidationError, match="integer >= 1"):
        chapter_fit[0].sample(0)


def test_lp_method_sampler_finds_a_seed():
    x, y, _ = chapter_like_data(N=60, seed=4)
    est = hb.LinearEIVSetEstimator(2, 2, output_bound=0.05, steady_state_gain=1.0,
                                   method="lp").fit(x, y)
    S = est.sample(5, random_state=0)
    for th in S.theta:
        assert explains(eiv_data(y, x, 0.0, 0.05, 2, 2, steady_state_gain=1.0), th)


# ----------------------------------------------------------------------------- envelope
def _check_envelope(est, omega, dt, samples, n_random=20000):
    env = est.frequency_response_bounds(omega, dt=dt)
    lags = est._b_lags()
    V, R = box_points(est.bounds_, n_random)
    GV = frequency_response(V, omega, est.na, lags, dt)
    GR = frequency_response(R, omega, est.na, lags, dt)
    GS = frequency_response(samples, omega, est.na, lags, dt)
    for G in (GV, GR, GS):
        assert np.all(env.contains(G))
    allG = np.vstack([GV, GR])
    emp = np.ptp(np.abs(allG), axis=0)
    ratio = (env.mag_upper - env.mag_lower) / emp
    assert np.all(ratio <= 1.5), ratio.max()
    return env, ratio


def test_envelope_contains_vertices_random_points_and_samples(chapter_fit, chapter_samples):
    est = chapter_fit[0]
    w = np.logspace(-3, np.log10(np.pi), 512)
    env, ratio = _check_envelope(est, w, 1.0, chapter_samples.theta)
    assert np.all(env.phase_bounded)
    # the true system (noise at the bounds) is inside
    assert np.all(env.contains(frequency_response(chapter_fit[3], w, 2, [1, 2])))


def test_envelope_rejects_responses_outside(chapter_fit):
    est = chapter_fit[0]
    w = np.linspace(0.05, 3.0, 64)
    env = est.frequency_response_bounds(w)
    assert not env.contains(env.central * (env.mag_upper / env.mag_central) * 1.001).any()
    assert not env.contains(env.central * (env.mag_lower / env.mag_central) * 0.999).any()
    rot = np.exp(1j * (env.phase_upper - env.phase_central + 1e-3))
    assert not env.contains(env.central * rot).any()
    assert env.contains(env.central).all()


def test_envelope_on_the_gain_plane(chapter_fit, chapter_samples):
    est = chapter_fit[0]
    w = np.logspace(-3, np.log10(np.pi), 256)
    env0 = est.frequency_response_bounds(w)
    env = est.frequency_response_bounds(w, on_gain_plane=True)
    # own points of the box on the gain plane B(1) = A(1)
    rng = np.random.default_rng(11)
    P = rng.uniform(est.bounds_[:, 0], est.bounds_[:, 1], (60000, 4))
    row = np.array([-1.0, -1.0, 1.0, 1.0])
    P += np.outer((1.0 - P @ row) / (row @ row), row)
    P = P[np.all((P >= est.bounds_[:, 0]) & (P <= est.bounds_[:, 1]), axis=1)]
    assert len(P) > 1000
    for T in (P, chapter_samples.theta):
        G = frequency_response(T, w, 2, [1, 2])
        assert np.all(env.contains(G))
    assert np.all(env.mag_upper - env.mag_lower <= env0.mag_upper - env0.mag_lower)
    low = w < 0.1
    assert np.all((env.mag_upper - env.mag_lower)[low] < 0.5 * (env0.mag_upper - env0.mag_lower)[low])
    wk = rng.uniform(w[0], w[-1], 1000)
    k = np.searchsorted(w, wk) - 1
    Gk = np.abs(frequency_response(P[:500], wk, 2, [1, 2]))
    assert np.all(Gk <= env.mag_upper_between[k]) and np.all(Gk >= env.mag_lower_between[k])
    with pytest.raises(ParameterValidationError, match="gain constraint"):
        hb.LinearEIVSetEstimator(2, 2, output_bound=0.05, steady_state_gain=None,
                                 method="lp").fit(
            *chapter_like_data(N=40)[:2]).frequency_response_bounds(on_gain_plane=True)


def test_envelope_between_grid_frequencies(chapter_fit):
    est = chapter_fit[0]
    w = np.linspace(0, np.pi, 64)
    env = est.frequency_response_bounds(w)
    rng = np.random.default_rng(5)
    wk = rng.uniform(0, np.pi, 3000)
    k = np.searchsorted(w, wk) - 1
    V, R = box_points(est.bounds_, 300)
    G = frequency_response(np.vstack([V, R]), wk, 2, [1, 2])
    mag = np.abs(G)
    assert np.all(mag <= env.mag_upper_between[k]) and np.all(mag >= env.mag_lower_between[k])
    ph0 = np.interp(wk, w, env.phase_central)
    g0 = frequency_response(est.center_, wk, 2, [1, 2])[0]
    ph = ph0 + np.angle(G / g0)
    ok = np.isfinite(env.phase_lower_between[k])
    assert ok.mean() > 0.9
    assert np.all((ph <= env.phase_upper_between[k] + 1e-12)[:, ok])
    assert np.all((ph >= env.phase_lower_between[k] - 1e-12)[:, ok])
    ref = env.refine(rtol=0.01)
    assert ref.omega.size > w.size
    up = np.maximum(ref.mag_upper[:-1], ref.mag_upper[1:])
    assert np.all(ref.mag_upper_between <= up * 1.01 + 1e-12)


@pytest.mark.deep
def test_envelope_on_lric_data(lric_fit):
    est = lric_fit[0]
    S = est.sample(25, random_state=0)
    for th in S.theta[:10]:
        assert explains(eiv_data(lric_fit[2], lric_fit[1], 0.05, 0.05, 1, 1, nk=0), th)
    w = np.logspace(-2, np.log10(np.pi / 0.1), 512)
    _check_envelope(est, w, 0.1, S.theta)


def test_envelope_unbounded_when_a_box_contains_a_zero_on_the_circle():
    from hammerbound.modelset.frequency import frequency_envelope

    env = frequency_envelope(np.array([[-1.2, -0.8], [1.0, 1.0]]), 1, [1], np.array([0.0, 1.0]))
    assert np.isinf(env.mag_upper[0]) and not env.phase_bounded[0]
    assert np.isfinite(env.mag_upper[1])


def test_omega_validation(chapter_fit):
    with pytest.raises(DataValidationError, match="strictly increasing"):
        chapter_fit[0].frequency_response_bounds([1.0, 0.5])
    with pytest.raises(DataValidationError, match=">= 0"):
        chapter_fit[0].frequency_response_bounds([-1.0])
    with pytest.raises(ParameterValidationError, match="dt"):
        chapter_fit[0].frequency_response_bounds(dt=0)


def test_denominators_stable_matches_the_stability_triangle():
    rng = np.random.default_rng(0)
    for _ in range(40):
        c = rng.uniform(-1.8, 1.8), rng.uniform(-0.95, 0.95)
        r = rng.uniform(0, 0.3, 2)
        box = np.array([[c[0] - r[0], c[0] + r[0]], [c[1] - r[1], c[1] + r[1]]])
        corners = list(itertools.product(*box))
        truth = all(abs(a2) < 1 and abs(a1) < 1 + a2 for a1, a2 in corners)
        got = denominators_stable(box)
        assert not (got and not truth)  # never certifies an unstable member
        if truth and min(1 - abs(a2) for _, a2 in corners) > 0.05 and \
                min(1 + a2 - abs(a1) for a1, a2 in corners) > 0.05:
            assert got


# ----------------------------------------------------------------------------- weights
@pytest.fixture(scope="module")
def weights(chapter_fit):
    est = chapter_fit[0]
    return {k: est.uncertainty_weight(k, order=2) for k in ("multiplicative", "additive")}


@pytest.mark.parametrize("kind", ["multiplicative", "additive"])
def test_weight_bounds_vertices_and_samples(chapter_fit, chapter_samples, weights, kind):
    est = chapter_fit[0]
    uw = weights[kind]
    W = uw.W
    assert np.all(np.abs(W.poles()) < 1) and np.all(np.abs(W.zeros()) < 1)
    assert uw.certificate.holds and uw.certificate.min_ratio >= 1
    rng = np.random.default_rng(2)
    w = np.sort(np.concatenate([np.linspace(0, np.pi, 2048), rng.uniform(0, np.pi, 2048)]))
    V, R = box_points(est.bounds_, 3000)
    G = frequency_response(np.vstack([V, R, chapter_samples.theta]), w, 2, [1, 2])
    G0 = frequency_response(est.center_, w, 2, [1, 2])[0]
    dev = np.abs(G / G0 - 1) if kind == "multiplicative" else np.abs(G - G0)
    Wm = np.abs(W(np.exp(1j * w)))
    assert np.all(dev <= Wm)
    # tightness: the exact per-frequency bound is attained up to the random sampling
    exact = deviation_bound(est.bounds_, 2, [1, 2], w, kind=kind)
    assert np.all(dev.max(axis=0) <= exact)
    assert np.median(Wm / exact) < 1.5


@pytest.mark.deep
def test_weight_on_lric_data(lric_fit):
    est, u, y = lric_fit
    uw = est.uncertainty_weight(dt=0.1)
    assert uw.W.dt == 0.1
    w = np.linspace(0, np.pi / 0.1, 2000)
    V, R = box_points(est.bounds_, 2000)
    G = frequency_response(np.vstack([V, R]), w, 1, [0, 1], dt=0.1)
    G0 = frequency_response(est.center_, w, 1, [0, 1], dt=0.1)[0]
    assert np.all(np.abs(G / G0 - 1) <= np.abs(uw.W(np.exp(1j * w * 0.1))))


def test_a_weight_that_is_too_small_is_not_certified(chapter_fit, weights):
    est = chapter_fit[0]
    small = weights["multiplicative"].W * 0.9
    cert = certify_weight(small, est.bounds_, 2, [1, 2])
    assert not cert.holds and cert.min_ratio < 1


def test_weight_parameters_are_validated(chapter_fit):
    est = chapter_fit[0]
    with pytest.raises(ParameterValidationError, match="n_grid"):
        est.uncertainty_weight(n_grid=1)
    with pytest.raises(ParameterValidationError, match="margin"):
        est.uncertainty_weight(margin="big")
    with pytest.raises(ParameterValidationError, match="order"):
        est.uncertainty_weight(order=-1)
    with pytest.raises(ParameterValidationError, match="kind"):
        est.uncertainty_weight("relative")


def test_unbounded_weight_raises():
    import control

    with pytest.raises(UnboundedSetError, match="vanishes on"):
        fit_weight(np.array([[-1.2, -0.8], [1.0, 1.0]]), 1, [1], control.tf([1], [1, 0], 1.0))


def test_robust_stability_check_covers_the_box(chapter_fit, weights):
    """||W T|| < 1 (python-control) => every plant of the box is stabilised (checked)."""
    import control

    est = chapter_fit[0]
    uw = weights["multiplicative"]
    C = control.tf([0.05, 0], [1, -1], 1.0)
    T = control.feedback(uw.central * C, 1)
    assert np.all(np.abs(T.poles()) < 1)
    peak = control.norm(uw.W * T, p="inf")
    w = np.linspace(0, np.pi, 8000)
    assert peak == pytest.approx(np.max(np.abs((uw.W * T)(np.exp(1j * w)))), rel=1e-3)
    assert peak < 1
    assert denominators_stable(est.bounds_[:2])
    V, R = box_points(est.bounds_, 200)
    for th in np.vstack([V, R]):
        A = np.concatenate([[1.0], th[:2]])
        B = np.concatenate([[0.0], th[2:]])
        # closed loop 1 + G C = 0  <=>  A (z - 1) z^2 + 0.05 z B(z) z = 0 in powers of z
        Az, Bz = np.polymul(A, [1.0, -1.0]), 0.05 * np.concatenate([B, [0.0]])
        assert np.max(np.abs(np.roots(np.polyadd(Az, Bz)))) < 1


# ----------------------------------------------------------------------------- backlash
@pytest.fixture(scope="module")
def stage1():
    ex = hb.chapter_example(0.05, N=30, random_state=0)
    est = hb.BacklashSetEstimator(0.05).fit(ex.steady.u, ex.steady.y)
    return est, ex


def test_backlash_samples_explain_the_data(stage1):
    est, ex = stage1
    S = est.sample(500, random_state=0)
    u, y = ex.steady.u, ex.steady.y
    for ml, cl, mr, cr in S.gamma:
        pred = np.where(u > 0, mr * (u - cr), ml * (u + cl))
        assert np.all(np.abs(y - pred) <= 0.05 * (1 + 1e-9))
    assert np.all(S.gamma >= est.gamma_bounds_[:, 0] - 1e-12)
    assert np.all(S.gamma <= est.gamma_bounds_[:, 1] + 1e-12)
    # spread: every interval is covered to a large extent
    assert np.all(np.ptp(S.gamma, axis=0) > 0.6 * np.diff(est.gamma_bounds_, axis=1)[:, 0])


def test_inverse_cancels_the_central_backlash(stage1):
    est, _ = stage1
    inv = est.inverse()
    v = np.concatenate([np.linspace(0, inv.v_range[1], 50), np.linspace(inv.v_range[1], inv.v_range[0], 80)])
    u = inv.compensate(v)
    x = play(u, *inv.gamma, x0=0.0)
    np.testing.assert_allclose(x, v, atol=1e-12)


def test_inverse_error_bound_holds_for_backlash_samples(stage1):
    est, _ = stage1
    inv = est.inverse()
    rng = np.random.default_rng(7)
    lo_v, hi_v = inv.v_range
    # dense command sequence: random walk with reversals, plateaus and large jumps
    steps = rng.normal(0, 0.02 * (hi_v - lo_v), 1500)
    steps[rng.random(1500) < 0.1] = 0.0
    v = np.clip(np.cumsum(steps), lo_v, hi_v)
    v[700:720] = np.linspace(lo_v, hi_v, 20)
    u = inv.compensate(v)
    lo, hi = inv.error_bounds(v)
    S = est.sample(150, random_state=1)
    worst = 0.0
    for g in S.gamma:
        e = play(u, *g, x0=0.0) - v
        assert np.all(e >= lo) and np.all(e <= hi)
        worst = max(worst, np.max(np.abs(e)))
    # the band is tight: a vertex backlash on a rising ramp attains its end
    assert worst > 0.3 * np.max(inv.error_bound(v))


def test_inverse_branch_band_is_attained_at_polygon_vertices(stage1):
    est, _ = stage1
    inv = est.inverse()
    v = np.linspace(0.0, inv.v_range[1], 200)
    u = inv.compensate(v)  # monotone rise from rest
    b = inv.branch_errors(v)
    errs = []
    for mb_r in est.right_.vertices_mb:
        for mb_l in est.left_.vertices_mb[:3]:
            g = (mb_l[0], mb_l[1] / mb_l[0], mb_r[0], mb_r[1] / mb_r[0])
            errs.append(play(u, *g, x0=0.0)[-1] - v[-1])
    assert max(errs) == pytest.approx(b["rise"][1][-1], rel=1e-6, abs=1e-9)
    assert min(errs) == pytest.approx(b["rise"][0][-1], rel=1e-6, abs=1e-9)


def test_the_compensator_steps_through_a_control_loop(stage1):
    """One command at a time, each computed from the measured inner signal (an integral
    loop around the tests' own play operator): the stateful compensator emits what
    compensate() emits for the whole sequence, and the guaranteed band holds for every
    sampled backlash (trial 7: calling compensate() per sample restarted from x0)."""
    est, _ = stage1
    inv = est.inverse()
    lo_v, hi_v = inv.v_range
    ref = 0.8 * hi_v * np.sign(np.sin(np.linspace(0, 12, 400)))  # set-point square wave
    for g in est.sample(40, random_state=3).gamma:
        c = inv.compensator()
        v, u, x = [], [], [0.0]
        vt = 0.0
        for r in ref:
            vt = float(np.clip(vt + 0.3 * (r - x[-1]), lo_v, hi_v))
            u.append(c.step(vt))
            v.append(vt)
            x.append(float(play(np.array(u), *g, x0=0.0)[-1]))
        v, u, x = np.array(v), np.array(u), np.array(x[1:])
        np.testing.assert_array_equal(u, inv.compensate(v))
        lo, hi = inv.error_bounds(v)
        assert np.all(x - v >= lo) and np.all(x - v <= hi)
    c.reset()
    assert (c.v_prev, c.u) == (inv.x0, inv.u_init)
    # the advice names the way that always works (trial 10: "a wider range" alone led to
    # IllPosedBacklashError)
    with pytest.raises(DataValidationError, match=r"command range.*saturate the command.*"
                                                  r"np\.clip\(v, \*inverse\.v_range\)"):
        c.step(hi_v * 2 + 1)
    with pytest.raises(DataValidationError, match="finite number"):
        c.step(float("nan"))


def test_compensate_warns_when_given_one_number(stage1):
    from hammerbound.exceptions import DataWarning

    inv = stage1[0].inverse()
    with pytest.warns(DataWarning, match="compensator"):
        inv.compensate(0.1)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        inv.compensate([0.1])  # a sequence of one command: as asked


def test_inverse_validation(stage1):
    est, _ = stage1
    inv = est.inverse()
    with pytest.raises(DataValidationError, match="command range"):
        inv.compensate([inv.v_range[1] * 2 + 1])
    with pytest.raises(IllPosedBacklashError, match="Narrow v_range"):
        est.inverse(v_range=(-50.0, 50.0))
    with pytest.raises(ParameterValidationError, match="v_min < v_max"):
        est.inverse(v_range=(1.0, 0.0))
    lo, hi = inv.error_bounds([0.1], initial_error=(-0.2, 0.3))
    assert lo[0] <= -0.2 and hi[0] >= 0.3


@pytest.mark.deep
def test_identifier_delegates_and_figures(stage1, tmp_path):
    import matplotlib.pyplot as plt

    _, ex = stage1
    idf = hb.HammersteinBacklashIdentifier(
        hb.BacklashSetEstimator(0.05),
        hb.LinearEIVSetEstimator(output_bound=0.05, method="exact"),
    ).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    gs, ts = idf.sample(5, random_state=0)
    assert gs.gamma.shape == (5, 4) and ts.theta.shape == (5, 4)
    env = idf.frequency_response_bounds(np.logspace(-2, np.log10(np.pi), 50))
    fig = env.plot(samples=frequency_response(ts.theta, env.omega, 2, [1, 2]))
    fig.savefig(tmp_path / "bode.png")
    inv = idf.inverse()
    fig2 = inv.plot(samples=gs.gamma)
    fig2.savefig(tmp_path / "comp.png")
    plt.close("all")
    assert (tmp_path / "bode.png").stat().st_size > 0


def test_inverse_summary_rounds_its_guaranteed_band_outward(stage1):
    """The summary's "guaranteed residual x - v in [lo, hi]" was printed with ``.4g``,
    which may round either end inward (a narrower band than the one guaranteed)."""
    import re

    inv = stage1[0].inverse()
    v = np.linspace(inv.v_range[0], inv.v_range[1], 201)
    lo, hi = inv.error_bounds(v)
    shown = re.search(r"guaranteed residual x - v in \[(\S+), (\S+)\]", inv.summary())
    a, b = (float(t) for t in shown.groups())
    assert a <= lo.min() and b >= hi.max()  # never inside the band
    assert np.isclose(a, lo.min(), rtol=1e-3) and np.isclose(b, hi.max(), rtol=1e-3)


def test_inverse_plot_colours_the_lines_as_the_other_figures(stage1):
    """Trial 15: the inverse's figure drew the left line in C1 and the right in C0, the
    report's characteristic the other way round."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_rgb

    fig = stage1[0].inverse().plot()
    bands = {c.get_label(): to_rgb(c.get_facecolor()[0]) for c in fig.axes[0].collections}
    assert bands["left line, feasible band"] == to_rgb("C0")
    assert bands["right line, feasible band"] == to_rgb("C1")
    plt.close(fig)


def test_results_have_a_one_line_repr(stage1):
    """Trial 16: the repr of an UncertaintyWeight printed thousands of numbers (the
    dataclass default); results now show arrays by shape, on one line."""
    from hammerbound.results import OutputEnvelope

    inv = stage1[0].inverse()
    env = OutputEnvelope(np.zeros(500), np.ones(500), np.full(500, 0.5), 0.1)
    for result in (inv, env):
        text = repr(result)
        assert "\n" not in text and len(text) < 600 and "<array" in text, text
        assert text.startswith(type(result).__name__ + "(")
