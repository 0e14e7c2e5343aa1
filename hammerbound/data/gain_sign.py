"""The sign of a record's gain, for the hint of an empty verdict.

The model's backlash slopes are positive and its linear block has unit steady-state gain
(22.8), so the model rises with its input: a reverse-acting plant (a valve that closes as
its signal rises, a cooling loop) is explained by no parameters of it, and the fit says
"empty". Its output negated is. These least-squares fits only *suggest* that cause in the
message of an empty verdict; they decide nothing and bound nothing.
"""

from __future__ import annotations

import numpy as np

__all__ = ["NEGATED_HINT", "negative_gain_hint", "record_a1", "record_gain", "steady_slope"]

#: What to do about a reverse-acting plant (swapped columns named: new-user trial 16).
NEGATED_HINT = ("the model's backlash slopes are positive and its linear block has unit "
                "gain (22.8), so a plant whose output falls as its input rises is "
                "explained by no parameters of it. Are the input and output columns "
                "swapped? That gives a negative gain too. If not, fit the negated output "
                "(-y) and read the backlash in those terms.")


def _least_squares(u, y, lags_y, lags_u):
    """``theta = (a, b)`` of the least-squares equation-error fit of ``y_t + sum_i a_i
    y_{t-i} = sum_j b_j u_{t-j}`` and the number of ``a_i``; None when it is not defined
    (too few samples, a singular fit)."""
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    lags_y, lags_u = np.asarray(lags_y, dtype=int), np.asarray(lags_u, dtype=int)
    n0 = int(max(lags_y.max(initial=0), lags_u.max(initial=0)))
    t = np.arange(n0, y.size)
    if t.size <= lags_y.size + lags_u.size:
        return None
    phi = np.column_stack([-y[t - i] for i in lags_y] + [u[t - j] for j in lags_u])
    theta, _, rank, _ = np.linalg.lstsq(phi, y[t], rcond=None)
    return None if rank < phi.shape[1] else (theta, lags_y.size)


def record_gain(u, y, lags_y, lags_u) -> float:
    """Steady-state gain ``B(1) / A(1)`` of the least-squares equation-error fit of
    ``y_t + sum_i a_i y_{t-i} = sum_j b_j u_{t-j}`` (``lags_y = 1..na``, ``lags_u`` the
    input lags); NaN when it is not defined (too few samples, a singular fit, A(1) = 0)."""
    fit = _least_squares(u, y, lags_y, lags_u)
    if fit is None:
        return float("nan")
    theta, na = fit
    a1 = 1.0 + theta[:na].sum()
    return float("nan") if a1 == 0 else float(theta[na:].sum() / a1)


def record_a1(u, y, lags_y, lags_u) -> float:
    """``A(1) = 1 + sum_i a_i`` of the same least-squares fit (NaN when not defined): small
    for a slow or lightly damped plant, whose unit-gain normalisation fixes the scale
    between the backlash slopes and ``B`` only weakly."""
    fit = _least_squares(u, y, lags_y, lags_u)
    return float("nan") if fit is None else float(1.0 + fit[0][: fit[1]].sum())


def steady_slope(u, y) -> float:
    """Least-squares slope of steady-state outputs against their inputs (NaN for fewer
    than two distinct inputs)."""
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    if u.size < 2 or np.ptp(u) == 0:
        return float("nan")
    return float(np.polyfit(u, y, 1)[0])


def negative_gain_hint(gain: float, what: str = "least-squares gain") -> str:
    """A sentence for an empty verdict when ``gain`` is negative, else ''."""
    if not gain < 0:
        return ""
    return f"The record's {what} is negative ({gain:.3g}): {NEGATED_HINT}"
