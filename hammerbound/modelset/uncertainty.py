"""Uncertainty weights of the identified set for robust design, with their proof.

For every ``theta`` in the orthotope and every frequency,

* multiplicative: ``|G(e^{jw}) / G0(e^{jw}) - 1| <= |W(e^{jw})|``;
* additive: ``|G(e^{jw}) - G0(e^{jw})| <= |W(e^{jw})|``,

with ``G0`` the central model and ``W`` a low-order, stable, minimum-phase discrete
``control.TransferFunction``.

**The bound at one frequency is exact.** With ``a = A(e^{jw})`` in the zonotope ``Z_A``
and ``b = B(e^{jw})`` in ``Z_B`` (independent, see :mod:`.frequency`),
``|G - G0| = |b - G0 a| / |a|``. For fixed ``a`` it is convex in ``b``, so its maximum is
at a vertex of ``Z_B``; for fixed ``b`` the function ``a -> b/a - G0`` is holomorphic on
the convex set ``Z_A`` (0 outside it), so by the maximum-modulus principle its maximum is
on the boundary of ``Z_A``. On an edge ``a(t) = p + t d`` the squared ratio is a quotient
of two quadratics in ``t``, whose stationary points solve a *quadratic* equation: the
supremum is the largest value over the vertices of ``Z_B``, the edges of ``Z_A``, their
end points and those roots, in closed form (:func:`deviation_bound`). It is widened by a
relative ``1e-9`` for rounding.

**Between frequencies.** On ``[w_k, w_k+1]`` every ``|G/G0 - 1|`` (and ``|G - G0|``) is
``K``-Lipschitz with ``K`` built from ``max |Z_B|``, ``min |Z_A|``, ``|A0|``, ``|B0|`` over the
interval and the Lipschitz constants ``L_A``, ``L_B`` of :mod:`.frequency`; so is their
supremum ``delta``. Hence ``delta <= (delta_k + delta_k+1)/2 + K h / 2`` on the interval,
and likewise ``|W| >= (|W_k| + |W_k+1|)/2 - L_W h / 2``. :func:`certify_weight` checks the
second above the first on *every* interval of a uniform grid of ``[0, pi/dt]`` (which
covers all frequencies: the coefficients are real, so ``|.|`` is even and
``2 pi / dt``-periodic in ``w``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import expit

from ..exceptions import ParameterValidationError, UnboundedSetError
from .frequency import _lipschitz
from .zonotope import value_sets

__all__ = ["KINDS", "UncertaintyWeight", "WeightCertificate", "certify_weight",
           "deviation_bound", "fit_weight"]

KINDS = ("multiplicative", "additive")
_RTOL = 1e-9


def _split(bounds, na):
    bounds = np.asarray(bounds, dtype=float)
    a_lo = np.concatenate([[1.0], bounds[:na, 0]])
    a_hi = np.concatenate([[1.0], bounds[:na, 1]])
    return a_lo, a_hi, bounds[na:, 0], bounds[na:, 1]


def deviation_bound(bounds, na, b_lags, omega, dt=1.0, kind="multiplicative"):
    """Exact ``sup |G/G0 - 1|`` (or ``sup |G - G0|``) over the box at each frequency.

    Returns an array of shape (n,), ``inf`` where some ``A`` in the box vanishes.
    """
    if kind not in KINDS:
        raise ParameterValidationError(f"kind must be one of {KINDS}; got {kind!r}.")
    a_lo, a_hi, b_lo, b_hi = _split(bounds, na)
    wd = np.asarray(omega, dtype=float) * dt
    ZA = value_sets(a_lo, a_hi, np.arange(na + 1), wd)
    ZB = value_sets(b_lo, b_hi, np.asarray(b_lags), wd)
    with np.errstate(divide="ignore", invalid="ignore"):
        G0 = ZB.centre / ZA.centre
    amin = ZA.min_abs()
    vb = ZB.vertices()  # (n, nvb)
    va = ZA.vertices()  # (n, nva), CCW; edges va[k] -> va[k+1]
    p = va[:, None, :]
    d = (np.roll(va, -1, axis=1) - va)[:, None, :]
    q = vb[:, :, None] - G0[:, None, None] * p  # b - G0 a(0)
    s = G0[:, None, None] * d                   # N(t) = |q - t s|^2
    n0, n1, n2 = np.abs(q) ** 2, -2 * (q * s.conj()).real, np.abs(s) ** 2
    d0, d1, d2 = np.abs(p) ** 2, 2 * (p * d.conj()).real, np.abs(d) ** 2
    c2 = n2 * d1 - n1 * d2
    c1 = 2 * (n2 * d0 - n0 * d2)
    c0 = n1 * d0 - n0 * d1
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        disc = np.sqrt(np.maximum(c1 * c1 - 4 * c2 * c0, 0.0))
        qq = -0.5 * (c1 + np.where(c1 >= 0, 1.0, -1.0) * disc)
        t1 = np.where(c2 != 0, qq / np.where(c2 != 0, c2, 1.0), -1.0)
        t2 = np.where(qq != 0, c0 / np.where(qq != 0, qq, 1.0), -1.0)
    cands = [np.zeros_like(n0), np.ones_like(n0), t1, t2] + [
        np.full_like(n0, f) for f in np.linspace(0.125, 0.875, 7)]  # safety net only
    best = np.zeros(n0.shape[0])
    for t in cands:
        t = np.where(np.isfinite(t), np.clip(t, 0.0, 1.0), 0.0)
        num = n0 + t * (n1 + t * n2)
        den = d0 + t * (d1 + t * d2)
        with np.errstate(invalid="ignore", divide="ignore"):
            r = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.inf)
        best = np.maximum(best, np.max(r.reshape(r.shape[0], -1), axis=1))
    dev = np.sqrt(np.maximum(best, 0.0))
    if kind == "multiplicative":
        with np.errstate(divide="ignore", invalid="ignore"):
            dev = dev / np.abs(G0)
    dev = dev * (1 + _RTOL) + _RTOL * 1e-3
    return np.where(amin > 0, dev, np.inf)


def _between(bounds, na, b_lags, omega, dt, kind, dev):
    """Upper bound of the deviation on each interval [omega_k, omega_k+1] (Lipschitz)."""
    a_lo, a_hi, b_lo, b_hi = _split(bounds, na)
    w = np.asarray(omega, dtype=float)
    wd = w * dt
    a_lags, b_lags = np.arange(na + 1), np.asarray(b_lags)
    ZA = value_sets(a_lo, a_hi, a_lags, wd)
    ZB = value_sets(b_lo, b_hi, b_lags, wd)
    LA, LB = _lipschitz(a_lo, a_hi, a_lags, dt), _lipschitz(b_lo, b_hi, b_lags, dt)
    h = np.diff(w)

    def up(x, L):
        return 0.5 * (x[:-1] + x[1:]) + 0.5 * L * h

    def down(x, L):
        return np.maximum(0.5 * (x[:-1] + x[1:]) - 0.5 * L * h, 0.0)

    amin, amax, bmax = down(ZA.min_abs(), LA), up(ZA.max_abs(), LA), up(ZB.max_abs(), LB)
    a0, b0 = np.abs(ZA.centre), np.abs(ZB.centre)
    with np.errstate(divide="ignore", invalid="ignore"):
        if kind == "multiplicative":
            a0max, b0max, b0min = up(a0, LA), up(b0, LB), down(b0, LB)
            den = amin * b0min
            K = (LB * a0max + bmax * LA) / den + bmax * a0max * (LA * b0max + amax * LB) / den**2
        else:
            K = 2 * (LB / amin + bmax * LA / amin**2)
        K = np.where(np.isfinite(K), K, np.inf)
        return 0.5 * (dev[:-1] + dev[1:]) + 0.5 * K * h


@dataclass(frozen=True)
class WeightCertificate:
    """Proof that ``|W| >= deviation`` on every interval of a grid covering ``[0, pi/dt]``.

    ``deviation_between[k]`` bounds the deviation on ``[omega_k, omega_k+1]`` and
    ``weight_lower[k]`` bounds ``|W|`` from below there; ``holds`` is
    ``all(weight_lower >= deviation_between)`` and ``min_ratio`` the smallest ratio.
    """

    omega: np.ndarray
    deviation: np.ndarray
    deviation_between: np.ndarray
    weight_lower: np.ndarray
    holds: bool
    min_ratio: float


def _poly_abs_bounds(coefs, omega, dt):
    """|P(e^{jw dt})| at omega for P(z) = sum coefs[k] z^(n-k) and its Lipschitz constant."""
    c = np.asarray(coefs, dtype=float)
    n = c.size - 1
    z = np.exp(1j * np.asarray(omega) * dt)
    val = np.abs(np.polyval(c, z))
    L = dt * float(np.sum(np.arange(n, -1, -1) * np.abs(c)))
    return val, L, float(np.sum(np.abs(c)))


def _weight_lower(W, omega, dt):
    num = np.ravel(np.asarray(W.num[0][0], dtype=float))
    den = np.ravel(np.asarray(W.den[0][0], dtype=float))
    nv, LN, nmax = _poly_abs_bounds(num, omega, dt)
    dv, LD, dmax = _poly_abs_bounds(den, omega, dt)
    h = np.diff(omega)
    dmin_i = np.maximum(np.minimum(dv[:-1], dv[1:]) - 0.5 * LD * h, 0.0)
    with np.errstate(divide="ignore"):
        LW = np.where(dmin_i > 0, (LN * dmax + nmax * LD) / np.where(dmin_i > 0, dmin_i, 1.0) ** 2,
                      np.inf)
        wv = nv / dv
    return np.maximum(0.5 * (wv[:-1] + wv[1:]) - 0.5 * LW * h, 0.0) * (1 - 1e-12)


def _check_grid(n_grid):
    if not isinstance(n_grid, (int, np.integer)) or isinstance(n_grid, bool) or n_grid < 64:
        raise ParameterValidationError(
            f"n_grid must be an integer >= 64 (points of the proof grid on [0, pi/dt]); "
            f"got {n_grid!r}."
        )


def _cert_grid(bounds, na, b_lags, dt, kind, n_grid):
    w = np.linspace(0.0, np.pi / dt, int(n_grid))
    dev = deviation_bound(bounds, na, b_lags, w, dt, kind)
    return w, dev, _between(bounds, na, b_lags, w, dt, kind, dev)


def certify_weight(W, bounds, na, b_lags, dt=1.0, kind="multiplicative",
                   n_grid: int = 8192, _grid=None) -> WeightCertificate:
    """Check ``|W(e^{jw dt})| >= sup_theta deviation`` for *all* ``w`` (see module doc)."""
    _check_grid(n_grid)
    w, dev, dev_b = _cert_grid(bounds, na, b_lags, dt, kind, n_grid) if _grid is None else _grid
    wl = _weight_lower(W, w, dt)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(dev_b > 0, wl / dev_b, np.inf)
    return WeightCertificate(w, dev, dev_b, wl, bool(np.all(wl >= dev_b)), float(np.min(ratio)))


@dataclass(frozen=True)
class UncertaintyWeight:
    """A certified uncertainty weight.

    Attributes
    ----------
    W : control.TransferFunction
        Stable, minimum-phase weight with the data's sampling time.
    kind : {"multiplicative", "additive"}
    central : control.TransferFunction
        The central model ``G0`` the uncertainty is measured around.
    omega, deviation : ndarray
        Fit grid (rad/s) and the exact deviation bound there.
    certificate : WeightCertificate
        The proof over all frequencies (``certificate.holds`` is always True for a
        returned weight).
    """

    W: object
    kind: str
    central: object
    omega: np.ndarray
    deviation: np.ndarray
    certificate: WeightCertificate

    @property
    def poles(self):
        return np.asarray(self.W.poles())

    @property
    def zeros(self):
        return np.asarray(self.W.zeros())


def _roots_from(x, n, rmax):
    """Map unconstrained x (length n) to n roots (conjugate pairs + one real) inside |z|<rmax."""
    roots = []
    k = 0
    for _ in range(n // 2):
        r = rmax * expit(x[k])
        ph = np.pi * expit(x[k + 1])
        roots += [r * np.exp(1j * ph), r * np.exp(-1j * ph)]
        k += 2
    if n % 2:
        roots.append(rmax * np.tanh(x[k]))
    return np.array(roots, dtype=complex)


def _params_from(roots, n, rmax):
    """Inverse of :func:`_roots_from` for a start point (roots clipped inside rmax)."""
    roots = sorted(np.asarray(roots, dtype=complex), key=lambda r: -abs(r.imag))
    roots = [r for r in roots if r.imag >= 0]  # one of each conjugate pair (and reals)
    x = []
    for k in range(n // 2):
        r = roots[k] if k < len(roots) else 0j
        rad = min(max(abs(r), 1e-3 * rmax), 0.95 * rmax)
        ph = min(max(abs(np.angle(r)), 1e-3), np.pi - 1e-3)
        x += [np.log(rad / (rmax - rad)), np.log(ph / (np.pi - ph))]
    if n % 2:
        r = roots[n // 2].real if n // 2 < len(roots) else 0.0
        x.append(np.arctanh(np.clip(r / rmax, -0.95, 0.95)))
    return np.array(x, dtype=float)


def _shape(x, n, z, rmax):
    zr = _roots_from(x[:n], n, rmax)
    pr = _roots_from(x[n:], n, rmax)
    num = np.prod(z[:, None] - zr[None, :], axis=1) if n else np.ones_like(z)
    den = np.prod(z[:, None] - pr[None, :], axis=1) if n else np.ones_like(z)
    return np.abs(num / den), zr, pr


def _unbounded_message(kind):
    why = ("some A in the parameter box vanishes on the unit circle (0 is in its value set)"
           if kind == "additive" else
           "some A in the parameter box, or the central numerator B0, vanishes on (or too "
           "near) the unit circle, where G/G0 - 1 is unbounded")
    fix = "" if kind == "additive" else " or use kind='additive'"
    return (f"the {kind} uncertainty cannot be bounded: {why}, so no finite weight exists. "
            f"Narrow the set (more data, method='exact'){fix}.")


def fit_weight(bounds, na, b_lags, central_tf, dt=1.0, kind="multiplicative", order=2,
               omega=None, margin=0.05, n_grid=8192, random_state=0,
               rmax=0.98) -> UncertaintyWeight:
    """Fit and certify a weight of the given ``order`` above the deviation bound.

    The shape (poles and zeros inside ``|z| <= rmax``) minimises the mean log-ratio
    ``log(|W| / deviation)`` on ``omega`` (log-spaced by default), with the gain set so that
    ``|W| >= (1 + margin) deviation`` there; then :func:`certify_weight` proves the bound on
    every interval of ``n_grid`` points over ``[0, pi/dt]`` and the gain is raised if needed.
    """
    import control
    from scipy.optimize import minimize

    if not (isinstance(order, (int, np.integer)) and 0 <= order <= 8):
        raise ParameterValidationError(f"order must be an integer in [0, 8]; got {order!r}.")
    _check_grid(n_grid)
    if not (isinstance(margin, (int, float, np.floating, np.integer)) and np.isfinite(margin)
            and margin >= 0):
        raise ParameterValidationError(f"margin must be >= 0; got {margin!r}.")
    nyq = np.pi / dt
    w = np.linspace(0.0, nyq, 256) if omega is None else np.asarray(omega, float)
    w = np.union1d(w, np.logspace(np.log10(1e-4 * nyq), np.log10(nyq), 256))
    dev = deviation_bound(bounds, na, b_lags, w, dt, kind)
    if not np.all(np.isfinite(dev)):
        raise UnboundedSetError(_unbounded_message(kind))
    target = dev * (1 + margin)
    floor = 1e-6 * max(float(np.max(target)), 1e-300)
    tgt = np.maximum(target, floor)
    z = np.exp(1j * w * dt)
    logw = np.log(tgt)

    def obj(x):
        mag, _, _ = _shape(x, order, z, rmax)
        lr = np.log(np.maximum(mag, 1e-300)) - logw
        return float(np.mean(lr - np.min(lr)))

    rng = np.random.default_rng(random_state)
    best_x = np.zeros(2 * order)
    if order:
        # starts: flat weight, poles at the central model's poles, random shapes
        starts = [np.zeros(2 * order), rng.normal(0, 2, 2 * order)]
        pc = np.asarray(central_tf.poles(), dtype=complex)
        zc = np.asarray(central_tf.zeros(), dtype=complex)
        zc = zc[np.abs(zc) < 1]
        starts.append(np.concatenate([_params_from([], order, rmax),
                                      _params_from(pc, order, rmax)]))
        starts.append(np.concatenate([_params_from(zc, order, rmax),
                                      _params_from(pc, order, rmax)]))
        best = np.inf
        for s in starts:
            res = minimize(obj, s, method="Nelder-Mead",
                           options={"maxiter": 300 * order, "xatol": 1e-6, "fatol": 1e-9})
            if res.fun < best:
                best, best_x = res.fun, res.x
    mag, zr, pr = _shape(best_x, order, z, rmax)
    grid = _cert_grid(bounds, na, b_lags, dt, kind, n_grid)
    if not (np.all(np.isfinite(grid[1])) and np.all(np.isfinite(grid[2]))):
        raise UnboundedSetError(_unbounded_message(kind))
    mag_c, _, _ = _shape(best_x, order, np.exp(1j * grid[0] * dt), rmax)
    k = max(float(np.max(tgt / mag)), float(np.max(grid[1] / mag_c)))
    num = k * np.real(np.poly(zr)) if order else np.array([k])
    den = np.real(np.poly(pr)) if order else np.array([1.0])
    W = control.tf(num, den, dt)
    cert = certify_weight(W, bounds, na, b_lags, dt, kind, n_grid, _grid=grid)
    for _ in range(5):
        if cert.holds:
            break
        W = W * (1.0 / cert.min_ratio * (1 + 1e-6))
        cert = certify_weight(W, bounds, na, b_lags, dt, kind, n_grid, _grid=grid)
    if not cert.holds:  # pragma: no cover - the gain scaling above always succeeds
        raise UnboundedSetError("could not certify the weight on the frequency grid.")
    return UncertaintyWeight(W, kind, central_tf, w, dev, cert)
