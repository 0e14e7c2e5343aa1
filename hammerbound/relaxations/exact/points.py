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
from ...solvers.highs_process import wall_stamp
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


def b_for_a(problem: EIVProblem, theta, k: int, sense: float) -> np.ndarray | None:
    """The ``b`` (inside the a priori box) that, with ``theta``'s ``a`` fixed, explains the
    data with errors inside their bounds, or None (unverified: the caller checks it).

    Without input errors the equations (22.34) at fixed ``a`` are linear in ``b`` and the
    output errors ``eta``, so this is one LP: for an end of a ``b_j`` (``k >= na``) the
    ``b`` that minimises ``sense * b_k`` with the errors ``B_FOR_A_MARGIN`` inside their
    bounds; for an end of an ``a_i``, the ``b`` with the errors deepest inside.
    """
    from scipy.optimize import linprog

    pr = problem
    na, p, n = pr.na, pr.p, pr.N
    theta = np.asarray(theta, dtype=float)
    phi, yt = pr.regressors()
    m_eta = fixed_theta_matrix(pr, theta).tocsc()[:, :n]
    nb = p - na
    deta = np.asarray(pr.deta, dtype=float)
    # variables [b (nb), eta (n), s]: M eta - phi_b b = yt + phi_a a, |eta| <= deta (1 - s)
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
    c = np.zeros(nb + n + 1)
    if k >= na:
        c[k - na] = sense
        s_range = (B_FOR_A_MARGIN, B_FOR_A_MARGIN)
    else:
        c[-1] = -1.0
        s_range = (B_FOR_A_MARGIN, 0.5)
    bounds = [tuple(r) for r in pr.theta_box[na:]] + [(None, None)] * n + [s_range]
    res = linprog(c, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq.tocsr(), b_eq=b_eq, bounds=bounds,
                  method="highs")
    return res.x[:nb].copy() if res.status == 0 else None
