"""The smallest output bound at which the steady-state data can be explained.

Each side's steady states lie on one line ``y = m u + q`` within their output bounds. The
smallest factor ``s`` such that some line has ``|y_j - m u_j - q| <= s * deta_j`` on every
point of a side (a Chebyshev line fit, an LP in ``(m, q, s)``) is a lower bound of the
factor at which the stage-1 set is non-empty (that set also asks ``m, c >= 0``). Below
``max(s_left, s_right)`` times the given bound the data are certainly explained by no
backlash; a given bound just above it leaves little room for a noise bound that was
underestimated (new-user trial 17: 0.048 for noise within 0.05 gave an interval of ``m_r``
without the truth, and nothing showed how close the data came to the bound).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

__all__ = ["smallest_bound_factor", "smallest_bound_text"]


def _side_factor(u, y, deta) -> float:
    """min s s.t. |y_j - m u_j - q| <= s deta_j, from the LP's dual (a lower bound)."""
    n = u.size
    # variables (m, q, s): y - m u - q <= s d  and  -(y - m u - q) <= s d
    a_ub = np.vstack([np.column_stack([-u, -np.ones(n), -deta]),
                      np.column_stack([u, np.ones(n), -deta])])
    b_ub = np.concatenate([-y, y])
    res = linprog([0.0, 0.0, 1.0], A_ub=a_ub, b_ub=b_ub,
                  bounds=[(None, None), (None, None), (0.0, None)], method="highs")
    if res.status != 0:
        return 0.0  # no statement (never a bound that might be too high)
    # the dual objective b_ub . lambda (lambda <= 0 in scipy's sign) is a lower bound of the
    # LP's value for any dual-feasible lambda; HiGHS's duals are feasible to ~1e-9, so the
    # factor is taken 1e-6 lower to stay on the safe side
    dual = float(-(b_ub @ -res.ineqlin.marginals)) if res.ineqlin is not None else res.fun
    return max(0.0, min(dual, res.fun) * (1.0 - 1e-6) - 1e-12)


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
