"""McCormick relaxation of (22.34) on a *working set* of equations (long records).

At large N most equations of (22.34) are inactive at the optimum of a node LP. The
relaxation :class:`WorkingSetRelaxation` holds the rows of only a subset ``S`` of the
equations (their product variables ``w`` and McCormick envelopes, built exactly as in
:class:`.mccormick.McCormickRelaxation`, relaxed outward by the same tolerances) and grows
``S`` on demand (:meth:`WorkingSetRelaxation.add_equations`, rows and columns appended to the
persistent HiGHS model, which keeps its basis).

**Why every bound stays certified.** Dropping constraints can only lower the minimum: the
LP on ``S`` is a relaxation of the full McCormick LP, itself a relaxation of the EIV set.
So the rigorous dual bound of the ``S``-LP (:mod:`._highs`) is a valid lower bound over
*all* equations, and an ``S``-LP certified infeasible certifies the full set empty. The
working set only decides how *tight* a node bound is, never whether it is valid.

**Separation** (which equations to add, :func:`interval_excess` and
:meth:`.points._Screen.binding`): at the LP point ``theta``, first cheap interval arithmetic
(an equation whose nominal residual exceeds its largest error term cannot hold at
``theta`` for any errors), then the equations that carry the infeasibility certificate of
the screening LP at ``theta`` (its binding rows). A node is only branched or closed once
no equation outside ``S`` is found violated at its LP point (or its bound closes it).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...solvers.highs import HighsLP
from ...solvers.safe_lp import mul_down, mul_up
from ...tolerances import FEASIBILITY_RTOL
from ..problem import EIVProblem, equation_scale
from .mccormick import McCormickBase, _node_options, _prod_bounds

#: use the working set by default from this many equations on (below, the full LP is cheap)
AUTO_MIN_EQUATIONS = 600
#: initial working set size and most equations added per separation round
INITIAL_SIZE = 24
ADD_PER_ROUND = 40
#: after this many re-solves of one LP, the working set doubles per round
#: (:meth:`WorkingSetRelaxation.separate`), and it takes every equation once it would pass
#: this fraction of them
GROW_AFTER = 8
GROW_ALL = 0.5


def initial_equations(problem: EIVProblem, box, size: int = INITIAL_SIZE) -> np.ndarray:
    """A first working set: the equations most violated at the box centre, plus a spread."""
    m = problem.equation_times.size
    size = min(size, m)
    spread = np.unique(np.linspace(0, m - 1, max(size // 2, 1)).round().astype(int))
    exc = interval_excess(problem, np.asarray(box, dtype=float).mean(axis=1))
    worst = np.argsort(-exc)[:size - spread.size]
    return np.unique(np.concatenate([spread, worst]))


class EquationData:
    """Per-equation data of (22.34) precomputed for fast interval tests at many theta."""

    def __init__(self, problem: EIVProblem):
        pr = self.problem = problem
        self.phi, self.yt = pr.regressors()
        self.abs_phi, self.abs_yt = np.abs(self.phi), np.abs(self.yt)
        self.eta_idx, self.dx_idx = pr.eta_index(), pr.dx_index()
        self.deta = pr.deta[self.eta_idx]  # (m, na + 1)
        self.dxb = pr.dx_group[self.dx_idx]  # (m, nbp)
        self._last = None

    def terms(self, theta):
        """``(r, err, scale)``: nominal residuals, largest error terms and equation scales
        (:func:`.problem.equation_scale`) at ``theta`` (each shape (n_eq,))."""
        theta = np.asarray(theta, dtype=float)
        if self._last is not None and np.array_equal(self._last[0], theta):
            return self._last[1]
        na = self.problem.na
        at = np.abs(theta)
        r = self.yt + self.phi @ theta
        err = self.deta @ np.concatenate([[1.0], at[:na]])
        if at.size > na:
            err = err + self.dxb @ at[na:]
        scale = self.abs_yt + self.abs_phi @ at + err
        out = (r, err, scale)
        self._last = (theta.copy(), out)
        return out

    def excess(self, theta, tau=None) -> np.ndarray:
        """Per-equation amount by which ``|r_t(theta)|`` exceeds its largest error term.

        ``r_t(theta)`` is the nominal residual and ``E_t = deta_t + sum_i |a_i| deta_{t-i}
        + sum_j |b_j| dx_g(t-j)`` the most the errors can explain; ``|r_t| - E_t - tau_t
        > 0`` means equation ``t`` fails at ``theta`` whatever the errors (shape (n_eq,),
        divided by the equation's scale so that equations compare).
        """
        r, err, scale = self.terms(theta)
        if tau is None:
            tau = FEASIBILITY_RTOL * scale
        return (np.abs(r) - err - tau) / np.maximum(scale, 1e-300)

    def partial_excess(self, theta, eta, dx, fixed_eta, fixed_dx, tau) -> np.ndarray:
        """Like :meth:`excess`, with the errors ``eta[fixed_eta]``, ``dx[fixed_dx]`` fixed
        at the given values (those of a working-set LP point) and the others free."""
        pr = self.problem
        na = pr.na
        theta = np.asarray(theta, dtype=float)
        r, _, scale = self.terms(theta)
        coef_e = np.concatenate([[1.0], theta[:na]])  # eta_{t-i} enters with a_i (a_0 = 1)
        fe = fixed_eta[self.eta_idx]
        ve = eta[self.eta_idx]
        mid = r - (fe * ve) @ coef_e
        rad = (~fe * self.deta) @ np.abs(coef_e)
        b = theta[na:]
        if b.size:
            fd = fixed_dx[self.dx_idx]
            vd = dx[self.dx_idx]
            mid = mid + (fd * vd) @ b
            rad = rad + (~fd * self.dxb) @ np.abs(b)
        return (np.abs(mid) - rad - tau) / np.maximum(scale, 1e-300)


def interval_excess(problem: EIVProblem, theta, tau=None) -> np.ndarray:
    """:meth:`EquationData.excess` for a single theta (see there)."""
    return EquationData(problem).excess(theta, tau)


class WorkingSetRelaxation(McCormickBase):
    """Persistent McCormick LP relaxation of (22.34) on a growing set of equations.

    Columns ``z = [theta (p), eta (N), dx (K), w (products of the working set)]``: the
    first ``p + N + K`` columns (and so :meth:`split_eta_dx`) are those of
    :class:`.mccormick.McCormickRelaxation`.

    Parameters
    ----------
    problem : EIVProblem
    box : ndarray, shape (p, 2)
        Initial theta box (the outward tolerance of every equation row is taken over it).
    equations : array_like of int
        Initial working set (indices into ``problem.equation_times``).
    """

    def __init__(self, problem: EIVProblem, box, equations):
        pr = self.problem = problem
        p, n, k, na = pr.p, pr.N, pr.n_groups, pr.na
        self.data = EquationData(pr)
        self.phi, self.yt = self.data.phi, self.data.yt
        m = self.m = self.phi.shape[0]
        self.eta_idx = pr.eta_index()
        dx_idx = pr.dx_index()
        nbp = dx_idx.shape[1]
        pair = np.arange(nbp)[None, :] * k + dx_idx
        upairs, inv = np.unique(pair.ravel(), return_inverse=True)
        self.b_inv = inv.reshape(m, nbp)
        self.b_x = na + upairs // k
        self.b_e = p + n + upairs % k
        self.npa = na * m  # global a-product id: i * m + t (lag i + 1)
        self.wcol = np.full(self.npa + upairs.size, -1, dtype=np.int64)
        self.w0 = p + n + k
        box = np.asarray(box, dtype=float)
        thmax = np.max(np.abs(box), axis=1)
        thmax = np.where(np.isfinite(thmax), thmax, np.max(np.abs(pr.theta_box), axis=1))
        self.tau = FEASIBILITY_RTOL * equation_scale(pr, thmax)
        self.e_lo = np.concatenate([-pr.deta, -pr.dx_group])
        self.e_hi = np.concatenate([pr.deta, pr.dx_group])
        # local product arrays (appended as products enter the working set)
        self.px = np.zeros(0, dtype=np.int64)
        self.pe = np.zeros(0, dtype=np.int64)
        self.pw = np.zeros(0, dtype=np.int64)
        self.mc_rows = np.zeros((0, 4), dtype=np.int64)
        self.in_set = np.zeros(m, dtype=bool)
        self.used_eta = np.zeros(n, dtype=bool)  # error columns that appear in the set's rows
        self.used_dx = np.zeros(k, dtype=bool)
        # base model: the error columns and the gain equality (exact, not relaxed)
        ncol = self.w0
        g = pr.gain_row()
        if g is not None:
            A = sp.csc_matrix((g[0], (np.zeros(p, dtype=int), np.arange(p))), shape=(1, ncol))
            rl = ru = np.array([g[1]])
        else:
            A = sp.csc_matrix((0, ncol))
            rl = ru = np.zeros(0)
        lb = np.concatenate([box[:, 0], self.e_lo])
        ub = np.concatenate([box[:, 1], self.e_hi])
        self.lp = HighsLP(A, rl, ru, lb, ub, options=_node_options(pr))
        self.box = box.copy()
        self._by_x = None
        self.add_equations(equations)

    @property
    def p(self) -> int:
        return self.problem.p

    @property
    def ncol(self) -> int:
        return self.lp.A.shape[1]

    @property
    def equations(self) -> np.ndarray:
        """The working set (sorted equation indices)."""
        return np.flatnonzero(self.in_set)

    def add_equations(self, eqs) -> int:
        """Add the equations ``eqs`` (those not yet in the set); returns how many were new."""
        eqs = np.unique(np.asarray(eqs, dtype=np.int64))
        eqs = eqs[~self.in_set[eqs]] if eqs.size else eqs
        if eqs.size == 0:
            return 0
        p, na = self.p, self.problem.na
        lp = self.lp
        # ---- new product columns ---------------------------------------------------------
        a_ids = (np.arange(na)[:, None] * self.m + eqs[None, :]).ravel()  # (na * len,)
        a_x = np.repeat(np.arange(na), eqs.size)
        a_e = p + self.eta_idx[eqs][:, 1:].T.ravel()
        b_glob = np.unique(self.b_inv[eqs].ravel())
        b_glob = b_glob[self.wcol[self.npa + b_glob] < 0]
        ids = np.concatenate([a_ids, self.npa + b_glob])
        nx = np.concatenate([a_x, self.b_x[b_glob]]).astype(np.int64)
        ne = np.concatenate([a_e, self.b_e[b_glob]]).astype(np.int64)
        # a product whose error is fixed at zero gets no column: its wcol stays -1 and
        # its equations skip it
        live = self._can_be_nonzero(ne)
        ids, nx, ne = ids[live], nx[live], ne[live]
        nnew = ids.size
        c0 = lp.A.shape[1]
        cols = c0 + np.arange(nnew)
        self.wcol[ids] = cols
        xl, xu = self.box[nx, 0], self.box[nx, 1]
        eL, eU = self.e_lo[ne - p], self.e_hi[ne - p]
        wl, wu = _prod_bounds(xl, xu, eL, eU)
        lp.add_cols(wl, wu)
        # ---- McCormick rows of the new products, then the equation rows -------------------
        r0 = lp.A.shape[0]
        mc = r0 + 4 * np.arange(nnew)[:, None] + np.arange(4)[None, :]
        rows, cc, vals = [], [], []
        e_coef = [-xl, -xu, -xu, -xl]
        x_coef = [-eL, -eU, -eL, -eU]
        for s in range(4):
            rows += [mc[:, s]] * 3
            cc += [cols, ne, nx]
            vals += [np.ones(nnew), e_coef[s], x_coef[s]]
        inf = np.full(nnew, np.inf)
        lo = np.column_stack([mul_down(-xl, eL), mul_down(-xu, eU), -inf, -inf]).ravel()
        hi = np.column_stack([inf, inf, mul_up(-xu, eL), mul_up(-xl, eU)]).ravel()
        er = r0 + 4 * nnew + np.arange(eqs.size)
        for q in range(p):
            rows.append(er)
            cc.append(np.full(eqs.size, q))
            vals.append(self.phi[eqs, q])
        rows.append(er)
        cc.append(p + self.eta_idx[eqs, 0])
        vals.append(-np.ones(eqs.size))
        for ids_j, sign in [(i * self.m + eqs, -1.0) for i in range(na)] + \
                [(self.npa + self.b_inv[eqs, j], 1.0) for j in range(self.b_inv.shape[1])]:
            col = self.wcol[ids_j]
            on = col >= 0
            rows.append(er[on])
            cc.append(col[on])
            vals.append(np.full(int(on.sum()), sign))
        nr = 4 * nnew + eqs.size
        block = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows) - r0, np.concatenate(cc))),
            shape=(nr, lp.A.shape[1]))
        y = self.yt[eqs]
        lp.add_rows(np.concatenate([lo, -y - self.tau[eqs]]),
                    np.concatenate([hi, -y + self.tau[eqs]]), block)
        self.px = np.concatenate([self.px, nx])
        self.pe = np.concatenate([self.pe, ne])
        self.pw = np.concatenate([self.pw, cols])
        self.mc_rows = np.concatenate([self.mc_rows, mc])
        self.in_set[eqs] = True
        self.used_eta[self.eta_idx[eqs].ravel()] = True
        self.used_dx[self.problem.dx_index()[eqs].ravel()] = True
        self._by_x = None
        return int(eqs.size)

    def separate(self, x, screen=None, limit: int = ADD_PER_ROUND, grow: bool = False
                 ) -> np.ndarray:
        """Equations outside the working set found violated at the LP point ``x`` (at most
        ``limit``, the most violated first).

        1. interval arithmetic at ``theta = x[:p]`` (:meth:`EquationData.excess`);
        2. the same with the errors of the set's rows fixed at their LP values (catches the
           equations that couple with the set through shared errors);
        3. if a screening LP (:class:`.points._Screen`) is given, the equations outside the set
           binding in its certificate that no errors explain the data at ``theta``.

        With ``grow=True`` (an LP that has already been re-solved :data:`GROW_AFTER` times)
        and an equation found violated, the set doubles instead: those found and the
        equations of step 1 nearest to violation, as many as the set holds (at least
        ``limit``), and all the rest once the set would pass
        :data:`GROW_ALL` of the equations. Seen on an output-error record (N = 3000,
        Delta eta = 0.1): one OBBT LP needed 2723 of the 2998 equations and took 220
        rounds of about ten violated equations each (120 s).
        """
        found = self._violated(x, screen, limit)
        if not grow or found.size == 0:
            return found
        out = np.flatnonzero(~self.in_set)
        size = max(limit, self.m - out.size, found.size)
        if self.m - out.size + size >= GROW_ALL * self.m:
            return out
        exc = self.data.excess(x[: self.p], self.tau)[out]
        exc[np.isin(out, found)] = np.inf
        return out[np.argsort(-exc)[:size]]

    def _violated(self, x, screen, limit) -> np.ndarray:
        """Steps 1-3 of :meth:`separate`."""
        theta = x[: self.p]
        exc = self.data.excess(theta, self.tau)
        exc[self.in_set] = -np.inf
        bad = np.flatnonzero(exc > 0)
        if bad.size == 0:
            eta, dx = self.split_eta_dx(x)
            exc = self.data.partial_excess(theta, eta, dx, self.used_eta, self.used_dx,
                                           self.tau)
            exc[self.in_set] = -np.inf
            bad = np.flatnonzero(exc > 0)
        if bad.size:
            return bad[np.argsort(-exc[bad])[:limit]]
        if screen is None:
            return bad
        b = screen.binding(theta)
        b = b[~self.in_set[b]]
        return b[:limit]
