"""Linear programs whose reported bound is *guaranteed*, whatever the solver's accuracy.

A floating-point LP solver returns an approximately optimal primal/dual pair. Its
objective value is not a valid bound in general: an inaccurate solve can report a
minimum slightly *above* the true one. When every variable has finite bounds
``l <= z <= u``, weak duality gives a rigorous lower bound from *any* multipliers
(Neumaier & Shcherbina, 2004)::

    min c'z  s.t.  A_eq z = b_eq,  A_ub z <= b_ub,  l <= z <= u
    >=  y_eq' b_eq + y_ub' b_ub + sum_i min(r_i l_i, r_i u_i),
        r = c - A_eq' y_eq - A_ub' y_ub,   y_ub <= 0 (clipped).

The sum is evaluated in floating point and then lowered by a rounding margin, so the
result is a lower bound of the exact LP value. Infeasibility is certified the same way
on the phase-1 problem (minimum total violation): a rigorous positive lower bound on the
total violation proves that no feasible point exists.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from ..status import FAILED, INFEASIBLE, OPTIMAL

EPS = np.finfo(float).eps


@dataclass(frozen=True)
class SafeLPResult:
    """Outcome of :func:`safe_minimize`.

    Attributes
    ----------
    status : {"optimal", "infeasible", "failed"}
        ``"infeasible"`` is only returned with a certificate (see module docstring).
    bound : float
        Rigorous lower bound of the minimum (``+inf`` if certified infeasible,
        ``-inf`` if nothing could be certified).
    value : float
        The solver's own (uncertified) objective value, or NaN.
    x : ndarray or None
        The solver's primal point.
    message : str
    """

    status: str
    bound: float
    value: float
    x: np.ndarray | None
    message: str = ""


def _csr(a, n):
    if a is None:
        return sp.csr_matrix((0, n))
    return sp.csr_matrix(a)


def dual_bound(c, A_ub, b_ub, A_eq, b_eq, lb, ub, y_ub, y_eq) -> float:
    """Rigorous lower bound of the LP from arbitrary multipliers (see module docstring)."""
    c = np.asarray(c, dtype=float)
    y_ub = np.minimum(np.asarray(y_ub, dtype=float), 0.0)
    y_eq = np.asarray(y_eq, dtype=float)
    r = c - A_eq.T @ y_eq - A_ub.T @ y_ub
    terms = np.concatenate([y_eq * b_eq, y_ub * b_ub, np.minimum(r * lb, r * ub)])
    if not np.all(np.isfinite(terms)):
        return -np.inf
    total = float(np.sum(terms))
    # rounding: the residual r and the sum each carry at most ~ (nnz + n) eps relative error
    mag = float(
        np.sum(np.abs(terms))
        + np.abs(A_eq).T @ np.abs(y_eq) @ np.maximum(np.abs(lb), np.abs(ub))
        + np.abs(A_ub).T @ np.abs(y_ub) @ np.maximum(np.abs(lb), np.abs(ub))
    )
    width = max(A_ub.shape[0], A_eq.shape[0]) + terms.size
    return total - 4.0 * width * EPS * (mag + 1e-300) - 1e-300


def safe_minimize(c, A_ub=None, b_ub=None, A_eq=None, b_eq=None, bounds=None,
                  options=None) -> SafeLPResult:
    """Minimise ``c'z`` with a rigorous lower bound. ``bounds`` must be a finite ``(n, 2)`` array.

    Uses HiGHS through :func:`scipy.optimize.linprog` for the numbers and weak duality for
    the guarantee. ``options`` (e.g. tighter ``primal_feasibility_tolerance``) go to HiGHS;
    they change the accuracy of the primal point, never the validity of ``bound``.
    """
    c = np.asarray(c, dtype=float)
    n = c.size
    bounds = np.asarray(bounds, dtype=float)
    if bounds.shape != (n, 2) or not np.all(np.isfinite(bounds)):
        raise ValueError("safe_minimize needs finite bounds of shape (n, 2) on every variable.")
    lb, ub = bounds[:, 0], bounds[:, 1]
    A_ub = _csr(A_ub, n)
    A_eq = _csr(A_eq, n)
    b_ub = np.zeros(0) if b_ub is None else np.asarray(b_ub, dtype=float)
    b_eq = np.zeros(0) if b_eq is None else np.asarray(b_eq, dtype=float)
    if np.any(lb > ub):
        return SafeLPResult(INFEASIBLE, np.inf, np.nan, None, "empty variable box")
    res = linprog(
        c,
        A_ub=A_ub if A_ub.shape[0] else None,
        b_ub=b_ub if A_ub.shape[0] else None,
        A_eq=A_eq if A_eq.shape[0] else None,
        b_eq=b_eq if A_eq.shape[0] else None,
        bounds=bounds,
        method="highs",
        options=options,
    )
    if res.status == 0:
        y_ub = res.ineqlin.marginals if A_ub.shape[0] else np.zeros(0)
        y_eq = res.eqlin.marginals if A_eq.shape[0] else np.zeros(0)
        bnd = dual_bound(c, A_ub, b_ub, A_eq, b_eq, lb, ub, y_ub, y_eq)
        return SafeLPResult(OPTIMAL, bnd, float(res.fun), res.x, res.message)
    if res.status == 2:
        if certify_infeasible(A_ub, b_ub, A_eq, b_eq, lb, ub):
            return SafeLPResult(INFEASIBLE, np.inf, np.nan, None, "certified infeasible")
        return SafeLPResult(FAILED, -np.inf, np.nan, None, "infeasibility not certified")
    return SafeLPResult(FAILED, -np.inf, np.nan, None, str(res.message))


def certify_infeasible(A_ub, b_ub, A_eq, b_eq, lb, ub, time_limit=None) -> bool:
    """True only if the phase-1 LP has a *rigorous* positive minimum total violation
    (``time_limit`` seconds for it, None: no limit; a stopped phase 1 certifies nothing)."""
    n = lb.size
    m_ub, m_eq = A_ub.shape[0], A_eq.shape[0]
    # worst violation of every row over the box (finite) bounds the slacks
    absb = np.maximum(np.abs(lb), np.abs(ub))
    smax_ub = np.abs(A_ub) @ absb + np.abs(b_ub) + 1.0
    smax_eq = np.abs(A_eq) @ absb + np.abs(b_eq) + 1.0
    # variables: z, s_ub (m_ub), s_p (m_eq), s_m (m_eq)
    c = np.concatenate([np.zeros(n), np.ones(m_ub + 2 * m_eq)])
    Aub = sp.hstack([A_ub, -sp.eye(m_ub), sp.csr_matrix((m_ub, 2 * m_eq))]).tocsr()
    Aeq = sp.hstack([A_eq, sp.csr_matrix((m_eq, m_ub)), sp.eye(m_eq), -sp.eye(m_eq)]).tocsr()
    bnds = np.vstack(
        [np.column_stack([lb, ub]), np.column_stack([np.zeros(m_ub), smax_ub]),
         np.column_stack([np.zeros(2 * m_eq), np.concatenate([smax_eq, smax_eq])])]
    )
    res = safe_minimize(c, Aub, b_ub, Aeq, b_eq, bnds,
                        options=None if time_limit is None else {"time_limit": time_limit})
    return res.status == OPTIMAL and res.bound > 0.0


def row_dual_bound(c, A, rl, ru, lb, ub, y, *, with_reduced=False):
    """Rigorous lower bound of ``min c'z, rl <= Az <= ru, lb <= z <= ub`` from multipliers ``y``.

    Parameters
    ----------
    c : ndarray, shape (n,)
    A : scipy.sparse matrix, shape (m, n)
    rl, ru : ndarray, shape (m,)
        Row bounds (``-inf`` / ``+inf`` allowed).
    lb, ub : ndarray, shape (n,)
        Finite column bounds.
    y : ndarray, shape (m,)
        Any multipliers (e.g. HiGHS row duals, or a dual ray with ``c = 0``).

    with_reduced : bool, default False
        Also return the reduced costs ``r = c - A'(y+ + y-)`` behind the bound.

    Returns
    -------
    float or (float, ndarray or None)
        A lower bound of the exact LP value (``-inf`` if none can be certified); with
        ``with_reduced`` also ``r`` (shape (n,)). The bound depends on the column bounds
        only through ``sum_j min(r_j l_j, r_j u_j)``, so it stays valid, with that term
        updated, for any other column box (reduced-cost bound tightening).
    """
    y = np.asarray(y, dtype=float)
    if y.shape != (A.shape[0],) or not np.all(np.isfinite(y)):
        return (-np.inf, None) if with_reduced else -np.inf
    fin_l = np.isfinite(rl)
    fin_u = np.isfinite(ru)
    yp = np.where(fin_l, np.maximum(y, 0.0), 0.0)
    yn = np.where(fin_u, np.minimum(y, 0.0), 0.0)
    yy = yp + yn
    r = np.asarray(c, dtype=float) - A.T @ yy
    t_l = np.where(yp != 0.0, yp * np.where(fin_l, rl, 0.0), 0.0)
    t_u = np.where(yn != 0.0, yn * np.where(fin_u, ru, 0.0), 0.0)
    t_z = np.minimum(r * lb, r * ub)
    terms = np.concatenate([t_l, t_u, t_z])
    if not np.all(np.isfinite(terms)):
        return (-np.inf, None) if with_reduced else -np.inf
    total = float(np.sum(terms))
    absz = np.maximum(np.abs(lb), np.abs(ub))
    mag = float(np.sum(np.abs(terms)) + abs(A).T @ np.abs(yy) @ absz + np.abs(c) @ absz)
    width = A.shape[0] + terms.size
    bound = total - 4.0 * width * EPS * (mag + 1e-300) - 1e-300
    return (bound, r) if with_reduced else bound


def round_down(v):
    """Next float towards ``-inf`` (outward rounding of computed lower data)."""
    return np.nextafter(np.nextafter(v, -np.inf), -np.inf)


def round_up(v):
    """Next float towards ``+inf`` (outward rounding of computed upper data)."""
    return np.nextafter(np.nextafter(v, np.inf), np.inf)


def mul_down(a, b):
    """A float ``<= a * b`` (exact): the rounded product moved outward, except that a
    product with an exact zero factor stays ``0``.

    A product with a zero factor (a theta box edge at 0, an input-error bound of 0) is
    exact; rounding it outward gave ``-+1e-323`` (subnormal) bounds that HiGHS had to carry
    as nonzero data (its log listed bounds and right-hand sides down to ``1e-323``).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return np.where((a == 0.0) | (b == 0.0), 0.0, round_down(a * b))


def mul_up(a, b):
    """A float ``>= a * b`` (exact); see :func:`mul_down` (exact zeros stay ``0``)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return np.where((a == 0.0) | (b == 0.0), 0.0, round_up(a * b))
