"""The fixed-theta witness LP of the EIV set (22.34), shared by the exact method and the
sampler: :class:`WitnessLP` (one warm-started HiGHS instance for many ``theta``) and
:func:`seek_feasible` (a first feasible point by minimising its violation).

At fixed ``theta`` the constraints of (22.34) are linear in the errors ``(eta, dx)``:
``min s`` s.t. ``|M(theta) z - r(theta)| <= s`` over the error boxes. The solver's answer is
only ever a *candidate*: a point is accepted by the rule of :func:`.problem.check_theta`
(the witness clipped to the boxes, its residuals recomputed), never by the solver's value.
A weaker screen only costs time, never a bound.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..solvers.highs_process import new_highs, past
from .exact.local import colwise_structure, solve_colwise
from .problem import EIVProblem, equation_scale

__all__ = ["WitnessLP", "fixed_theta_matrix", "seek_feasible"]


def fixed_theta_matrix(problem: EIVProblem, theta) -> sp.csr_matrix:
    """``M(theta)`` (equations x errors ``[eta; dx]``): the equations (22.34) at fixed
    ``theta`` read ``M(theta) z = r(theta)`` (``r``: :meth:`EIVProblem.simulate_noise_free`)."""
    pr = problem
    theta = np.asarray(theta, dtype=float)
    m = pr.equation_times.size
    a, b = theta[: pr.na], theta[pr.na :]
    dx_idx = pr.dx_index()
    rows = np.concatenate([np.repeat(np.arange(m), pr.na + 1),
                           np.repeat(np.arange(m), dx_idx.shape[1])])
    cols = np.concatenate([pr.eta_index().ravel(), pr.N + dx_idx.ravel()])
    vals = np.concatenate([np.tile(np.concatenate([[1.0], a]), m), np.tile(-b, m)])
    return sp.csr_matrix((vals, (rows, cols)), shape=(m, pr.N + pr.n_groups))


class WitnessLP:
    """The fixed-theta LP of (22.34) on one warm-started HiGHS instance.

    Same LP as :func:`.problem.check_theta` (``min s`` with ``|M(theta) z - r(theta)| <= s``
    over the error boxes), kept on one HiGHS instance and warm-started from the previous
    basis, for many ``theta``: :meth:`violation` / :meth:`screens` (fast and *unverified*:
    the branch-and-bound's screen) and :meth:`witness` (a candidate witness, clipped to the
    boxes and judged by the rule of :func:`check_theta`: the sampler's membership test).

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
            from .exact.working_set import EquationData, initial_equations

            self.data = EquationData(pr)
            self.in_set = np.zeros(m, dtype=bool)
            self.in_set[initial_equations(pr, pr.theta_box)] = True
            self._struct_full = None
        else:
            self.in_set = np.ones(m, dtype=bool)
        self._struct = None
        #: :func:`time.time` stamp at which a screening LP stops (None: only the run
        #: limit); a stopped LP screens nothing (violation +inf)
        self.deadline = None
        self.h = new_highs()  # no "threads" option: see solvers.highs_process.new_highs
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
        # an LP stopped by its deadline (+inf) is not remembered: it says nothing of theta
        self._last = (theta.copy(), v) if np.isfinite(v) else None
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
            from .exact.working_set import ADD_PER_ROUND

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
            np.concatenate([r, np.full(m, hs.kHighsInf)]), self.bases.get(keep),
            deadline=self.deadline)
        if self.bases[keep] is None:
            return np.inf
        v = float(self.h.getInfo().objective_function_value)
        if v > self.tol_at(theta):
            y = np.abs(np.asarray(self.h.getSolution().row_dual))
            w = y[:m] + y[m:]
            self._last_eqs = eqs[w > 1e-9 * max(float(w.max(initial=0.0)), 1e-300)]
        return v

    def witness(self, theta):
        """``(z, relative violation)`` at ``theta`` or None when HiGHS gives no optimum.

        ``z = [eta; dx]`` is the LP's solution clipped to the error boxes and the violation
        is recomputed from it in numpy (``max_t |M z - r|_t / equation_scale_t``), as
        :func:`check_theta` judges a witness: acceptance (``<= FEASIBILITY_RTOL``) rests
        on that recomputation, not on the solver. Always over every equation.
        """
        theta = np.asarray(theta, dtype=float)
        if self.working_set:
            if self._struct_full is None:
                self._struct_full = self._structure(np.arange(self.m))
            st, keep = self._struct_full, "full"
        else:
            if self._struct is None:
                self._struct = self._structure(np.arange(self.m))
            st, keep = self._struct, "set"
        self._last = None
        if not np.isfinite(self._solve(theta, st, keep)):
            return None
        z = np.clip(np.asarray(self.h.getSolution().col_value)[: self.nz], self.lb[: self.nz],
                    self.ub[: self.nz])
        pr = self.problem
        if self.m == 0:
            return z, 0.0
        resid = np.abs(fixed_theta_matrix(pr, theta) @ z - pr.simulate_noise_free(theta))
        return z, float(np.max(resid / equation_scale(pr, theta)))

    def tol_at(self, theta) -> float:
        """Screening tolerance: the strictest equation tolerance of :func:`check_theta`."""
        from ..tolerances import FEASIBILITY_RTOL

        theta = np.asarray(theta, dtype=float)
        if self._tol is None or not np.array_equal(self._tol[0], theta):
            scale = self.data.terms(theta)[2] if self.working_set else \
                equation_scale(self.problem, theta)
            self._tol = (theta.copy(), FEASIBILITY_RTOL * float(np.min(scale)))
        return self._tol[1]

    def screens(self, theta) -> bool:
        return self.violation(theta) <= self.tol_at(theta)


def seek_feasible(problem: EIVProblem, screen: WitnessLP, accept, starts, box, max_evals=800,
                  deadline=None):
    """A first accepted point of the EIV set, or None.

    Thin feasible sets (the two-level inner signal, high noise) may contain none of the
    relaxation's points. Starting from ``starts`` (projected onto the gain equality
    (22.8), if any), Nelder-Mead minimises the screening violation (zero on the set)
    plus the distance outside ``box``, in the coordinates of the gain hyperplane; the
    first screened point that ``accept(theta)`` accepts (anything but None, e.g. a
    :func:`check_theta`-based verifier) is returned as ``accept``'s result. The search
    gives up (returns None) at ``deadline`` (a :func:`time.time` timestamp), if given;
    the screening LPs stop there too.
    """
    pr = problem
    g = pr.gain_row()
    if g is None:
        basis = np.eye(pr.p)
    else:
        # orthonormal basis of {d : g . d = 0}
        basis = np.linalg.svd(g[0][None, :])[2][1:].T
    old = screen.deadline
    if deadline is not None:  # the screening LPs stop there too
        screen.deadline = deadline if old is None else min(old, deadline)
    try:
        return _nelder_mead_starts(pr, screen, accept, starts, box, basis, max_evals, deadline)
    finally:
        screen.deadline = old


def _nelder_mead_starts(pr, screen, accept, starts, box, basis, max_evals, deadline):
    """:func:`seek_feasible`'s search from each start in turn (see there)."""
    from scipy.optimize import minimize

    class _Found(Exception):
        pass

    class _Stop(Exception):
        pass

    for start in starts:
        th0 = on_gain_plane(pr, start)

        def f(z, th0=th0):
            if past(deadline):
                raise _Stop
            th = th0 + basis @ z
            out = np.maximum(box[:, 0] - th, 0.0) + np.maximum(th - box[:, 1], 0.0)
            if out.any():
                return float(np.sum(out)) + 1.0
            v = screen.violation(th)
            if v <= screen.tol_at(th):
                found = accept(th)
                if found is not None:
                    raise _Found(found)
            return v

        try:
            minimize(f, np.zeros(basis.shape[1]), method="Nelder-Mead",
                     options={"maxfev": max_evals, "xatol": 1e-12, "fatol": 0.0,
                              "initial_simplex": None})
        except _Found as hit:
            return hit.args[0]
        except _Stop:
            return None
    return None


def on_gain_plane(problem, theta):
    """Orthogonal projection of ``theta`` onto the gain equality (22.8), if there is one."""
    theta = np.asarray(theta, dtype=float)
    g = problem.gain_row()
    if g is None:
        return theta
    return theta + g[0] * (g[1] - g[0] @ theta) / float(g[0] @ g[0])
