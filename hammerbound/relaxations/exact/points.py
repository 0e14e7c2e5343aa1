"""Verified-feasible points of the EIV set (22.34) for the branch-and-bound
(:mod:`.bnb`): the screening LP and the pool of verified points.

The screen is the shared fixed-theta witness LP
(:class:`~hammerbound.relaxations.witness.WitnessLP`, also the sampler's): it measures, fast
and *unverified*, how far a fixed ``theta`` is from explaining the data; :class:`_Pool`
keeps the points that :func:`.problem.check_theta` accepted, each with its witness noise
sequences (the inner values of the intervals), and searches for a first one when no
relaxation point is feasible. A weaker screen only costs time, never a bound: acceptance
always goes through ``check_theta``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ...exceptions import SolverError
from ...solvers.highs_process import past, seconds_left, wall_stamp
from ..problem import EIVProblem, check_theta
from ..witness import WitnessLP, fixed_theta_matrix, seek_feasible
from ..witness import on_gain_plane as _on_gain_plane  # noqa: F401 - used by bnb

#: the branch-and-bound's screen is the shared fixed-theta witness LP
_Screen = WitnessLP


@dataclass
class _Point:
    theta: np.ndarray
    eta: np.ndarray
    dx: np.ndarray


@dataclass
class _Pool:
    """Verified-feasible points found so far (plus the screening LP)."""

    problem: EIVProblem
    points: list = field(default_factory=list)
    screen: _Screen | None = None
    checks: int = 0
    stop_at: float | None = None  # time.perf_counter() after which heuristics give up
    working_set: bool = False  # screen on a working set of equations (long records)
    local: object = None  # the SLP step's LP (.local.LinearisedSet), made on first use

    def _out_of_time(self) -> bool:
        return self.stop_at is not None and time.perf_counter() > self.stop_at

    def verify(self, theta) -> _Point | None:
        """Accept ``theta`` only if :func:`check_theta` says it is feasible."""
        self.checks += 1
        hint = None
        if self.working_set:
            # the full screening LP (warm-started) first: a rejection costs no check_theta,
            # and its solution is the candidate witness that check_theta judges
            self._ensure_screen()
            v, hint = self.screen.full(theta)
            if hint is None and (np.isfinite(v) or self._out_of_time()):
                return None  # rejected, or its LP stopped at the pool's end: not accepted
        try:
            chk = check_theta(self.problem, theta, witness=hint)
        except SolverError:  # not verified: simply not accepted as a witness
            return None
        if not chk.feasible:
            return None
        pt = _Point(np.array(theta, dtype=float), chk.eta, chk.dx)
        self.points.append(pt)
        return pt

    def _ensure_screen(self):
        if self.screen is None:
            self.screen = _Screen(self.problem, working_set=self.working_set)
        if self.stop_at is not None:  # the screening LPs stop with the pool too
            self.screen.deadline = wall_stamp(self.stop_at)

    def add(self, theta) -> _Point | None:
        """Screen, then verify (nothing once ``stop_at`` has passed)."""
        if self._out_of_time():
            return None
        self._ensure_screen()
        if not self.screen.screens(theta):
            return None
        return self.verify(theta)

    def _b_linear_at_fixed_a(self) -> bool:
        """Whether the equations at fixed ``a`` are linear in ``b`` (no input errors, so no
        products ``b_j dx``): what :meth:`complete` needs."""
        return not self.problem.has_input_errors

    def complete(self, theta, k, sense) -> _Point | None:
        """Without input errors, keep ``theta``'s ``a`` and choose its ``b`` by an LP, then
        verify (:func:`b_for_a`). Finds points of thin sets that the fixed-``theta``
        screen misses: the node LP's ``a`` often lies in the set when its ``b`` does not."""
        if self._out_of_time() or not self._b_linear_at_fixed_a():
            return None
        b = b_for_a(self.problem, theta, k, sense)
        if b is None:
            return None
        th = np.array(theta, dtype=float)
        th[self.problem.na:] = b
        return self.verify(th)

    def complete_line(self, inside, outside, k, sense, steps=12, resolution=0.0):
        """Bisection between a verified point ``inside`` and ``outside`` on ``a`` only, each
        ``a`` completed by :meth:`complete` (its ``b`` re-chosen): on a thin set the segment
        of whole ``theta`` leaves the set at once, while the ``a`` part stays in it longer.
        Returns the verified point nearest ``outside`` (None: none better than
        ``inside``)."""
        if not self._b_linear_at_fixed_a():
            return None
        na = self.problem.na
        d = np.asarray(outside, dtype=float) - np.asarray(inside, dtype=float)
        span = abs(float(d[k])) if k < na else np.inf
        lo, hi, best = 0.0, 1.0, None
        for _ in range(steps):
            if (hi - lo) * span <= resolution or self._out_of_time():
                break
            mid = 0.5 * (lo + hi)
            pt = self.complete(np.asarray(inside, dtype=float) + mid * d, k, sense)
            if pt is not None:
                lo, best = mid, pt
            else:
                hi = mid
        return best

    def seek(self, starts, box, max_evals=800, deadline=None) -> _Point | None:
        """Look for a first verified point when none of the LP points is feasible
        (:func:`~hammerbound.relaxations.witness.seek_feasible` with :meth:`verify`)."""
        self._ensure_screen()
        return seek_feasible(self.problem, self.screen, self.verify, starts, box,
                             max_evals=max_evals, deadline=deadline)

    def line_search(self, inside, outside, steps=20, k=None, resolution=0.0) -> _Point | None:
        """Verified point on the segment ``inside -> outside`` closest to ``outside``.

        ``inside`` must be (verified) feasible; bisection on the screening LP, then
        verification with :func:`check_theta` (backing off towards ``inside`` if needed).
        The bisection stops early once the bracket on ``theta_k`` is below ``resolution``.
        """
        self._ensure_screen()
        lo, hi = 0.0, 1.0
        d = outside - inside
        span = abs(float(d[k])) if k is not None else np.inf
        for _ in range(steps):
            if (hi - lo) * span <= resolution or self._out_of_time():
                break
            mid = 0.5 * (lo + hi)
            if self.screen.screens(inside + mid * d):
                lo = mid
            else:
                hi = mid
        for _ in range(3):
            if lo <= 0.0 or self._out_of_time():
                return None
            pt = self.verify(inside + lo * d)
            if pt is not None:
                return pt
            lo *= 0.5
        return None


#: relative margin by which :func:`b_for_a` keeps the output errors inside their bounds (the
#: point then passes :func:`check_theta`, whose tolerance is far smaller)
B_FOR_A_MARGIN = 1e-7


def _fixed_a_lp(problem: EIVProblem, a, cost_b, cost_s, s_range, deadline=None):
    """The LP at fixed ``a`` (no input errors): variables ``[b (nb), eta (N), s]`` with
    ``M(a) eta - phi_b b = yt + phi_a a`` (and the gain row), ``|eta| <= deta (1 - s)``,
    ``b`` in the a priori box, ``s`` in ``s_range``; minimises ``cost_b . b + cost_s s``.
    Returns scipy's result; an LP that reaches ``deadline`` (:func:`time.time`) stops
    with a nonzero status."""
    from scipy.optimize import linprog

    pr = problem
    na, p, n = pr.na, pr.p, pr.N
    theta = np.r_[np.asarray(a, dtype=float)[:na], np.zeros(p - na)]
    phi, yt = pr.regressors()
    m_eta = fixed_theta_matrix(pr, theta).tocsc()[:, :n]
    nb = p - na
    deta = np.asarray(pr.deta, dtype=float)
    a_eq = sp.hstack([sp.csc_matrix(-phi[:, na:]), m_eta, sp.csc_matrix((m_eta.shape[0], 1))])
    b_eq = yt + phi[:, :na] @ theta[:na]
    g = pr.gain_row()
    if g is not None:
        a_eq = sp.vstack([a_eq, sp.csc_matrix(np.r_[g[0][na:], np.zeros(n + 1)][None, :])])
        b_eq = np.r_[b_eq, g[1] - g[0][:na] @ theta[:na]]
    eye = sp.eye(n, format="csc")
    a_ub = sp.vstack([sp.hstack([sp.csc_matrix((n, nb)), eye, sp.csc_matrix(deta[:, None])]),
                      sp.hstack([sp.csc_matrix((n, nb)), -eye, sp.csc_matrix(deta[:, None])])])
    b_ub = np.r_[deta, deta]
    c = np.r_[np.asarray(cost_b, dtype=float), np.zeros(n), cost_s]
    bounds = [tuple(r) for r in pr.theta_box[na:]] + [(None, None)] * n + [tuple(s_range)]
    kw = dict(A_ub=a_ub, b_ub=b_ub, A_eq=a_eq.tocsr(), b_eq=b_eq, bounds=bounds,
              method="highs")
    res = linprog(c, **kw, options=_time_option(deadline))
    if res.status == 4:  # HiGHS's presolve often ends "not set" on these LPs (review)
        res = linprog(c, **kw, options={"presolve": False, **_time_option(deadline)})
    return res


def _time_option(deadline):
    """linprog's ``time_limit`` for an LP that must end by ``deadline`` (none: {})."""
    return {} if deadline is None else {"time_limit": seconds_left(np.inf, deadline)}


def b_for_a(problem: EIVProblem, theta, k: int, sense: float) -> np.ndarray | None:
    """The ``b`` (inside the a priori box) that, with ``theta``'s ``a`` fixed, explains the
    data with errors inside their bounds, or None (unverified: the caller checks it).

    Without input errors the equations (22.34) at fixed ``a`` are linear in ``b`` and the
    output errors ``eta``, so this is one LP: for an end of a ``b_j`` (``k >= na``) the
    ``b`` that minimises ``sense * b_k`` with the errors ``B_FOR_A_MARGIN`` inside their
    bounds; for an end of an ``a_i``, the ``b`` with the errors deepest inside.
    """
    na, nb = problem.na, problem.p - problem.na
    cost_b = np.zeros(nb)
    if k >= na:
        cost_b[k - na] = sense
        res = _fixed_a_lp(problem, theta, cost_b, 0.0, (B_FOR_A_MARGIN, B_FOR_A_MARGIN))
    else:
        res = _fixed_a_lp(problem, theta, cost_b, -1.0, (B_FOR_A_MARGIN, 0.5))
    return res.x[:nb].copy() if res.status == 0 else None


def a_margin(problem: EIVProblem, a, deadline=None) -> tuple[float, np.ndarray | None]:
    """``(s, b)``: the largest ``s`` such that, with ``A`` fixed to ``a``, some ``b`` in the
    a priori box explains the data with every output error within ``(1 - s)`` of its bound
    (no input errors; one LP). ``s >= 0`` exactly when ``a`` is the ``a`` of a point of
    the set; ``(-inf, None)`` if the LP fails or reaches ``deadline``."""
    nb = problem.p - problem.na
    res = _fixed_a_lp(problem, a, np.zeros(nb), -1.0, (None, 0.5), deadline)
    if res.status != 0:
        return -np.inf, None
    return float(res.x[-1]), res.x[:nb].copy()


#: evaluations (LPs) of :func:`seek_a`'s search; measured on a new-user trial's
#: output-error record (N = 2000, Delta eta = 0.02, na = 2): 45 LPs, 8 s, where the other
#: searches found no point in 240 s
SEEK_A_EVALS = 200
#: the value :func:`seek_a` minimises where an LP fails (an inf in Nelder-Mead's simplex
#: makes scipy warn and stall)
FAILED_LP_PENALTY = 1e6


def seek_a(problem: EIVProblem, start, box, verify, max_evals=SEEK_A_EVALS, deadline=None):
    """A first verified point of an output-error problem (no input errors): Nelder-Mead
    maximises :func:`a_margin` over ``a`` (inside ``box``'s rows of ``a``) from ``start``;
    the first ``a`` whose margin reaches :data:`B_FOR_A_MARGIN` is completed with its
    ``b`` and passed to ``verify`` (e.g. :meth:`_Pool.verify`), whose result is returned.
    None at ``max_evals`` or ``deadline`` (:func:`time.time`). The ``b`` eliminated, the
    search runs in ``na`` dimensions, where the set is a sliver that the fixed-theta
    searches in all ``p`` do not hit."""
    from scipy.optimize import minimize

    na = problem.na
    lo, hi = box[:na, 0], box[:na, 1]
    found = []

    class _Done(Exception):
        pass

    def neg_margin(a):
        if past(deadline):
            raise _Done
        a = np.clip(a, lo, hi)
        s, b = a_margin(problem, a, deadline)
        if s >= B_FOR_A_MARGIN:
            pt = verify(np.r_[a, b])
            if pt is not None:
                found.append(pt)
                raise _Done
        return -s if np.isfinite(s) else FAILED_LP_PENALTY  # no inf in the simplex

    a0 = np.clip(np.asarray(start, dtype=float)[:na], lo, hi)
    simplex = np.vstack([a0, a0 + np.diag(0.25 * (hi - lo))])
    try:
        minimize(neg_margin, a0, method="Nelder-Mead",
                 options={"maxfev": int(max_evals), "initial_simplex": simplex,
                          "xatol": 0.0, "fatol": 0.0})
    except _Done:
        pass
    return found[0] if found else None
