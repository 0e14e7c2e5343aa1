"""Bounds of the linear block on the gain hyperplane, exact at the steady state.

Every feasible model satisfies the steady-state gain equality (22.8)
``B(1) = g A(1)``; the parameter box cannot express it, so bounds over the box alone are
widest where the equality decides most: at low frequencies. With the last ``b_L``
eliminated, ``B(z) = sum_{j<L} b_j (z^-j - z^-L) + g z^-L A(1)`` and, for a fixed pair of
polynomial values ``(A0, B0)`` at the frequency (a central model ``G0 = B0/A0``),

    ``M = B A0 - B0 A = [g A0 z^-L - B0] + sum_{j<L} b_j A0 (z^-j - z^-L)
                        + sum_i a_i (g A0 z^-L - B0 z^-i)``

is *affine* in the remaining coordinates ``(a, b_{j<L})``: over their box its value set
is a zonotope, whose largest modulus is exact. Dropping ``b_L``'s own interval is an outer
step (the set ``{(a, b_{j<L}) in box, b_L from the equality}`` contains box ∩ plane).
Then, on the plane,

    ``|G/G0 - 1| = |M| / (|A| |B0|)``,   ``|G - G0| = |M| / (|A| |A0|)``

are bounded by ``max |Z_M| / min |Z_A|`` over the parts (decoupled: outward). When
``G0`` lies on the plane too (:func:`plane_centre`), every coefficient of ``M`` vanishes
at ``z = 1``: the bound is 0 at the steady state and grows like the frequency, where a
box bound is largest. With ``A0 = 1`` and ``B0 = g`` it bounds ``|G - g|``.
"""

from __future__ import annotations

import numpy as np

from .zonotope import Zonotopes

__all__ = ["plane_centre", "plane_numerator", "plane_numerator_lipschitz"]


def plane_centre(bounds, na, gain) -> np.ndarray:
    """The box centre (rows ``a_1..a_na``, then the ``b``'s by lag) with its last ``b``
    moved onto the gain plane:
    ``b_L = g (1 + sum a_i) - sum_{j<L} b_j`` at the centre's other coordinates (it may
    leave the box's interval of ``b_L``; it is a reference model, not a member)."""
    bounds = np.asarray(bounds, dtype=float)
    theta = bounds.mean(axis=1)
    a, b = theta[:na], theta[na:]
    theta[-1] = float(gain) * (1.0 + float(np.sum(a))) - float(np.sum(b[:-1]))
    return theta


def plane_numerator(bounds, na, b_lags, wd, gain, A0, B0) -> Zonotopes:
    """Value sets of ``M = B A0 - B0 A`` on the plane at the frequencies ``wd`` (rad per
    sample), over the box of ``(a, b_{j<L})`` (see the module docstring). ``A0``, ``B0``:
    complex arrays of the reference model's polynomials at ``wd`` (or scalars)."""
    bounds = np.asarray(bounds, dtype=float)
    b_lags = np.asarray(b_lags, dtype=float)
    wd = np.asarray(wd, dtype=float).ravel()
    A0 = np.broadcast_to(np.asarray(A0, dtype=complex), wd.shape)
    B0 = np.broadcast_to(np.asarray(B0, dtype=complex), wd.shape)
    g, L, free = float(gain), b_lags[-1], b_lags[:-1]
    zL = np.exp(-1j * wd * L)
    coef_a = (g * A0 * zL)[:, None] - B0[:, None] * np.exp(-1j * np.outer(wd, np.arange(1, na + 1)))
    coef_b = A0[:, None] * (np.exp(-1j * np.outer(wd, free)) - zL[:, None])
    const = g * A0 * zL - B0
    lo = np.concatenate([bounds[:na, 0], bounds[na:na + free.size, 0]])
    hi = np.concatenate([bounds[:na, 1], bounds[na:na + free.size, 1]])
    coef = np.concatenate([coef_a, coef_b], axis=1)
    centre = const + coef @ (0.5 * (lo + hi))
    r = 0.5 * (hi - lo)
    keep = r > 0
    return Zonotopes(centre, coef[:, keep] * r[keep])


def plane_numerator_lipschitz(bounds, na, b_lags, gain, dt) -> float:
    """Lipschitz constant in ``omega`` of ``|M|`` with ``A0 = 1``, ``B0 = g`` (``M = B - gA``
    on the plane), for every point of the box: ``|d/dw z^-k| = k dt``."""
    bounds = np.asarray(bounds, dtype=float)
    b_lags = np.asarray(b_lags, dtype=float)
    g, L, free = abs(float(gain)), float(b_lags[-1]), b_lags[:-1]
    amax = np.max(np.abs(bounds[:na]), axis=1) if na else np.zeros(0)
    bmax = np.max(np.abs(bounds[na:na + free.size]), axis=1)
    return float(dt) * (g * L + float(np.sum(bmax * (free + L)))
                        + g * float(np.sum(amax * (L + np.arange(1, na + 1)))))
