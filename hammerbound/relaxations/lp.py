"""Polytopic outer bounds of the EIV set (22.34) by linear programming.

This is the LP baseline of Cerone (1993) and Cerone & Regruto (2007) used in [6] of the
chapter. Every equation of (22.34) is decoupled from the others by bounding the unknown
errors by their worst case: with ``r_t(theta) = y_t + phi_t . theta``,

    |r_t(theta)| <= deta_t + sum_i |a_i| deta_{t-i} + sum_j |b_j| dx_{g(t-j)}.

Inside one of the ``2^p`` sign orthants ``s`` of theta (``s_k theta_k >= 0``) the absolute
values are linear, so the orthant's part of the outer set is the polytope::

    (phi_t - q_t) . theta <= deta_t - y_t,   (-phi_t - q_t) . theta <= deta_t + y_t,
    q_t = [s_i deta_{t-i} (i = 1..na), s_j dx_{g(t-j)} (j in b_lags)],

intersected with ``theta_box``, the orthant and the gain equality (22.8); every row's
right-hand side is relaxed outward by ``FEASIBILITY_RTOL`` times the magnitudes of its
terms (:mod:`hammerbound.tolerances`). The parameter
uncertainty intervals (22.35) of the union are the min/max over the feasible orthants.
Every reported number is a *guaranteed* bound (dual bound, see :mod:`._highs`).
"""

from __future__ import annotations

import dataclasses
import itertools
import time
import warnings

import numpy as np
import scipy.sparse as sp

from ..exceptions import EmptyFeasibleSetError, SolverError, UnboundedSetError
from ..solvers.highs import HighsLP
from ..solvers.highs_process import RUN_TIME_LIMIT
from ..status import BOX, LIMIT, OPTIMAL
from ..tolerances import feasibility_tol
from .problem import EIVProblem
from .result import BoundInfo, IntervalResult, LPDetails, Polytope
from .units import Units

__all__ = ["lp_bounds", "orthant_polytope"]


def orthant_box(problem: EIVProblem, signs) -> np.ndarray | None:
    """``theta_box`` intersected with the orthant ``signs`` (shape (p, 2)), or None if empty."""
    box = problem.theta_box.copy()
    s = np.asarray(signs)
    box[s > 0, 0] = np.maximum(box[s > 0, 0], 0.0)
    box[s < 0, 1] = np.minimum(box[s < 0, 1], 0.0)
    if np.any(box[:, 0] > box[:, 1]):
        return None
    return box


def orthant_polytope(problem: EIVProblem, signs, n_eq: int | None = None):
    """Halfspace description of the decoupled outer set in one sign orthant.

    Parameters
    ----------
    problem : EIVProblem
    signs : array_like of {-1, +1}, shape (p,)
        Orthant ``s_k theta_k >= 0``.
    n_eq : int, optional
        Use only the first ``n_eq`` equations (default: all).

    Returns
    -------
    A_ub : ndarray, shape (2 n_eq, p)
    b_ub : ndarray, shape (2 n_eq,)
    A_eq : ndarray, shape (0 or 1, p)
        Gain equality (22.8) if the problem has one.
    b_eq : ndarray, shape (0 or 1,)
    """
    phi, yt = problem.regressors()
    s = np.asarray(signs, dtype=float)
    m = phi.shape[0] if n_eq is None else int(n_eq)
    phi, yt = phi[:m], yt[:m]
    eta_idx = problem.eta_index()[:m]
    dx_idx = problem.dx_index()[:m]
    q = np.hstack([problem.deta[eta_idx[:, 1:]], problem.dx_group[dx_idx]]) * s[None, :]
    d = problem.deta[eta_idx[:, 0]]
    # tolerance policy (hammerbound.tolerances): every row is relaxed outward by the
    # relative tolerance of the magnitudes of its terms (at unit coefficients), so that
    # rounding in the data (e.g. noise exactly at +-deta) never cuts a consistent theta
    tol = feasibility_tol(yt, np.abs(phi).sum(axis=1), d, np.abs(q).sum(axis=1))
    A_ub = np.vstack([phi - q, -phi - q])
    b_ub = np.concatenate([d - yt + tol, d + yt + tol])
    g = problem.gain_row()
    if g is None:
        A_eq, b_eq = np.zeros((0, problem.p)), np.zeros(0)
    else:
        A_eq, b_eq = g[0][None, :], np.array([g[1]])
    return A_ub, b_ub, A_eq, b_eq


def _build_lp(problem, signs, box, n_eq=None) -> HighsLP:
    A_ub, b_ub, A_eq, b_eq = orthant_polytope(problem, signs, n_eq)
    A = sp.csc_matrix(np.vstack([A_ub, A_eq]))
    rl = np.concatenate([np.full(b_ub.size, -np.inf), b_eq])
    ru = np.concatenate([b_ub, b_eq])
    return HighsLP(A, rl, ru, box[:, 0], box[:, 1])


def _solve_orthant(problem, signs, box):
    """All ``2p`` guaranteed bounds in one orthant; None if certified infeasible."""
    p = problem.p
    t0 = time.perf_counter()
    lp = _build_lp(problem, signs, box)
    res = lp.solve()
    if res.status == "infeasible":
        return None
    lo, hi = box[:, 0].copy(), box[:, 1].copy()
    vlo = np.full(p, np.nan)
    vhi = np.full(p, np.nan)
    stopped = np.zeros((p, 2), dtype=bool)  # an LP stopped by its time limit
    iters = 0
    for k in range(p):
        for sense in (1.0, -1.0):
            c = np.zeros(p)
            c[k] = sense
            lp.set_cost(c)
            r = lp.solve()
            iters += r.iterations
            if r.status == "infeasible":
                return None
            if r.refused:
                # the LP bound is the first certified bound: nothing to fall back on
                raise SolverError(
                    f"the LP outer bound of {problem.param_names[k]} could not be computed: "
                    f"{r.note}. Rescaling the data (inputs and outputs of order one) "
                    f"usually helps.")
            # ended before optimality (its time limit): its dual bound is certified, maybe
            # weak, and the end's status says so
            stopped[k, 0 if sense > 0 else 1] = r.status != "optimal"
            if sense > 0:
                lo[k] = max(lo[k], r.bound)
                vlo[k] = r.value
            else:
                hi[k] = min(hi[k], -r.bound)
                vhi[k] = -r.value
    if np.any(lo > hi):  # only possible if the set is (numerically) a point; keep it
        mid = 0.5 * (lo + hi)
        lo, hi = np.minimum(lo, mid), np.maximum(hi, mid)
    return {"lo": lo, "hi": hi, "vlo": vlo, "vhi": vhi, "iterations": iters,
            "stopped": stopped, "time": time.perf_counter() - t0}


def _orthant_empty(problem, signs, box, n_eq) -> bool:
    lp = _build_lp(problem, signs, box, n_eq)
    return lp.solve().status == "infeasible"


def _all_empty(problem, orthants, n_eq) -> bool:
    return all(_orthant_empty(problem, s, b, n_eq) for s, b in orthants)


def _first_empty_equation(problem, orthants) -> int:
    """Smallest number of equations whose outer set is certified empty (bisection)."""
    lo, hi = 0, problem.equation_times.size
    if _all_empty(problem, orthants, 0):
        return 0
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if _all_empty(problem, orthants, mid):
            hi = mid
        else:
            lo = mid
    return hi


def touches_box(bounds, box) -> np.ndarray:
    """Boolean (p, 2): which bound coincides with the a priori box (to a relative 1e-9)."""
    w = np.maximum(1.0, box[:, 1] - box[:, 0])
    return np.column_stack([bounds[:, 0] <= box[:, 0] + 1e-9 * w,
                            bounds[:, 1] >= box[:, 1] - 1e-9 * w])


def box_limited_ends(bounds, box, names) -> list[tuple[int, str]]:
    """Interval ends that coincide with the a priori box: ``(k, "a2 upper")`` pairs."""
    touch = touches_box(bounds, box)
    return [(int(k), f"{names[k]} {'lower' if e == 0 else 'upper'}")
            for k, e in zip(*np.nonzero(touch), strict=True)]


def end_statuses(names, infos, bounds, box) -> tuple:
    """``(lower, upper)`` status per parameter: each end's solve status (from ``infos``),
    :data:`~hammerbound.status.BOX` where the end coincides with the a priori ``box``."""
    where = {n: k for k, n in enumerate(names)}
    st = [[None, None] for _ in names]
    for info in infos:
        st[where[info.param]][0 if info.sense == "min" else 1] = info.status
    for k, e in zip(*np.nonzero(touches_box(bounds, box)), strict=True):
        st[k][e] = BOX
    return tuple(tuple(pair) for pair in st)


def _statuses(names, infos, bounds, box, stopped) -> tuple:
    """:func:`end_statuses`, with :data:`~hammerbound.status.LIMIT` kept for an end whose
    LP ended before optimality even where it sits at the box (the box is then not the
    data's answer)."""
    st = end_statuses(names, infos, bounds, box)
    return tuple(tuple(LIMIT if stopped[k, e] else st[k][e] for e in (0, 1))
                 for k in range(len(names)))


def raise_if_box_limited(bounds, box, names, stopped=()) -> None:
    """Raise :class:`UnboundedSetError` when some interval end coincides with the box.

    ``stopped``: labels (``"name lower"``) of ends that a time or node limit stopped; at
    the box those are not the data's answer, and the message says so."""
    ends = [lab for _, lab in box_limited_ends(bounds, box, names)]
    if ends:
        raise UnboundedSetError(box_limit_message(ends, stopped))


def box_limit_message(ends, stopped=(), where="inside the a priori theta_box",
                      advice="a tighter theta_box") -> str:
    """Why the interval ends ``ends`` (labels ``"name lower"``) sit at their a priori box
    (``where``): the data's answer, or, for the labels in ``stopped``, a search that a
    limit stopped, whose answer is not known. ``advice`` completes "supply more (or more
    exciting) data or ...". One text for :func:`raise_if_box_limited` and the estimator's
    check of the default ``b_j`` box (:func:`hammerbound.stage2.fitting.check_box`)."""
    stopped = set(stopped)
    cut = [lab for lab in ends if lab in stopped]
    data = [lab for lab in ends if lab not in stopped]
    parts = []
    if data:
        parts.append(f"the data do not bound {', '.join(data)} {where}; supply more (or "
                     f"more exciting) data or {advice}")
    if cut:
        parts.append(f"no bound on {', '.join(cut)} {where}: the search stopped there (a "
                     "time or node limit, or a crash that a warning names), so whether the "
                     "data bound it is not known; if a limit stopped it, give the search "
                     "more time (total_time_limit, time_limit, max_nodes)")
    return "; ".join(parts) + "."


def lp_bounds(problem: EIVProblem, n_jobs: int = 1, *, check_box: bool = True) -> IntervalResult:
    """Guaranteed polytopic outer parameter uncertainty intervals (22.35) of (22.34).

    Parameters
    ----------
    problem : EIVProblem
        The EIV problem; ``problem.theta_box`` (shape (p, 2)) bounds every orthant LP.
    n_jobs : int, default 1
        Orthants are solved in parallel with joblib when ``n_jobs != 1``.
    check_box : bool, default True
        Raise :class:`UnboundedSetError` when a bound touches ``theta_box``.

    Returns
    -------
    IntervalResult
        ``method="lp"``; ``bounds`` (p, 2) are guaranteed to contain the intervals of the
        (nonconvex) EIV set; an end that coincides with ``theta_box`` has status
        :data:`~hammerbound.status.BOX`. ``polytopes`` lists, for every feasible orthant, a
        :class:`~hammerbound.relaxations.result.Polytope` with ``signs`` (p,), ``A`` (k, p),
        ``b`` (k,) such that the orthant's part of the outer set is ``{theta : A theta <= b}``
        (the box, the orthant and the gain equality are included as rows); ``details``
        counts the orthants (:class:`~hammerbound.relaxations.result.LPDetails`).

    Raises
    ------
    EmptyFeasibleSetError
        Every orthant is certified infeasible; ``first_index`` is the time ``t`` of the
        first equation at which the set becomes empty.
    UnboundedSetError
        A bound coincides with the a priori box (``check_box=True``).
    """
    units = Units.of(problem)
    return _results_back(_lp_bounds(units.problem(problem), n_jobs, check_box), units)


def _results_back(res: IntervalResult, units: Units) -> IntervalResult:
    """A result of the problem in ``units`` (:mod:`.units`), in the data's units: the
    ``b_j`` columns of bounds, ends and polytopes times the input factor (exact)."""
    if units.input == 1.0:
        return res
    f = units.factors(res.bounds.shape[0])  # theta_search = f * theta
    infos = tuple(dataclasses.replace(
        i, bound=i.bound / f[n // 2], solver_value=i.solver_value / f[n // 2])
        for n, i in enumerate(res.infos))
    polys = tuple(Polytope(q.signs, q.A * f, q.b) for q in res.polytopes)
    return dataclasses.replace(res, bounds=units.back(res.bounds), infos=infos,
                               polytopes=polys)


def _lp_bounds(problem: EIVProblem, n_jobs: int, check_box: bool) -> IntervalResult:
    """:func:`lp_bounds` on a problem in the units it is solved in."""
    t0 = time.perf_counter()
    p = problem.p
    orthants = []
    for s in itertools.product((-1, 1), repeat=p):
        box = orthant_box(problem, s)
        if box is not None:
            orthants.append((np.array(s), box))
    if n_jobs == 1 or len(orthants) < 2:
        sols = [_solve_orthant(problem, s, b) for s, b in orthants]
    else:
        from joblib import Parallel, delayed

        sols = Parallel(n_jobs=n_jobs)(delayed(_solve_orthant)(problem, s, b) for s, b in orthants)
    feas = [(o, r) for o, r in zip(orthants, sols, strict=True) if r is not None]
    if not feas:
        k = _first_empty_equation(problem, orthants)
        if k == 0:
            raise EmptyFeasibleSetError(
                "theta_box and the gain equality (22.8) have no common point; "
                "enlarge theta_box or check the gain.", first_index=None, relaxation="lp")
        t = int(problem.equation_times[k - 1])
        raise EmptyFeasibleSetError(
            f"no theta explains the data within the error bounds: the LP outer set of (22.34) "
            f"becomes empty at equation t = {t} (0-based sample index). Check the output error "
            f"bound (output_bound), the input error bound (input_bound) and the model orders "
            f"near that sample.",
            first_index=t, relaxation="lp")
    lo = np.min([r["lo"] for _, r in feas], axis=0)
    hi = np.max([r["hi"] for _, r in feas], axis=0)
    if not np.all(np.isfinite(lo)) or not np.all(np.isfinite(hi)):  # pragma: no cover
        raise SolverError("LP bounds are not finite although every variable is boxed.")
    bounds = np.column_stack([lo, hi])
    elapsed = time.perf_counter() - t0
    names = problem.param_names
    per = elapsed / (2 * p)
    iters = sum(r["iterations"] for _, r in feas)
    infos = []
    stopped = np.any([r["stopped"] for _, r in feas], axis=0)
    for k in range(p):
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN: every LP stopped
            vlo = np.nanmin([r["vlo"][k] for _, r in feas])
            vhi = np.nanmax([r["vhi"][k] for _, r in feas])
        for e, (sense, b, v) in enumerate((("min", lo[k], vlo), ("max", hi[k], vhi))):
            infos.append(BoundInfo(
                param=names[k], sense=sense, bound=float(b), solver_value=float(v),
                status=LIMIT if stopped[k, e] else OPTIMAL, certified=True, time=per,
                iterations=iters // (2 * p),
                message=f"union of {len(feas)} feasible sign orthant(s)"
                + ("; an LP ended before optimality (e.g. at its time limit of at most "
                   f"{RUN_TIME_LIMIT:g} s): a certified outer bound" if stopped[k, e] else ""),
            ))
    polys = []
    for (s, box), _ in feas:
        A_ub, b_ub, A_eq, b_eq = orthant_polytope(problem, s)
        eye = np.eye(p)
        A = np.vstack([A_ub, A_eq, -A_eq, eye, -eye])
        b = np.concatenate([b_ub, b_eq, -b_eq, box[:, 1], -box[:, 0]])
        polys.append(Polytope(s, A, b))
    if check_box:
        if stopped.any() and box_limited_ends(bounds, problem.theta_box, names):
            raise SolverError(
                "an LP of the outer bounds ended before optimality (e.g. at its time limit of "
                f"at most {RUN_TIME_LIMIT:g} s per LP) with an end still at theta_box, so it "
                "is not known whether the data bound it. Rescale the data (order one) or "
                "shorten the record.")
        raise_if_box_limited(bounds, problem.theta_box, names)
    return IntervalResult(
        param_names=tuple(names), bounds=bounds, infos=tuple(infos), method="lp", time=elapsed,
        status=_statuses(names, infos, bounds, problem.theta_box, stopped),
        polytopes=tuple(polys),
        details=LPDetails(len(orthants), len(feas)),
    )
