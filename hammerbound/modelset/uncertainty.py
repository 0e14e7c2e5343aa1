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

**Between frequencies.** On ``[w_k, w_k+1]`` (width ``h``) every ``|G/G0 - 1|`` (and
``|G - G0|``) is ``K``-Lipschitz with ``K`` built from ``max |Z_B|``, ``min |Z_A|``,
``|A0|``, ``|B0|`` over the interval and the Lipschitz constants ``L_A``, ``L_B`` of
:mod:`.frequency` -- or, whichever is smaller, from writing both deviations as
``M / (A B0)`` and ``M / (A A0)`` with ``M = (B - B0) A0 - (A - A0) B0``, whose modulus and
derivative are bounded by the box's radii (so ``K`` shrinks with the box); so is their
supremum ``delta``. Hence
``delta <= (delta_k + delta_k+1)/2 + K h / 2`` on the interval. For ``W = N / D`` the
moduli ``|N|`` and ``|D|`` are ``L_N``- and ``L_D``-Lipschitz (``L_P = dt sum_k k |p_k|``),
so on the interval ``|W| >= ((|N_k| + |N_k+1|)/2 - L_N h/2) / ((|D_k| + |D_k+1|)/2 +
L_D h/2)`` (an absolute rounding margin of ``1e-12 sum |p_k|`` is taken off ``|N|`` and
added to ``|D|``). This bound never divides by ``min |D|``, which is small when ``W`` has
poles near the unit circle (as it must when the deviation rises steeply, e.g. near a
zero of ``G0`` close to ``z = -1`` after a zero-order hold). :func:`certify_weight`
checks the second bound above the first on *every* interval of a grid of ``[0, pi/dt]``
(which covers all frequencies: the coefficients are real, so ``|.|`` is even and
``2 pi / dt``-periodic in ``w``): a uniform grid of ``n_grid`` points, with the
intervals where the Lipschitz slack (not the weight) decides bisected locally.

**Which weight.** :func:`fit_weight` fits shapes of every order ``0 .. order`` (each
order started, among others, from the best weight of the order below, which it contains
exactly: see :mod:`.weight_shape`), certifies each one (raising its gain until the proof
holds) and returns the *best certified* weight: the one with the smallest mean
over-bound ``mean_w 20 log10(|W(w)| / delta(w))`` in dB over the fit grid (the gap a
designer pays on a logarithmic frequency axis; ``delta`` floored at ``1e-6 max delta``).
A lower order wins ties, so the returned order can be lower than the one asked for.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import ParameterValidationError, UnboundedSetError
from .frequency import _lipschitz
from .gain_plane import plane_centre, plane_numerator
from .weight import UncertaintyWeight, WeightCertificate, num_den
from .weight_shape import embed, fit_shape, magnitude, polynomial, start_from_roots
from .zonotope import ROUND_RTOL, value_sets

__all__ = ["KINDS", "UncertaintyWeight", "WeightCertificate", "certify_weight",
           "deviation_bound", "fit_weight"]

KINDS = ("multiplicative", "additive")
_RTOL = 1e-9
#: the proof grid grows to at most this many times ``n_grid`` points by local bisection
_REFINE_FACTOR = 8
#: bisect an interval when its Lipschitz slack costs more than this (relative) ...
_REFINE_GAIN = 0.01
#: ... for at most this many rounds
_REFINE_ROUNDS = 12


def _split(bounds, na):
    bounds = np.asarray(bounds, dtype=float)
    a_lo = np.concatenate([[1.0], bounds[:na, 0]])
    a_hi = np.concatenate([[1.0], bounds[:na, 1]])
    return a_lo, a_hi, bounds[na:, 0], bounds[na:, 1]


def deviation_bound(bounds, na, b_lags, omega, dt=1.0, kind="multiplicative", *,
                    gain=None):
    """Exact ``sup |G/G0 - 1|`` (or ``sup |G - G0|``) over the box at each frequency.

    With ``gain``: the supremum over the box *on the gain plane* ``B(1) = gain A(1)``
    around the plane's centre (:func:`.gain_plane.plane_centre`), bounded by the smaller of
    the box's exact supremum and the plane bound of :mod:`.gain_plane` (0 at the steady
    state). Returns an array of shape (n,), ``inf`` where some ``A`` in the box vanishes.
    """
    if kind not in KINDS:
        raise ParameterValidationError(f"kind must be one of {KINDS}; got {kind!r}.")
    return _points(bounds, na, np.asarray(b_lags), np.asarray(omega, dtype=float) * dt,
                   kind, gain)["dev"]


def _centre(bounds, na, gain):
    """The reference model's coefficients: the box centre, or with ``gain`` the centre
    moved onto the gain plane."""
    bounds = np.asarray(bounds, dtype=float)
    return bounds.mean(axis=1) if gain is None else plane_centre(bounds, na, gain)


def _points(bounds, na, b_lags, wd, kind, gain):
    """The deviation bound at the frequencies ``wd`` (rad per sample) and the moduli the
    Lipschitz bounds between them need (see :class:`_ProofGrid`)."""
    a_lo, a_hi, b_lo, b_hi = _split(bounds, na)
    ZA = value_sets(a_lo, a_hi, np.arange(na + 1), wd)
    ZB = value_sets(b_lo, b_hi, b_lags, wd)
    theta0 = _centre(bounds, na, gain)
    # the reference model's polynomials at wd (without gain: the value sets' centres)
    a0, b0 = np.r_[1.0, theta0[:na]], theta0[na:]
    A0 = value_sets(a0, a0, np.arange(na + 1), wd).centre
    B0 = value_sets(b0, b0, b_lags, wd).centre
    dev = _deviation(ZA, ZB, kind, A0, B0)
    amin = ZA.min_abs()
    if gain is not None:
        mmax = plane_numerator(bounds, na, b_lags, wd, gain, A0, B0).max_abs()
        ref = np.abs(B0) if kind == "multiplicative" else np.abs(A0)
        with np.errstate(divide="ignore", invalid="ignore"):
            plane = np.where((amin > 0) & (ref > 0), mmax / (amin * np.where(ref > 0, ref, 1.0)),
                             np.inf)
        dev = np.minimum(dev, plane * (1 + _RTOL) + _RTOL * 1e-3)
    return {"w": wd, "dev": dev, "amin": amin, "amax": ZA.max_abs(), "bmax": ZB.max_abs(),
            "a0": np.abs(A0), "b0": np.abs(B0)}


def _deviation(ZA, ZB, kind, A0, B0):
    """The box's exact supremum of the deviation around ``G0 = B0 / A0`` from the value
    sets of ``A`` and ``B`` (any ``G0``: the maximum-modulus argument does not need it to
    be the box's centre)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        G0 = B0 / A0
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


class _ProofGrid:
    """Frequencies of the proof with the exact deviation and the moduli its Lipschitz
    bound between neighbours needs (:meth:`between`); :meth:`refine` bisects intervals.
    With ``gain`` the deviation is around the plane's centre, whose ``b_L`` may lie outside
    the box: its own Lipschitz constant and distances to the box are used for it."""

    _FIELDS = ("w", "dev", "amin", "amax", "bmax", "a0", "b0")

    def __init__(self, bounds, na, b_lags, dt, kind, w, gain=None):
        self.bounds, self.na, self.b_lags = np.asarray(bounds, float), na, np.asarray(b_lags)
        self.dt, self.kind, self.gain = float(dt), kind, gain
        a_lo, a_hi, b_lo, b_hi = _split(self.bounds, na)
        self.LA = _lipschitz(a_lo, a_hi, np.arange(na + 1), self.dt)
        self.LB = _lipschitz(b_lo, b_hi, self.b_lags, self.dt)
        b0 = _centre(self.bounds, na, gain)[na:]
        self.LB0 = _lipschitz(b0, b0, self.b_lags, self.dt)
        # radii of the box around the centre: |A - A0| <= rA, |d/dw (A - A0)| <= LrA
        # (likewise for B, whose centre on the plane need not be the box's)
        ra, rb = 0.5 * (a_hi - a_lo), np.maximum(b_hi - b0, b0 - b_lo)
        self.rA, self.rB = float(np.sum(ra)), float(np.sum(rb))
        self.LrA = self.dt * float(np.sum(np.arange(na + 1) * ra))
        self.LrB = self.dt * float(np.sum(self.b_lags * rb))
        self.data = self._points(np.asarray(w, dtype=float))

    @classmethod
    def uniform(cls, bounds, na, b_lags, dt, kind, n_grid, gain=None):
        return cls(bounds, na, b_lags, dt, kind, np.linspace(0.0, np.pi / dt, int(n_grid)),
                   gain)

    def _points(self, w):
        out = _points(self.bounds, self.na, self.b_lags, w * self.dt, self.kind, self.gain)
        out["w"] = w
        return out

    @property
    def omega(self):
        return self.data["w"]

    @property
    def dev(self):
        return self.data["dev"]

    @property
    def size(self):
        return self.omega.size

    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.dev)) and np.all(np.isfinite(self.between())))

    def refine(self, mask):
        """The grid with the midpoints of the intervals ``mask`` added."""
        w = self.omega
        new = self._points(0.5 * (w[:-1] + w[1:])[mask])
        order = np.argsort(np.concatenate([w, new["w"]]), kind="stable")
        out = object.__new__(_ProofGrid)
        out.__dict__.update(self.__dict__)
        out.data = {k: np.concatenate([self.data[k], new[k]])[order] for k in self._FIELDS}
        return out

    def between(self):
        """Upper bound of the deviation on each interval ``[w_k, w_k+1]`` (Lipschitz)."""
        d, LA, LB = self.data, self.LA, self.LB
        h = np.diff(d["w"])

        def up(x, L):
            return 0.5 * (x[:-1] + x[1:]) + 0.5 * L * h

        def down(x, L):
            return np.maximum(0.5 * (x[:-1] + x[1:]) - 0.5 * L * h, 0.0)

        LB0 = self.LB0  # of the centre's B (A0 is the box centre's A: LA)
        amin, amax, bmax = down(d["amin"], LA), up(d["amax"], LA), up(d["bmax"], LB)
        a0max, b0max, b0min = up(d["a0"], LA), up(d["b0"], LB0), down(d["b0"], LB0)
        a0min = np.maximum(amin, down(d["a0"], LA))  # A0 lies in A's value set
        # G/G0 - 1 = M/(A B0) and G - G0 = M/(A A0) with M = B A0 - A B0
        # = (B - B0) A0 - (A - A0) B0: small and slowly varying for a small box
        m_max = self.rB * a0max + self.rA * b0max
        dm_max = self.LrB * a0max + self.rB * LA + self.LrA * b0max + self.rA * LB0
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if self.kind == "multiplicative":
                den = amin * b0min
                K = (LB * a0max + bmax * LA) / den \
                    + bmax * a0max * (LA * b0max + amax * LB0) / den**2
                dden = LA * b0max + amax * LB0
            else:
                K = LB / amin + bmax * LA / amin**2 + LB0 / a0min + b0max * LA / a0min**2
                den = amin * a0min
                dden = LA * a0max + amax * LA
            K = np.minimum(K, dm_max / den + m_max * dden / den**2)
            K = np.where(np.isfinite(K), K, np.inf)
            return 0.5 * (d["dev"][:-1] + d["dev"][1:]) + 0.5 * K * h


def _poly_abs(coefs, omega, dt):
    """``|P(e^{jw dt})|`` for ``P(z) = sum coefs[k] z^(n-k)``, its Lipschitz constant in
    ``w`` and an absolute rounding margin of the evaluation."""
    c = np.asarray(coefs, dtype=float)
    n = c.size - 1
    val = np.abs(np.polyval(c, np.exp(1j * np.asarray(omega) * dt)))
    scale = float(np.sum(np.abs(c)))
    return val, dt * float(np.sum(np.arange(n, -1, -1) * np.abs(c))), ROUND_RTOL * scale


def _weight_lower(W, omega, dt):
    """Lower bound of ``|W|`` on each interval of ``omega`` (see the module doc)."""
    num, den = num_den(W)
    nv, LN, en = _poly_abs(num, omega, dt)
    dv, LD, ed = _poly_abs(den, omega, dt)
    h = np.diff(omega)
    n_lo = np.maximum(0.5 * (nv[:-1] + nv[1:]) - 0.5 * LN * h - en, 0.0)
    d_up = 0.5 * (dv[:-1] + dv[1:]) + 0.5 * LD * h + ed
    return n_lo / d_up * (1 - 1e-12)


def _check_grid(n_grid):
    if not isinstance(n_grid, (int, np.integer)) or isinstance(n_grid, bool) or n_grid < 64:
        raise ParameterValidationError(
            f"n_grid must be an integer >= 64 (points of the proof grid on [0, pi/dt]); "
            f"got {n_grid!r}."
        )


def _certify(W, grid, max_points):
    """Certificate of ``W`` on ``grid``, bisecting the intervals where the Lipschitz slack
    (not the weight) makes the proof fail; returns it with the (refined) grid."""
    dt = grid.dt
    for rnd in range(_REFINE_ROUNDS + 1):
        w, dev_b = grid.omega, grid.between()
        wl = _weight_lower(W, w, dt)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(dev_b > 0, wl / dev_b, np.inf)
            pv = np.abs(W(np.exp(1j * w * dt))) / grid.dev
        ends = np.minimum(pv[:-1], pv[1:])  # what the interval could reach when bisected
        slack = (ratio < 1) & (ratio * (1 + _REFINE_GAIN) < ends)
        room = max_points - grid.size
        if not slack.any() or room <= 0 or rnd == _REFINE_ROUNDS:
            break
        if slack.sum() > room:  # the worst intervals first
            keep = np.argsort(np.where(slack, ratio / ends, np.inf))[:room]
            slack = np.zeros_like(slack)
            slack[keep] = True
        grid = grid.refine(slack)
    cert = WeightCertificate(w, grid.dev, dev_b, wl, bool(np.all(wl >= dev_b)),
                             float(np.min(ratio)))
    return cert, grid


def certify_weight(W, bounds, na, b_lags, dt=1.0, kind="multiplicative",
                   n_grid: int = 8192, _grid=None, *, gain=None) -> WeightCertificate:
    """Check ``|W(e^{jw dt})| >= sup_theta deviation`` for *all* ``w`` (see module doc):
    on a uniform grid of ``n_grid`` points over ``[0, pi/dt]``, with intervals bisected
    where the Lipschitz slack decides (up to ``8 n_grid`` points in all). With ``gain``
    the supremum is over the box on the gain plane (:func:`deviation_bound`)."""
    _check_grid(n_grid)
    if kind not in KINDS:
        raise ParameterValidationError(f"kind must be one of {KINDS}; got {kind!r}.")
    grid = (_ProofGrid.uniform(bounds, na, b_lags, dt, kind, n_grid, gain) if _grid is None
            else _grid)
    return _certify(W, grid, _REFINE_FACTOR * int(n_grid))[0]


def _unbounded_message(kind, grid):
    """Why no finite weight exists, at which frequency, and what helps (new-user trial 20:
    a fit 2e-7 wide with its central zero at z = -1.0000001 was told to narrow the set)."""
    bad = ~np.isfinite(grid.dev)
    bad[:-1] |= ~np.isfinite(grid.between())
    i = int(np.flatnonzero(bad)[0]) if bad.any() else 0
    d = grid.data
    j = min(i + 1, grid.size - 1)  # the failing interval's ends: the nearer one is named
    # which polynomial is nearer 0 there, as a distance in frequency (value / Lipschitz
    # constant; review 52: the ratio to its size named A for a box 1e-7 wide)
    a_far = d["amin"][[i, j]] / max(grid.LA, 1e-300)
    b_far = d["b0"][[i, j]] / max(grid.LB0, 1e-300)
    blame_a = kind == "additive" or float(np.min(a_far)) <= float(np.min(b_far))
    k = [i, j][int(np.argmin(a_far if blame_a else b_far))]
    w = grid.omega[k]
    at = f"near w = {w:.4g} rad/{'s' if grid.dt != 1.0 else 'sample'}"
    if blame_a or d["amin"][k] == 0:
        grid_words = ("" if d["amin"][k] == 0 else
                      f"; |A| >= {d['amin'][k]:.3g} at the proof grid's points there, too "
                      "little for the proof between them: a larger n_grid may do")
        return (f"the {kind} uncertainty cannot be bounded: some A in the parameter box "
                f"vanishes on (or too near) the unit circle {at} (0 is in, or too near, its "
                f"value set{grid_words}), so no finite weight is certified. Narrow the set "
                "(more data, method='exact').")
    z = np.exp(1j * w * grid.dt)
    zs = "z = -1, the Nyquist frequency" if np.isclose(z.real, -1) else \
        ("z = 1" if np.isclose(z.real, 1) else f"z = {z.real:.4g}{z.imag:+.4g}j")
    return (f"the multiplicative uncertainty cannot be bounded: the central numerator B0 "
            f"vanishes on (or too near) the unit circle {at} ({zs}; |B0| = "
            f"{d['b0'][k]:.3g} there, while every A of the box stays at least "
            f"{d['amin'][k]:.3g} from 0), where G/G0 - 1 is unbounded or too large to "
            "certify; a narrower set does not move that zero. A zero there is common in "
            "sampled plants (equal b_j put it at z = -1). "
            "Use kind='additive': |G - G0| stays bounded there.")


def _check_fit_args(order, margin, n_grid):
    if not (isinstance(order, (int, np.integer)) and not isinstance(order, bool)
            and 0 <= order <= 8):
        raise ParameterValidationError(f"order must be an integer in [0, 8]; got {order!r}.")
    _check_grid(n_grid)
    if not (isinstance(margin, (int, float, np.floating, np.integer)) and np.isfinite(margin)
            and margin >= 0):
        raise ParameterValidationError(f"margin must be >= 0; got {margin!r}.")


def _certified(x, n, fit, grid, max_points, rmax):
    """The weight of shape ``x`` (order ``n``) with the smallest gain that the fit grid's
    target and the proof accept, its certificate and the grid; ``None`` if no gain can
    be certified (a lower bound of 0 where the deviation is positive)."""
    import control

    z_fit = np.exp(1j * fit["w"] * grid.dt)
    z_grid = np.exp(1j * grid.omega * grid.dt)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        mag = magnitude(x[:n], n, z_fit, rmax) / magnitude(x[n:], n, z_fit, rmax)
        mag_g = magnitude(x[:n], n, z_grid, rmax) / magnitude(x[n:], n, z_grid, rmax)
        k = max(float(np.max(fit["target"] / mag)), float(np.max(grid.dev / mag_g)))
    if not (np.isfinite(k) and k > 0):
        return None
    W = control.tf(k * polynomial(x[:n], n, rmax), polynomial(x[n:], n, rmax), grid.dt)
    for _ in range(4):
        cert, grid = _certify(W, grid, max_points)
        if cert.holds:
            return W, cert, grid
        if not (np.isfinite(cert.min_ratio) and cert.min_ratio > 0):
            return None
        W = W * (1.0 / cert.min_ratio * (1 + 1e-6))
    return None  # pragma: no cover - one gain step suffices up to rounding


def _excess_db(W, fit, dt):
    mag = np.abs(W(np.exp(1j * fit["w"] * dt)))
    return float(np.mean(20 * np.log10(mag / fit["floored"])))


def _starts(n, prev, central_tf, rng, rmax):
    """Starting shapes of order ``n``: the best of order ``n - 1`` (exactly embedded), a
    flat weight, a random one, the central model's poles (and zeros), and a zero at
    ``rmax`` with those poles: a deviation that vanishes at ``w = 0`` (on the gain plane)
    needs a zero near ``z = 1``, which the other starts did not reach (new-user trial 19:
    order 2 gave ``|W(1)| = 0.108`` against a bound of 0 there; with this start 0.0066,
    mean excess 12.5 -> 6.1 dB)."""
    flat = np.zeros(n)
    pc = np.asarray(central_tf.poles(), dtype=complex)
    zc = np.asarray(central_tf.zeros(), dtype=complex)
    zc = zc[np.abs(zc) < 1]
    starts = [np.zeros(2 * n), rng.normal(0, 2, 2 * n),
              np.concatenate([flat, start_from_roots(pc, n, rmax)]),
              np.concatenate([start_from_roots(zc, n, rmax), start_from_roots(pc, n, rmax)]),
              np.concatenate([start_from_roots([rmax] + [0.0] * (n - 1), n, rmax),
                              start_from_roots(pc, n, rmax)])]
    if prev is not None:
        m = n - 1
        starts.insert(0, np.concatenate([embed(prev[:m], m), embed(prev[m:], m)]))
    return starts


def fit_weight(bounds, na, b_lags, central_tf, dt=1.0, kind="multiplicative", order=2,
               omega=None, margin=0.05, n_grid=8192, random_state=0,
               rmax=0.98, *, tf_dt=None, frequency_unit="rad/s",
               gain=None) -> UncertaintyWeight:
    """The best certified weight of order at most ``order`` above the deviation bound.

    For each order ``0 .. order`` the shape (poles and zeros inside ``|z| <= rmax``)
    minimises the mean log-ratio ``log(|W| / deviation)`` on ``omega`` (default: 256
    linear and 256 log-spaced points up to ``pi/dt``) from several starts; each result
    gets the smallest gain with ``|W| >= (1 + margin) deviation`` on ``omega`` that
    :func:`certify_weight` proves on all of ``[0, pi/dt]``. The certified candidate with
    the smallest :attr:`UncertaintyWeight.excess_db` is returned (the lower order on a
    tie). The constant weight (order 0) always certifies, so a finite deviation always
    gives a weight. ``tf_dt``: the sampling time given to ``W`` (default ``dt``; ``True``
    when it is not known and ``omega`` is in rad/sample, as ``frequency_unit`` says).
    ``gain``: bound the box *on the gain plane* around its centre there
    (:func:`deviation_bound`); ``central_tf`` must then be that centre's model.
    """
    _check_fit_args(order, margin, n_grid)
    nyq = np.pi / dt
    w = np.linspace(0.0, nyq, 256) if omega is None else np.asarray(omega, float)
    w = np.union1d(w, np.logspace(np.log10(1e-4 * nyq), np.log10(nyq), 256))
    dev = deviation_bound(bounds, na, b_lags, w, dt, kind, gain=gain)
    grid = _ProofGrid.uniform(bounds, na, b_lags, dt, kind, n_grid, gain)
    if not (np.all(np.isfinite(dev)) and grid.finite()):
        raise UnboundedSetError(_unbounded_message(kind, grid))
    floor = 1e-6 * max(float(np.max(dev)), 1e-300)
    fit = {"w": w, "target": np.maximum(dev * (1 + margin), floor),
           "floored": np.maximum(dev, floor)}
    z = np.exp(1j * w * dt)
    max_points = _REFINE_FACTOR * int(n_grid)
    rng = np.random.default_rng(random_state)
    best, prev = None, None  # best: (excess, W, cert); prev: best shape of the last order
    for n in range(int(order) + 1):
        if n == 0:
            shapes = [np.zeros(0)]
        else:
            res = fit_shape(np.log(fit["target"]), z, n, _starts(n, prev, central_tf, rng, rmax),
                            rmax, 300 * n)
            shapes = [x for _, x in sorted(res, key=lambda r: r[0])]
        best_n = None
        for x in shapes:
            out = _certified(x, n, fit, grid, max_points, rmax)
            if out is None:
                continue
            W, cert, grid = out
            e = _excess_db(W, fit, dt)
            if best_n is None or e < best_n[0]:
                best_n = (e, x)
            if best is None or e < best[0] - 1e-9:
                best = (e, W, cert)
        prev = shapes[0] if best_n is None else best_n[1]
    e, W, cert = best
    if tf_dt is not None and tf_dt is not W.dt:
        import control

        W = control.tf(W.num[0][0], W.den[0][0], tf_dt)
    return UncertaintyWeight(W, kind, central_tf, w, dev, cert, e, frequency_unit,
                             on_gain_plane=gain is not None)
