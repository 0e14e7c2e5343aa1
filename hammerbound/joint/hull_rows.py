"""Hull rows of the play operator at an ambiguous sample.

An ambiguous sample's value is ``v = max(R, min(L, S))`` (:class:`~.modes.Ambiguous`;
``R``, ``L`` the lines at its input, ``S`` the state before it), so on every branch

* ``v <= max(R, S)`` (``min(L, S) <= S``) and
* ``v >= min(L, S)`` (``max(R, ...) >= min(L, S)``).

Over the rectangle of the ranges of ``(R, S)`` (``(L, S)``) the convex function ``max``
lies below every plane that is above it at the four corners (a convex function's maximum
over a segment is at an end), and the concave ``min`` above every plane below it there.
The planes through three corners that pass the fourth are the rectangle's concave
(convex) envelope: two planes, linear rows in the LP's columns of ``R``, ``L`` and ``S``.
Where the band rows ``R <= v <= L`` leave ``v`` anywhere in a dead band while ``S`` holds
it near one end, these rows keep it there. Every row holds at every point of the box:
the ranges are the sound interval ranges of :mod:`.modes`, and each plane's constant is
raised by its own rounding error at the corners plus a relative margin.
"""

from __future__ import annotations

import numpy as np

from .modes import _MARGIN, AMBIG, INIT, LEFT, RIGHT, line_ranges

__all__ = ["envelope_planes", "hull_rows"]

# _MARGIN (of .modes, the ranges' margin): the relative margin of a plane's constant too
# a plane that misses its fourth corner by more than this (relative) is the other
# triangulation's, not the envelope's
_MISS = 1e-9
#: plane coefficients below this are dropped (:func:`_without_small`)
SMALL = 1e-3


def _state_ranges(kind, src, st, u, g):
    """Ranges of the states ``(kind, src)`` (arrays) before the ambiguous samples, over the
    box ``g`` (rows ``m_l, c_l, m_r, c_r, z0``)."""
    lo, hi = np.empty(kind.size), np.empty(kind.size)
    for k, (m, c, sign) in ((RIGHT, (g[2], g[3], -1.0)), (LEFT, (g[0], g[1], 1.0))):
        sel = kind == k
        lo[sel], hi[sel] = line_ranges(u[src[sel]], m, c, sign)
    sel = kind == INIT
    lo[sel], hi[sel] = g[4, 0], g[4, 1]
    amb = np.flatnonzero(kind == AMBIG)
    lo[amb] = [st.ambiguous[s].lo for s in src[amb]]
    hi[amb] = [st.ambiguous[s].hi for s in src[amb]]
    return lo, hi


def envelope_planes(p_range, s_range, upper: bool):
    """Planes ``alpha P + beta S + gamma`` above ``max(P, S)`` (``upper``) or below
    ``min(P, S)`` on the rectangles of the ranges (arrays, one rectangle each): arrays
    ``(alpha, beta, gamma, ok)`` of shape (n, 4), one plane per skipped corner; ``ok``
    marks the envelope's two planes (none when the ranges do not overlap -- one argument
    is then the max or min everywhere, and the one-sided rows say so -- or a range is a
    point)."""
    (pl, ph), (sl, sh) = (np.atleast_1d(np.asarray(r, dtype=float)) for r in p_range), \
        (np.atleast_1d(np.asarray(r, dtype=float)) for r in s_range)
    f = np.maximum if upper else np.minimum
    f00, f10, f01, f11 = f(pl, sl), f(ph, sl), f(pl, sh), f(ph, sh)
    with np.errstate(divide="ignore", invalid="ignore"):
        dp, ds = ph - pl, sh - sl
        # skip (0,0): through (1,0), (0,1), (1,1); skip (1,1): through (0,0), (1,0), (0,1);
        # skip (1,0): through (0,0), (0,1), (1,1); skip (0,1): through (0,0), (1,0), (1,1)
        alpha = np.stack([(f11 - f01) / dp, (f10 - f00) / dp, (f11 - f01) / dp,
                          (f10 - f00) / dp], axis=1)
        beta = np.stack([(f11 - f10) / ds, (f01 - f00) / ds, (f01 - f00) / ds,
                         (f11 - f10) / ds], axis=1)
    anchor = np.stack([f11 - alpha[:, 0] * ph - beta[:, 0] * sh,
                       f00 - alpha[:, 1] * pl - beta[:, 1] * sl,
                       f00 - alpha[:, 2] * pl - beta[:, 2] * sl,
                       f00 - alpha[:, 3] * pl - beta[:, 3] * sl], axis=1)
    corners = [(pl, sl, f00), (ph, sl, f10), (pl, sh, f01), (ph, sh, f11)]
    gaps = np.stack([alpha * x[:, None] + beta * y[:, None] + anchor - v[:, None]
                     for x, y, v in corners])  # (4 corners, n, 4 planes); >= 0 if upper
    scale = np.max(np.abs(np.stack([pl, ph, sl, sh])), axis=0)[:, None] + 1.0
    miss = -gaps.min(axis=0) if upper else gaps.max(axis=0)  # how far a corner is missed
    good = (pl < sh) & (sl < ph) & (dp > 0) & (ds > 0)
    ok = good[:, None] & (miss <= _MISS * scale) & np.isfinite(anchor)
    slack = np.maximum(miss, 0.0) + 4 * _MARGIN * scale
    gamma = anchor + slack if upper else anchor - slack
    return alpha, beta, gamma, ok


def hull_rows(rows, problem, box, st, bc, key_of):
    """Add the envelope rows of every ambiguous sample to ``rows`` (a ``_Rows`` of
    :mod:`.relaxation`): ``v <= plane(R, S)`` and ``v >= plane(L, S)``. ``bc``: the LP
    columns of ``beta``; ``key_of(t, j)`` the keys of rows ``j`` of samples ``t``
    (arrays)."""
    from .relaxation import B_DL, B_DR, B_ML, B_MR, _form_terms

    if not st.ambiguous:
        return
    p, u = problem.p, np.asarray(problem.u, dtype=float)
    g = np.asarray(box, dtype=float)[p: p + 5]
    t = np.array([a.t for a in st.ambiguous], dtype=np.int64)
    n = t.size
    state = _StateView(st)
    s_lo, s_hi = _state_ranges(state.kind, state.src, st, u, g)
    # the state's linear form (beta index, coefficient) x 2, as for an equation's sample
    s_idx, s_val = _form_terms(state, u, np.arange(n))
    ut = u[t]
    sizes = _beta_sizes(g, st)
    for j, (upper, (m, c, sign), cols, coef) in enumerate((
            (True, (g[2], g[3], -1.0), (B_MR, B_DR), (ut, -np.ones(n))),
            (False, (g[0], g[1], 1.0), (B_ML, B_DL), (ut, np.ones(n))))):
        p_lo, p_hi = line_ranges(ut, m, c, sign)
        alpha, beta, gamma, ok = envelope_planes((p_lo, p_hi), (s_lo, s_hi), upper)
        k, q = np.nonzero(ok)  # sample index, plane
        if k.size == 0:
            continue
        a, b, gam = _without_small(alpha[k, q], beta[k, q], gamma[k, q],
                                   (p_lo[k], p_hi[k]), (s_lo[k], s_hi[k]), upper)
        # v - a (m u_t +- d) - b (S form) on the right side; five entries per row
        col = np.column_stack([bc[5 + k], np.full(k.size, bc[cols[0]]),
                               np.full(k.size, bc[cols[1]]), bc[s_idx[k, 0]], bc[s_idx[k, 1]]])
        val = np.column_stack([np.ones(k.size), -a * coef[0][k], -a * coef[1][k],
                               -b * s_val[k, 0], -b * s_val[k, 1]])
        # the LP holds the coefficients rounded (and summed where S and the line share
        # columns): the constant also moves outward by a margin of the terms' size
        idx = np.column_stack([5 + k, np.full(k.size, cols[0]), np.full(k.size, cols[1]),
                               s_idx[k, 0], s_idx[k, 1]])  # beta indices of the entries
        size = np.sum(np.abs(val) * sizes[idx], axis=1)
        gam = gam + 4 * _MARGIN * size if upper else gam - 4 * _MARGIN * size
        r = np.repeat(np.arange(k.size), 5)
        lo = np.full(k.size, -np.inf) if upper else gam
        hi = gam if upper else np.full(k.size, np.inf)
        rows.add(r, col.ravel(), val.ravel(), lo, hi, key=key_of(t[k], 4 * j + q))


def _beta_sizes(g, st):
    """Largest magnitude of each inner variable ``beta = (m_l, d_l, m_r, d_r, z0, v..)``
    over the box (``d = m c``)."""
    big = np.max(np.abs(g), axis=1)
    amb = [max(abs(a.lo), abs(a.hi)) for a in st.ambiguous]
    return np.array([big[0], big[0] * big[1], big[2], big[2] * big[3], big[4], *amb])


def _without_small(a, b, gamma, p_range, s_range, upper):
    """The planes with coefficients below :data:`SMALL` replaced by their bound over the
    range (``a P <= a P_hi`` for an upper plane, ``a P >= a P_lo`` for a lower one; the
    coefficients are in [0, 1]: max and min are nondecreasing), the constant moved outward
    by the term's value plus a relative margin. Tiny coefficients made HiGHS's simplex
    stall (a million iterations on an LP that takes two thousand without them)."""
    a, b, gamma = a.copy(), b.copy(), gamma.copy()
    for coef, (lo, hi) in ((a, p_range), (b, s_range)):
        small = (coef != 0) & (np.abs(coef) < SMALL)
        end = np.where((coef > 0) == upper, hi, lo)  # where the term is largest (upper)
        shift = coef[small] * end[small]
        pad = _MARGIN * (np.abs(shift) + np.abs(gamma[small]) + 1.0)
        gamma[small] += shift + pad if upper else shift - pad
        coef[small] = 0.0
    return a, b, gamma


class _StateView:
    """The states before the ambiguous samples as the ``kind``/``src`` arrays that
    :func:`~.relaxation._form_terms` reads (sample ``k`` = ambiguous sample ``k``)."""

    def __init__(self, st):
        self.kind = np.array([a.src_kind for a in st.ambiguous], dtype=np.int64)
        self.src = np.array([a.src for a in st.ambiguous], dtype=np.int64)
