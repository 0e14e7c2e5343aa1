"""Shape of an uncertainty weight: a parametrisation of stable, minimum-phase filters and
the least-squares-in-log fit of their shape to a deviation bound (no proof here: the
certificate is :func:`hammerbound.modelset.uncertainty.certify_weight`).

A monic polynomial of degree ``n`` with every root inside ``|z| < rmax`` is written as
``n // 2`` real quadratic factors ``z^2 + c1 z + c0`` and, for odd ``n``, one linear
factor ``z - r``. With ``c0 = rmax^2 tanh(x0)``, ``c1 = rmax (1 + c0 / rmax^2) tanh(x1)``
and ``r = rmax tanh(x)``, every real ``x`` gives such a polynomial (the Schur-stability
triangle of a quadratic, scaled by ``rmax``) and every such polynomial with real or
complex roots is reached. ``x = 0`` gives ``z^2`` (or ``z``), so a weight of order
``n - 1`` is *exactly* one of order ``n`` with a cancelling pole and zero at the origin
(:func:`embed`): a fit of order ``n`` started there is never worse than that of
order ``n - 1``.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

__all__ = ["embed", "fit_shape", "magnitude", "polynomial", "start_from_roots"]

_CLIP = 0.999  # starting points stay strictly inside the triangle
_POLISH, _RESTARTS = 2, 3  # the best two results are restarted up to three times


def _factors(x, n, rmax):
    """Coefficient rows ``[1, c1, c0]`` of the quadratics and ``[1, -r]`` of the linear
    factor (if ``n`` is odd)."""
    quads = []
    for k in range(n // 2):
        c0 = rmax * rmax * np.tanh(x[2 * k])
        c1 = rmax * (1.0 + c0 / (rmax * rmax)) * np.tanh(x[2 * k + 1])
        quads.append((c1, c0))
    lin = rmax * np.tanh(x[n - 1]) if n % 2 else None
    return quads, lin


def polynomial(x, n, rmax) -> np.ndarray:
    """Coefficients (highest power first) of the monic degree-``n`` polynomial of ``x``."""
    quads, lin = _factors(x, n, rmax)
    p = np.array([1.0])
    for c1, c0 in quads:
        p = np.polymul(p, [1.0, c1, c0])
    if lin is not None:
        p = np.polymul(p, [1.0, -lin])
    return p


def magnitude(x, n, z, rmax) -> np.ndarray:
    """``|P(z)|`` at the points ``z`` from the factors (no expanded coefficients)."""
    quads, lin = _factors(x, n, rmax)
    out = np.ones(z.shape)
    for c1, c0 in quads:
        out = out * np.abs(z * (z + c1) + c0)
    if lin is not None:
        out = out * np.abs(z - lin)
    return out


def _quad_params(c1, c0, rmax):
    t0 = np.clip(c0 / (rmax * rmax), -_CLIP, _CLIP)
    t1 = np.clip(c1 / (rmax * (1.0 + t0)), -_CLIP, _CLIP)
    return [float(np.arctanh(t0)), float(np.arctanh(t1))]


def start_from_roots(roots, n, rmax) -> np.ndarray:
    """Parameters of a degree-``n`` polynomial near the given roots (scaled inside
    ``0.95 rmax``; missing roots at 0, surplus ones dropped, smallest first)."""
    r = np.asarray(roots, dtype=complex).ravel()
    r = r[np.isfinite(r)]
    big = np.abs(r) > 0.95 * rmax
    r = np.where(big, r / np.where(big, np.abs(r), 1.0) * 0.95 * rmax, r)
    cplx = [v for v in r if v.imag > 1e-12]
    reals = sorted((v.real for v in r if abs(v.imag) <= 1e-12), key=lambda v: -abs(v))
    quads = [(-2 * v.real, abs(v) ** 2) for v in cplx]
    while len(reals) >= 2 and len(quads) < n // 2:
        a, b = reals.pop(0), reals.pop(0)
        quads.append((-(a + b), a * b))
    x = []
    for k in range(n // 2):
        c1, c0 = quads[k] if k < len(quads) else (0.0, 0.0)
        x += _quad_params(c1, c0, rmax)
    if n % 2:
        lin = reals[0] if reals else 0.0
        x.append(float(np.arctanh(np.clip(lin / rmax, -_CLIP, _CLIP))))
    return np.array(x, dtype=float)


def embed(x, n):
    """Parameters of order ``n + 1`` with the same polynomial times ``z`` (exactly)."""
    x = np.asarray(x, dtype=float)
    if n % 2 == 0:  # add the linear factor z (r = 0)
        return np.concatenate([x, [0.0]])
    # z (z - r) = z^2 - r z: c0 = 0 (x0 = 0), c1 = -r = rmax tanh(x1) -> x1 = -x_lin
    return np.concatenate([x[:n - 1], [0.0, -x[n - 1]]])


def fit_shape(log_target, z, n, starts, rmax, maxiter):
    """Zeros' and poles' parameters (length ``2 n``) minimising the mean log-excess
    ``mean(l - min l)``, ``l = log|N/D| - log_target`` on the points ``z`` (the gain is
    then fixed by the certificate), by Nelder-Mead from each of ``starts``.

    Returns a list of ``(objective, parameters)``, one per start."""
    def obj(x):
        lr = (np.log(np.maximum(magnitude(x[:n], n, z, rmax), 1e-300))
              - np.log(np.maximum(magnitude(x[n:], n, z, rmax), 1e-300)) - log_target)
        return float(np.mean(lr - np.min(lr)))

    def run(x, f):
        res = minimize(obj, x, method="Nelder-Mead",
                       options={"maxiter": maxiter, "xatol": 1e-6, "fatol": 1e-9})
        return (float(res.fun), res.x) if res.fun < f else (f, x)  # never worse

    results = [run(np.asarray(s, dtype=float), obj(s)) for s in starts]
    order = np.argsort([f for f, _ in results])
    for i in order[:_POLISH]:  # fresh simplices escape a collapsed one
        f, x = results[i]
        for _ in range(_RESTARTS):
            f_new, x = run(x, f)
            done = not f_new < f - 1e-6 * max(abs(f), 1e-3)
            f = f_new
            if done:
                break
        results[i] = (f, x)
    return results
