"""Value sets of interval polynomials on the unit circle: 2-D zonotopes, vectorised.

For a polynomial ``P(z) = sum_k p_k z^-k`` whose coefficients range over a box
``p_k in [c_k - r_k, c_k + r_k]``, the value set ``{P(e^{jw})}`` at one frequency is the
zonotope ``c(w) + sum_k s_k g_k(w)``, ``|s_k| <= 1``, with centre ``c(w) = sum c_k e^{-jkw}``
and generators ``g_k(w) = r_k e^{-jkw}`` (complex numbers = vectors of the plane). It is a
centrally symmetric convex polygon with at most ``2 n`` vertices, obtained exactly by
sorting the generators by angle (``O(n log n)`` per frequency). Everything here works on
arrays of frequencies at once.

The functions return *exact* extremes of the exact polygon up to floating-point rounding;
callers widen them outward by :data:`ROUND_RTOL` relative to the magnitudes involved.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ROUND_RTOL", "Zonotopes", "value_sets"]

#: Relative outward margin that covers the rounding of the sums below (a few ulps times
#: the number of terms; 1e-12 is far above it for the polynomial orders used here).
ROUND_RTOL = 1e-12


class Zonotopes:
    """A stack of 2-D zonotopes ``centre[i] + sum_k s_k gens[i, k]``, ``|s_k| <= 1``.

    Parameters
    ----------
    centre : complex array of shape (n,)
    gens : complex array of shape (n, k)
    """

    def __init__(self, centre, gens):
        self.centre = np.asarray(centre, dtype=complex)
        self.gens = np.asarray(gens, dtype=complex).reshape(self.centre.size, -1)
        # magnitude scale for the outward rounding margin
        self.scale = np.abs(self.centre) + np.sum(np.abs(self.gens), axis=1)
        self.margin = ROUND_RTOL * (1.0 + self.scale)

    # ------------------------------------------------------------------ geometry
    def vertices(self) -> np.ndarray:
        """Vertices counter-clockwise, shape (n, 2 k) (repeated vertices for zero generators)."""
        g = self.gens
        n, k = g.shape
        if k == 0:
            return self.centre[:, None]
        # flip every generator into the upper half-plane (angle in [0, pi)), sort by angle
        ang = np.angle(g)
        flip = (ang < 0) | (ang >= np.pi)
        g = np.where(flip, -g, g)
        ang = np.mod(np.angle(g), np.pi)
        order = np.argsort(ang, axis=1)
        gs = np.take_along_axis(g, order, axis=1)
        start = self.centre - gs.sum(axis=1)  # lowest vertex (min imaginary part)
        # counter-clockwise: walk +2 g in increasing angle, then -2 g in increasing angle
        steps = np.concatenate([2 * gs, -2 * gs], axis=1)
        verts = start[:, None] + np.concatenate(
            [np.zeros((n, 1), complex), np.cumsum(steps, axis=1)[:, :-1]], axis=1)
        return verts

    def max_abs(self) -> np.ndarray:
        """Exact ``max |z|`` over each zonotope (attained at a vertex), widened outward."""
        return np.max(np.abs(self.vertices()), axis=1) + self.margin

    def min_abs(self) -> np.ndarray:
        """Exact distance from 0 to each zonotope (0 when 0 is inside), widened outward."""
        if self.gens.shape[1] == 0:
            return np.maximum(np.abs(self.centre) - self.margin, 0.0)
        v = self.vertices()
        w = np.roll(v, -1, axis=1)
        e = w - v
        # 0 inside the CCW polygon iff it is left of (or on) every edge
        cross = (e.conj() * (-v)).imag  # cross(e, 0 - v)
        inside = np.all(cross >= -self.margin[:, None] * (np.abs(e) + 1e-300), axis=1)
        ee = np.abs(e) ** 2
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.where(ee > 0, np.clip(-(v * e.conj()).real / ee, 0.0, 1.0), 0.0)
        d = np.min(np.abs(v + t * e), axis=1)
        # A (nearly) flat polygon - e.g. every value set at w = 0 or Nyquist is a real
        # segment - makes the sign test meaningless. Its width is at most
        # 2 pi area / perimeter (area >= width * diameter / 2, perimeter <= pi * diameter),
        # so distance-to-boundary minus that width is a valid lower bound either way.
        area = 0.5 * np.sum((v.conj() * w).imag, axis=1)
        perim = np.sum(np.abs(e), axis=1)
        thin = area <= 1e-9 * perim**2
        width = np.where(perim > 0, 2 * np.pi * np.abs(area) / np.where(perim > 0, perim, 1.0), 0.0)
        d_thin = np.maximum(d - self.margin - width, 0.0)
        return np.where(thin, d_thin, np.where(inside, 0.0, np.maximum(d - self.margin, 0.0)))

    def arg_range(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lo, hi)`` of ``arg(z) - arg(centre)`` over each zonotope, in (-pi, pi).

        Valid where 0 is outside the zonotope (check :meth:`min_abs` > 0); the convex set
        then lies in an open half-plane through 0, its arguments form an interval of width
        < pi attained at vertices, and measuring them relative to the centre is
        unambiguous. Widened outward by the rounding margin (in radians, relative to the
        distance from 0).
        """
        v = self.vertices()
        c = self.centre
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.angle(v * np.where(c != 0, c.conj() / np.abs(c), 1.0)[:, None])
            pad = self.margin / np.maximum(np.min(np.abs(v), axis=1), 1e-300)
        return rel.min(axis=1) - pad, rel.max(axis=1) + pad


def value_sets(coef_lo, coef_hi, lags, omega) -> Zonotopes:
    """Value sets of ``sum_k p_k e^{-j lags_k omega}`` over the box ``[coef_lo, coef_hi]``.

    ``omega`` is in radians per sample. A constant term (e.g. the leading 1 of ``A``) is
    a lag-0 coefficient with ``lo == hi``.
    """
    lo = np.asarray(coef_lo, dtype=float)
    hi = np.asarray(coef_hi, dtype=float)
    lags = np.asarray(lags, dtype=float)
    w = np.asarray(omega, dtype=float).ravel()
    ph = np.exp(-1j * np.outer(w, lags))
    c = ph @ (0.5 * (lo + hi))
    r = 0.5 * (hi - lo)
    keep = r > 0
    return Zonotopes(c, ph[:, keep] * r[keep])
