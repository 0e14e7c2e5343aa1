"""Verified-feasible points of the EIV set (22.34) for the branch-and-bound
(:mod:`.bnb`): the screening LP and the pool of verified points.

:class:`_Screen` measures, fast and *unverified*, how far a fixed ``theta`` is from
explaining the data; :class:`_Pool` keeps the points that :func:`.problem.check_theta`
accepted, each with its witness noise sequences (the inner values of the intervals), and
searches for a first one when no relaxation point is feasible. A weaker screen only costs
time, never a bound: acceptance always goes through ``check_theta``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ...exceptions import SolverError
from ...solvers.highs import new_highs
from ..problem import EIVProblem, check_theta, equation_scale
from .local import colwise_structure, solve_colwise


@dataclass
class _Point:
    theta: np.ndarray
    eta: np.ndarray
    dx: np.ndarray


class _Screen:
    """Fast, *unverified* minimum violation of (22.34) at a fixed theta.

    Same LP as :func:`.problem.check_theta` (``min s`` with ``|M(theta) z - r(theta)| <= s``
    over the error boxes), kept on one HiGHS instance and warm-started from the previous
    basis. Only used to screen candidates; acceptance always goes through ``check_theta``.

    With ``working_set=True`` (long records) the LP holds only a growing subset of the
    equations, after an interval test of all of them (:func:`.working_set.interval_excess`,
    whose excess is a lower bound of ``s``); a candidate that passes is solved over all
    equations (:meth:`full`) before ``check_theta``, and a rejection there adds the binding
    equations to the subset. A weaker screen only costs time, never a bound.
    """

    def __init__(self, problem: EIVProblem, working_set: bool = False):
        import highspy

        pr = problem
        self.problem = pr
        n, k, na = pr.N, pr.n_groups, pr.na
        m = pr.equation_times.size
        eta_idx, dx_idx = pr.eta_index(), pr.dx_index()
        self.m, self.nz = m, n + k
        self._eta_idx, self._dx_idx = eta_idx, dx_idx
        self.na1, self.nbp = na + 1, dx_idx.shape[1]
        self.lb = np.concatenate([-pr.deta, -pr.dx_group, [0.0]])
        self.ub = np.concatenate([pr.deta, pr.dx_group, [highspy.kHighsInf]])
        self.working_set = bool(working_set)
        if self.working_set:
            from .working_set import EquationData, initial_equations

            self.data = EquationData(pr)
            self.in_set = np.zeros(m, dtype=bool)
            self.in_set[initial_equations(pr, pr.theta_box)] = True
            self._struct_full = None
        else:
            self.in_set = np.ones(m, dtype=bool)
        self._struct = None
        self.h = new_highs()  # no "threads" option: see _highs.new_highs
        self.bases = {}
        self._last = None
        self._last_eqs = None
        self._tol = None
        self._hs = highspy

    def _structure(self, eqs):
        """Fixed sparsity of A = [[M, -1], [M, 1]] on the equations ``eqs`` (column-major,
        duplicates summed): only the values depend on theta, gathered with one bincount."""
        n, k = self.problem.N, self.problem.n_groups
        m = eqs.size
        loc = np.arange(m)
        rows = np.concatenate([np.repeat(loc, self.na1), np.repeat(loc, self.nbp)])
        cols = np.concatenate([self._eta_idx[eqs].ravel(), n + self._dx_idx[eqs].ravel()])
        rows2 = np.concatenate([rows, rows + m, loc, loc + m])
        cols2 = np.concatenate([cols, cols, np.full(2 * m, n + k)])
        st = colwise_structure(rows2, cols2, n + k + 1)
        st.update(eqs=eqs, ones=np.concatenate([-np.ones(m), np.ones(m)]))
        return st

    def violation(self, theta) -> float:
        theta = np.asarray(theta, dtype=float)
        if self._last is not None and np.array_equal(self._last[0], theta):
            return self._last[1]
        v = self._violation(theta)
        self._last = (theta.copy(), v)
        return v

    def binding(self, theta) -> np.ndarray:
        """Equations (indices) with a non-zero multiplier in the screening LP at ``theta``.

        Empty when ``theta`` screens feasible. Otherwise these rows carry the certificate
        that no errors explain the data at ``theta`` (the working-set separation,
        :meth:`.working_set.WorkingSetRelaxation.separate`).
        """
        v = self.violation(theta)
        if not np.isfinite(v) or v <= self.tol_at(theta) or self._last_eqs is None:
            return np.zeros(0, dtype=np.int64)
        return self._last_eqs

    def full(self, theta):
        """Working-set mode: solve the screening LP over *all* equations at ``theta``.

        Returns ``(violation, (eta, dx) or None)``; when ``theta`` does not screen, the
        binding equations join the working set. The solution is only a candidate witness
        for :func:`check_theta`, which judges it by its own rule.
        """
        if self._struct_full is None:
            self._struct_full = self._structure(np.arange(self.m))
        theta = np.asarray(theta, dtype=float)
        v = self._solve(theta, self._struct_full, "full")
        self._last = None
        if not np.isfinite(v):
            return v, None
        if v > self.tol_at(theta):
            if self._last_eqs is not None:
                self.in_set[self._last_eqs] = True
                self._struct = None
            return v, None
        z = np.asarray(self.h.getSolution().col_value)
        n = self.problem.N
        return v, (z[:n], z[n : self.nz])

    def _violation(self, theta) -> float:
        self._last_eqs = None
        if self.working_set:
            from .working_set import ADD_PER_ROUND

            r, err, _ = self.data.terms(theta)
            exc = np.abs(r) - err  # s >= exc_t for every equation t
            worst = float(np.max(exc, initial=-np.inf))
            if worst > self.tol_at(theta):
                bad = np.flatnonzero(exc > self.tol_at(theta))
                self._last_eqs = bad[np.argsort(-exc[bad])[:ADD_PER_ROUND]]
                self.in_set[self._last_eqs] = True
                self._struct = None
                return worst
        if self._struct is None:
            self._struct = self._structure(np.flatnonzero(self.in_set))
            self.bases.pop("set", None)
        return self._solve(theta, self._struct, "set")

    def _solve(self, theta, st, keep) -> float:
        hs = self._hs
        pr = self.problem
        a, b = theta[: pr.na], theta[pr.na :]
        eqs = st["eqs"]
        m, nz = eqs.size, self.nz
        vals = np.concatenate([np.tile(np.concatenate([[1.0], a]), m), np.tile(-b, m)])
        r = pr.simulate_noise_free(theta)[eqs]
        c = np.zeros(nz + 1)
        c[-1] = 1.0
        self.bases[keep] = solve_colwise(
            self.h, st, np.concatenate([vals, vals, st["ones"]]), c, self.lb, self.ub,
            np.concatenate([np.full(m, -hs.kHighsInf), r]),
            np.concatenate([r, np.full(m, hs.kHighsInf)]), self.bases.get(keep))
        if self.bases[keep] is None:
            return np.inf
        v = float(self.h.getInfo().objective_function_value)
        if v > self.tol_at(theta):
            y = np.abs(np.asarray(self.h.getSolution().row_dual))
            w = y[:m] + y[m:]
            self._last_eqs = eqs[w > 1e-9 * max(float(w.max(initial=0.0)), 1e-300)]
        return v

    def tol_at(self, theta) -> float:
        """Screening tolerance: the strictest equation tolerance of :func:`check_theta`."""
        from ...tolerances import FEASIBILITY_RTOL

        theta = np.asarray(theta, dtype=float)
        if self._tol is None or not np.array_equal(self._tol[0], theta):
            scale = self.data.terms(theta)[2] if self.working_set else \
                equation_scale(self.problem, theta)
            self._tol = (theta.copy(), FEASIBILITY_RTOL * float(np.min(scale)))
        return self._tol[1]

    def screens(self, theta) -> bool:
        return self.violation(theta) <= self.tol_at(theta)


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
            if np.isfinite(v) and hint is None:
                return None
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

    def add(self, theta) -> _Point | None:
        """Screen, then verify (nothing once ``stop_at`` has passed)."""
        if self._out_of_time():
            return None
        self._ensure_screen()
        if not self.screen.screens(theta):
            return None
        return self.verify(theta)

    def seek(self, starts, box, max_evals=800, deadline=None) -> _Point | None:
        """Look for a first verified point when none of the LP points is feasible.

        Thin feasible sets (the two-level inner signal, high noise) may contain none of the
        relaxation's points. Starting from ``starts`` (projected onto the gain equality
        (22.8), if any), Nelder-Mead minimises the screening violation (zero on the set)
        plus the distance outside ``box``, in the coordinates of the gain hyperplane; the
        first screened point that :func:`check_theta` accepts is returned. The search gives
        up (returns None) at ``deadline`` (a :func:`time.time` timestamp), if given.
        """
        from scipy.optimize import minimize

        self._ensure_screen()
        pr = self.problem
        g = pr.gain_row()
        p = pr.p
        if g is None:
            basis = np.eye(p)
        else:
            # orthonormal basis of {d : g . d = 0}
            basis = np.linalg.svd(g[0][None, :])[2][1:].T

        class _Found(Exception):
            pass

        class _Stop(Exception):
            pass

        for start in starts:
            th0 = _on_gain_plane(pr, start)

            def f(z, th0=th0):
                if deadline is not None and time.time() > deadline:
                    raise _Stop
                th = th0 + basis @ z
                out = np.maximum(box[:, 0] - th, 0.0) + np.maximum(th - box[:, 1], 0.0)
                if out.any():
                    return float(np.sum(out)) + 1.0
                v = self.screen.violation(th)
                if v <= self.screen.tol_at(th) and self.verify(th) is not None:
                    raise _Found
                return v

            try:
                minimize(f, np.zeros(basis.shape[1]), method="Nelder-Mead",
                         options={"maxfev": max_evals, "xatol": 1e-12, "fatol": 0.0,
                                  "initial_simplex": None})
            except _Found:
                return self.points[-1]
            except _Stop:
                return None
        return None

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


def _on_gain_plane(problem, theta):
    """Orthogonal projection of ``theta`` onto the gain equality (22.8), if there is one."""
    theta = np.asarray(theta, dtype=float)
    g = problem.gain_row()
    if g is None:
        return theta
    return theta + g[0] * (g[1] - g[0] @ theta) / float(g[0] @ g[0])
