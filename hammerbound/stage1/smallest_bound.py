"""The smallest output bound at which the steady-state data can be explained.

Each side's steady states lie on one line ``y = m u + q`` within their output bounds. The
smallest factor ``s`` such that some line has ``|y_j - m u_j - q| <= s * deta_j`` on every
point of a side (a weighted Chebyshev line fit) is a lower bound of the factor at which
the stage-1 set is non-empty (that set also asks ``m, c >= 0``). It is computed from exact
subsets of the points (:func:`_side_factor`), so it can only err low. Below
``max(s_left, s_right)`` times the given bound the data are certainly explained by no
backlash; a given bound just above it leaves little room for a noise bound that was
underestimated (new-user trial 17: 0.048 for noise within 0.05 gave an interval of ``m_r``
without the truth, and nothing showed how close the data came to the bound).
"""

from __future__ import annotations

from fractions import Fraction
from itertools import combinations

import numpy as np
from scipy.optimize import linprog

__all__ = ["smallest_bound_factor", "smallest_bound_text"]


#: points of a side whose exact subsets are evaluated: those with the largest weighted
#: residuals against the LP's line (the minimax line of a side is fixed by three of them)
CANDIDATES = 6


def _side_factor(u, y, deta) -> float:
    """A lower bound of ``min s s.t. |y_j - m u_j - q| <= s deta_j`` that no solver error
    can raise: an LP in centred, scaled coordinates picks the points with the largest
    weighted residuals, and the exact (rational) minimax value of each subset of three of
    them, or of two at one input, is a lower bound of the whole side's (review 49: the LP's
    own value, unscaled, was up to 70x too high at scales of 1e8 or bounds of 1e-9)."""
    su = float(np.ptp(u)) or 1.0
    sy = float(np.ptp(y)) or float(np.max(deta))
    t, w, dw = (u - np.mean(u)) / su, (y - np.mean(y)) / sy, deta / sy
    n = u.size
    a_ub = np.vstack([np.column_stack([-t, -np.ones(n), -dw]),
                      np.column_stack([t, np.ones(n), -dw])])
    res = linprog([0.0, 0.0, 1.0], A_ub=a_ub, b_ub=np.concatenate([-w, w]),
                  bounds=[(None, None), (None, None), (0.0, None)], method="highs")
    if res.status != 0:
        return 0.0  # no statement (never a bound that might be too high)
    ratio = np.abs(w - res.x[0] * t - res.x[1]) / dw
    pick = np.argsort(-ratio)[:CANDIDATES]
    pts = sorted((Fraction(float(u[i])), Fraction(float(y[i])), Fraction(float(deta[i])))
                 for i in pick)
    best = Fraction(0)
    for (u1, y1, d1), (u2, y2, d2) in combinations(pts, 2):
        if u1 == u2:  # one input, two outputs: they need |y1 - y2| <= s (d1 + d2)
            best = max(best, abs(y1 - y2) / (d1 + d2))
    for (u1, y1, d1), (u2, y2, d2), (u3, y3, d3) in combinations(pts, 3):
        if u1 < u2 < u3:  # the middle point's distance from the chord of the outer two
            lam = (u3 - u2) / (u3 - u1)
            best = max(best, abs(y2 - lam * y1 - (1 - lam) * y3)
                       / (d2 + lam * d1 + (1 - lam) * d3))
    out = float(best)
    return out if Fraction(out) <= best else float(np.nextafter(out, 0.0))


def smallest_bound_factor(u, y, deta) -> float:
    """The largest over the two sides of the smallest factor of ``deta`` that lets one line
    explain that side's points (0 for a side with fewer than three points: two points lie
    on a line)."""
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    deta = np.broadcast_to(np.asarray(deta, dtype=float), u.shape)
    out = 0.0
    for mask in (u > 0, u < 0):
        if np.count_nonzero(mask) >= 3:
            out = max(out, _side_factor(u[mask], y[mask], deta[mask]))
    return out


def smallest_bound_text(factor, deta) -> str:
    """`` (the data allow no bound below X: ...)`` for a summary's output-bound line, X
    rounded down (it is a lower bound); empty when ``factor`` says nothing."""
    from ..tables import rounded_text

    if not factor > 0:
        return ""
    deta = np.asarray(deta, dtype=float)
    if np.all(deta == deta.flat[0]):
        low = f"{rounded_text(factor * float(deta.flat[0]), down=True, digits=3)}"
    else:
        low = f"{rounded_text(factor, down=True, digits=3)} x these bounds"
    return f" (the data allow no bound below {low}: no line explains a side there)"
