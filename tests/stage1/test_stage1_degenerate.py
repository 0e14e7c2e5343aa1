"""Stage 1 with the noise exactly at its bound on every sample (issue 29, item 3).

Constant ``+Delta`` noise makes the lower boundary of every measurement of a side pass
through the truth (a pencil of nearly concurrent lines); alternating signs make the set a
point up to the tolerance. Both methods must return the set -- sound, tight, with a
handful of vertices -- as for noise inside the bound. The data come from the tests' own
steady-state map; the sets are checked against exact rational vertex enumeration of the
measured constraints (their binding rows found by exact convex hulls).
"""

from __future__ import annotations

from fractions import Fraction
from itertools import combinations

import numpy as np
import pytest

import hammerbound as hb
from hammerbound.stage1.side_polygon import _hull_mask

GAMMA = np.array([0.8, 0.1, 0.84, 0.12])  # (ml, cl, mr, cr)
METHODS = ("polygon", "algorithm")
PATTERNS = ("plus", "minus", "alternating", "random")


def _steady(amps, gamma=GAMMA):
    """Steady-state backlash outputs (22.9)-(22.10), our own map: ``+a`` on the right
    line ``mr (u - cr)``, ``-a`` on the left line ``ml (u + cl)``."""
    ml, cl, mr, cr = gamma
    u = np.concatenate([amps, -amps])
    return u, np.where(u > 0, mr * (u - cr), ml * (u + cl))


def _noise(pattern, n, D, rng):
    """Noise exactly at the bound: ``+D`` or ``-D`` everywhere, alternating, random signs."""
    if pattern == "plus":
        return np.full(n, D)
    if pattern == "minus":
        return np.full(n, -D)
    if pattern == "alternating":
        return D * np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    return D * rng.choice([-1.0, 1.0], n)


def _data(pattern, M, D=1e-3, seed=0, spread=False):
    rng = np.random.default_rng(seed)
    amps = np.sort(rng.uniform(0.15, 3.0, M)) if spread else np.linspace(0.15, 3.0, M)
    u, w = _steady(amps)
    return u, w + _noise(pattern, u.size, D, rng)


def _sides(est):
    return ((est.left_, GAMMA[:2], 1.0), (est.right_, GAMMA[2:], -1.0))


# ---- the measured set, exactly -------------------------------------------------------------
def _hull(points, lower):
    """Lower (or upper) convex hull of rational points (monotone chain, exact)."""
    pts = sorted(points, reverse=not lower)
    out: list = []
    for p in pts:
        while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                 - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
            out.pop()
        out.append(p)
    return out


def _measured_rows(u, y, D, sigma):
    """``a . (m, beta) <= b`` for ``|y - m u - sigma beta| <= D``, ``m >= 0``, ``beta >= 0``,
    in exact rationals (the floats at their binary values, no tolerance). Only points on
    the lower hull of ``(u, y + D)`` and the upper hull of ``(u, y - D)`` can bind (the
    others are implied by their neighbours), so the rows come from those."""
    U = [Fraction(v) for v in u.tolist()]
    d, s = Fraction(D), Fraction(sigma)
    up = _hull([(uk, Fraction(yk) + d) for uk, yk in zip(U, y.tolist(), strict=True)], True)
    lo = _hull([(uk, Fraction(yk) - d) for uk, yk in zip(U, y.tolist(), strict=True)], False)
    rows = [(uk, s, z) for uk, z in up] + [(-uk, -s, -z) for uk, z in lo]
    return rows + [(Fraction(-1), Fraction(0), Fraction(0)), (Fraction(0), Fraction(-1), Fraction(0))]


def _exact_vertices(rows):
    """All vertices of ``{a . x <= b}`` (rational, by brute force over pairs of rows)."""
    out = set()
    for (a0, a1, b), (c0, c1, d) in combinations(rows, 2):
        det = a0 * c1 - a1 * c0
        if det == 0:
            continue
        x = ((b * c1 - a1 * d) / det, (a0 * d - b * c0) / det)
        if all(r0 * x[0] + r1 * x[1] <= rb for r0, r1, rb in rows):
            out.add(x)
    return sorted(out)


def _inside_hull(V, x) -> bool:
    """``x`` (rationals) in the convex hull of the float vertices ``V``, exactly."""
    V = np.asarray(V, dtype=float)
    c = V.mean(axis=0)
    V = V[np.argsort(np.arctan2(V[:, 1] - c[1], V[:, 0] - c[0]))]
    P = [(Fraction(float(p[0])), Fraction(float(p[1]))) for p in V]
    for k in range(len(P)):
        (x0, y0), (x1, y1) = P[k], P[(k + 1) % len(P)]
        if (x1 - x0) * (x[1] - y0) - (y1 - y0) * (x[0] - x0) < 0:
            return False
    return True


def _check_exact(fs, u, y, D, sigma, gamma):
    """The returned side against the measured set computed exactly: it contains every
    exact vertex (exactly), its vertices violate no measured constraint by more than 1e-9
    of the terms, its orthotope contains the exact one and exceeds it by < 1e-9 of the
    scales (m; the amplitudes for c), and it has a handful of vertices."""
    rows = _measured_rows(u, y, D, sigma)
    V = fs.vertices_mb
    assert 3 <= len(V) <= 8, len(V)  # a pencil of M boundaries left ~M vertices before
    exact = _exact_vertices(rows)
    for x in exact:
        assert _inside_hull(V, x), (fs.side, x)
    A = np.array([[float(r[0]), float(r[1])] for r in rows])
    b = np.array([float(r[2]) for r in rows])
    for v in V:
        excess = (A @ v - b) / (np.abs(A) @ np.abs(v) + np.abs(b) + 1e-300)
        assert excess.max() <= 1e-9, (fs.side, excess.max())
    assert fs.contains(gamma), fs.side
    if exact:  # (the floats of data at the bound may leave no exact point at all)
        m = [x[0] for x in exact]
        c = [x[1] / x[0] for x in exact if x[0] > 0]
        box = fs.orthotope
        scale = (max(m), float(np.max(np.abs(u))))
        for k, vals in enumerate((m, c)):
            lo, hi = Fraction(float(box[k, 0])), Fraction(float(box[k, 1]))
            assert lo <= min(vals) and max(vals) <= hi, (fs.side, k)
            assert float(min(vals) - lo) <= 1e-9 * scale[k], (fs.side, k)
            assert float(hi - max(vals)) <= 1e-9 * scale[k], (fs.side, k)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("pattern", PATTERNS)
@pytest.mark.parametrize("M, spread", [(12, True), (50, False), (500, False), (500, True)])
def test_sets_at_the_bound_are_the_exact_measured_sets(method, pattern, M, spread):
    D = 1e-3
    u, y = _data(pattern, M, D, seed=M + spread, spread=spread)
    est = hb.BacklashSetEstimator(D, method=method).fit(u, y)
    for fs, gamma, sigma in _sides(est):
        sel = (u < 0) if sigma > 0 else (u > 0)
        _check_exact(fs, u[sel], y[sel], D, sigma, gamma)


@pytest.mark.parametrize("pattern", PATTERNS)
def test_polygon_many_amplitudes_at_the_bound(pattern):
    """The issue's configuration at M = 4000 per side (polygon; its tightness check alone
    took 2.2 GB): the exact measured set, a handful of vertices."""
    D = 1e-3
    u, y = _data(pattern, 4000, D, seed=7)
    est = hb.BacklashSetEstimator(D).fit(u, y)
    for fs, gamma, sigma in _sides(est):
        sel = (u < 0) if sigma > 0 else (u > 0)
        _check_exact(fs, u[sel], y[sel], D, sigma, gamma)


@pytest.mark.parametrize("pattern", ["plus", "alternating"])
@pytest.mark.parametrize("scale", [1e-5, 1e4])
def test_both_methods_agree_at_the_bound_at_every_scale(pattern, scale):
    u, y = _data(pattern, 300, 1e-3, seed=3)
    u, y, D = u * scale, y * scale, 1e-3 * scale
    gamma = GAMMA * np.array([1.0, scale, 1.0, scale])
    ests = [hb.BacklashSetEstimator(D, method=m).fit(u, y) for m in METHODS]
    for est in ests:
        gb = est.gamma_bounds_
        assert np.all(gb[:, 0] <= gamma) and np.all(gamma <= gb[:, 1]), gb
    a, b = (e.gamma_bounds_ for e in ests)
    # slopes relative to themselves, dead zones relative to the amplitudes
    mag = np.array([1.0, np.abs(u).max(), 1.0, np.abs(u).max()])[:, None]
    assert np.all(np.abs(a - b) <= 1e-10 * mag), (a, b)


def test_hull_prefilter_on_collinear_points():
    """Points on a line to rounding (Qhull: "initial simplex is flat") keep only a few
    candidates, the two ends among them (the polygons above check the result)."""
    t = np.linspace(-1.0, 1.0, 5000)
    z = 0.3 * t + 0.1 + 1e-3 / 3  # rounding-level scatter about one line
    mask = _hull_mask(t, z)
    assert mask[0] and mask[-1] and mask.sum() <= 16
    assert _hull_mask(t, 0.25 * t).sum() <= 16  # exactly collinear
