"""McCormick LP relaxation of the EIV set (22.34) over a box of theta.

Variables ``z = [theta (p), eta (N), dx (K), w (P)]`` where every bilinear term of
(22.34) -- ``a_i eta_{t-i}`` (one per equation and lag) and ``b_j dx_g`` (one per *distinct*
pair ``(j, g)``; with the two-level inner signal only ``2 n_b`` of them) -- is replaced by
a product variable ``w = x e`` constrained by its McCormick envelope over
``x in [xL, xU]`` (a theta box edge) and ``e in [eL, eU]`` (the error box)::

    w >= xL e + eL x - xL eL,     w >= xU e + eU x - xU eU,
    w <= xU e + eL x - xU eL,     w <= xL e + eU x - xL eU.

Each equation of (22.34) becomes the linear row
``phi_t . theta - eta_t - sum_i w_(i,t-i) + sum_j w_(j,g(t-j)) = -y_t``; the gain
equality (22.8) is added as is. The relaxation contains the EIV set and is exact when
the theta box is a point. A product whose error bound is zero (e.g. ``b_j dx`` without
input errors) is exactly zero and gets no column or rows. Only the ``e`` coefficients and
the right-hand sides depend on the theta box, so :meth:`McCormickRelaxation.set_box`
updates a persistent HiGHS model in place (warm start). Right-hand sides and product bounds
are rounded outwards, so the relaxation is valid in floating point and LP bounds from
:mod:`._highs` are guaranteed.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...solvers.highs import HighsLP
from ...solvers.safe_lp import mul_down, mul_up
from ...tolerances import FEASIBILITY_RTOL
from ..problem import EIVProblem, equation_scale


def _prod_bounds(xl, xu, el, eu):
    """Outward-rounded bounds of ``x e`` over ``[xl, xu] x [el, eu]`` (arrays)."""
    pairs = [(xl, el), (xl, eu), (xu, el), (xu, eu)]
    lo = np.min([mul_down(a, b) for a, b in pairs], axis=0)
    hi = np.max([mul_up(a, b) for a, b in pairs], axis=0)
    return lo, hi


def _node_options(problem: EIVProblem) -> dict:
    """HiGHS options for the many warm-started node LPs of a branch-and-bound.

    Devex dual pricing re-solves the N = 300 chapter relaxations about 1.4x faster than
    HiGHS's default (steepest edge), and skipping scaling another 1.4x. Scaling is skipped
    only when the data are of order one (``max |y|`` and ``max |x|`` in [1e-2, 1e2]): the
    equation rows mix them with the unit coefficients of ``eta`` and ``w``, and on unscaled
    badly scaled data the duals are too inaccurate to certify tight node bounds (data x1e-4:
    a bound that closes in 5 nodes with scaling ran into the node limit without). The
    options only affect speed: every bound is certified from the duals afterwards.

    Without input errors (an output-error record) scaling stays on: there OBBT shrinks the
    box to a small fraction of the LP box, and a warm start from the basis of the wider box
    can be numerically singular. Unscaled, HiGHS 1.15-1.16 then crashes the process
    (N = 3000, Delta eta = 0.1, 2 of 2 seeds: the dual phase 1 starts at an objective of
    -9e242 and its row choice recurses without end); scaled, the same warm start solves
    in 412 iterations (``benchmarks/report_notes.md``, "HiGHS crash").
    """
    opts = {"simplex_dual_edge_weight_strategy": 1}
    sizes = [float(np.max(np.abs(problem.y), initial=0.0)),
             float(np.max(np.abs(problem.x), initial=0.0))]
    if problem.has_input_errors and all(1e-2 <= v <= 1e2 for v in sizes):
        opts["simplex_scale_strategy"] = 0
    return opts


def set_envelope(lp, rows, cols, pos, w_cols, xl, xu, eL, eU):
    """Set the 4 McCormick rows of the products ``w = x e`` of one theta ``x`` in ``[xl, xu]``
    with the errors ``e`` in ``[eL, eU]`` (arrays, one per product): coefficients of ``e``,
    outward-rounded row bounds and the bounds of the ``w`` columns ``w_cols``."""
    ones = np.ones(np.size(eL))
    # e-coefficients of the 4 rows: -xL, -xU, -xU, -xL
    lp.set_coeffs(rows, cols, pos,
                  np.column_stack([-xl * ones, -xu * ones, -xu * ones, -xl * ones]).ravel())
    lo = np.column_stack([mul_down(-xl, eL) * ones, mul_down(-xu, eU) * ones,
                          -np.inf * ones, -np.inf * ones]).ravel()
    hi = np.column_stack([np.inf * ones, np.inf * ones,
                          mul_up(-xu, eL) * ones, mul_up(-xl, eU) * ones]).ravel()
    lp.set_row_bounds(rows, lo, hi)
    wl, wu = _prod_bounds(xl, xu, eL, eU)
    lp.set_col_bounds(w_cols, wl, wu)


# the input-error variables become branching variables of the search (next to theta) when
# there are at most this many of them and they are shared by several samples (two-level)
MAX_SHARED_GROUPS = 16


def shared_groups(problem: EIVProblem) -> int:
    """How many input-error variables ``dx_var`` the search branches on: all ``K`` of them
    when they are few (``K <= MAX_SHARED_GROUPS``) and shared (``K < N``, e.g. the two-level
    inner signal, ``K = 2``), else none (independent per-sample errors)."""
    k = problem.n_groups
    return k if (k <= MAX_SHARED_GROUPS and k < problem.N) else 0


class McCormickBase:
    """What the full and the working-set McCormick relaxations share: the box update of
    the product envelopes and views of an LP point. Needs ``p``, ``problem``, ``lp``,
    the product index arrays ``pw``, ``px``, ``pe``, the rows ``mc_rows`` (P, 4), the error
    boxes ``e_lo``, ``e_hi``, the current ``box`` and ``_by_x`` (None: recompute).

    The box is the theta box (p, 2), optionally followed by the boxes (K, 2) of the shared
    input-error variables ``dx_var`` (:func:`shared_groups`): narrowing those tightens the
    envelope of every product ``b_j dx_var[g]`` at once, which the branch-and-bound uses on
    the two-level inner signal. A ``dx_var`` box must lie inside ``[-dx_group, dx_group]``.
    """

    def _positions(self):
        """Per theta index: the products, their McCormick rows, the e-columns and their
        positions in the LP matrix (cached until ``_by_x`` is reset)."""
        if self._by_x is None:
            self._by_x = []
            for q in range(self.p):
                sel = np.flatnonzero(self.px == q)
                r = self.mc_rows[sel].ravel()  # (len(sel)*4,) ordered (prod, s)
                c = np.repeat(self.pe[sel], 4)
                self._by_x.append((sel, r, c, self.lp.data_positions(r, c)))
            self._by_g = None
        return self._by_x

    def _group_positions(self):
        """Per input-error group: its products, their McCormick rows, the theta columns and
        the positions of those ``x``-coefficients in the LP matrix, and the group's column
        and the positions of its ``e``-coefficients (cached like :meth:`_positions`)."""
        self._positions()
        if getattr(self, "_by_g", None) is None:
            self._by_g = []
            base = self.p + self.problem.N
            for g in range(self.problem.n_groups):
                sel = np.flatnonzero(self.pe == base + g)
                r = self.mc_rows[sel].ravel()
                c = np.repeat(self.px[sel], 4)
                ec = np.repeat(self.pe[sel], 4)
                self._by_g.append((sel, r, c, self.lp.data_positions(r, c), ec,
                                   self.lp.data_positions(r, ec)))
        return self._by_g

    def _can_be_nonzero(self, pe) -> np.ndarray:
        """Per product with error column ``pe``: False where the error bound is zero, so
        the product is exactly zero and gets no column."""
        return self.e_hi[pe - self.p] > self.e_lo[pe - self.p]

    def dx_columns(self) -> np.ndarray:
        """LP columns of the input-error variables ``dx_var`` (shape (K,))."""
        pr = self.problem
        return pr.p + pr.N + np.arange(pr.n_groups)

    def set_box(self, box):
        """Update the relaxation in place to ``box``: the theta box (p, 2), optionally
        followed by the boxes of the ``dx_var`` (see the class docstring)."""
        box = np.asarray(box, dtype=float)
        p = self.p
        lp = self.lp
        if box.shape[0] > p:
            self._set_dx_box(box[p:])
            box = box[:p]
        changed = np.flatnonzero(np.any(box != self.box, axis=1))
        if changed.size == 0:
            return
        lp.set_col_bounds(changed, box[changed, 0], box[changed, 1])
        by_x = self._positions()
        for q in changed:
            sel, r, c, pos = by_x[q]
            if sel.size == 0:
                continue
            e = self.pe[sel] - self.p
            set_envelope(lp, r, c, pos, self.pw[sel], box[q, 0], box[q, 1],
                         self.e_lo[e], self.e_hi[e])
        self.box = box.copy()

    def _set_dx_box(self, dbox):
        """Narrow (or widen back) the boxes of the ``dx_var``: column bounds, and for every
        product ``b_j dx_var[g]`` the ``b``-coefficients and bounds of its McCormick rows
        and the bounds of its column."""
        pr = self.problem
        k0 = pr.N  # dx_var g is error index N + g (e_lo / e_hi)
        cur = np.column_stack([self.e_lo[k0:], self.e_hi[k0:]])
        changed = np.flatnonzero(np.any(dbox != cur, axis=1))
        if changed.size == 0:
            return
        lp = self.lp
        self.e_lo[k0 + changed] = dbox[changed, 0]
        self.e_hi[k0 + changed] = dbox[changed, 1]
        lp.set_col_bounds(self.dx_columns()[changed], dbox[changed, 0], dbox[changed, 1])
        by_g = self._group_positions()
        for g in changed:
            sel, r, c, pos, ec, epos = by_g[g]
            if sel.size == 0:
                continue
            xq = self.px[sel]
            xl, xu = self.box[xq, 0], self.box[xq, 1]
            eL = np.full(sel.size, dbox[g, 0])
            eU = np.full(sel.size, dbox[g, 1])
            # x-coefficients of the 4 rows: -eL, -eU, -eL, -eU
            lp.set_coeffs(r, c, pos, np.column_stack([-eL, -eU, -eL, -eU]).ravel())
            set_envelope(lp, r, ec, epos, self.pw[sel], xl, xu, eL, eU)

    def violations(self, x, n_shared: int = 0) -> np.ndarray:
        """Per branching variable, the sum of ``|w - x e|`` over its products at an LP point
        ``x``: shape (p,), or (p + n_shared,) with the shared ``dx_var`` appended."""
        v = np.abs(x[self.pw] - x[self.px] * x[self.pe])
        out = np.bincount(self.px, weights=v, minlength=self.p)
        if n_shared:
            base = self.p + self.problem.N
            g = self.pe - base
            on = g >= 0
            out = np.concatenate([out, np.bincount(g[on], weights=v[on], minlength=n_shared)])
        return out

    def split_eta_dx(self, x):
        """``(eta (N,), dx (K,))`` part of an LP point."""
        p, n = self.p, self.problem.N
        return x[p : p + n], x[p + n : p + n + self.problem.n_groups]


class _Triplets:
    """COO triplets of a sparse matrix under construction."""

    def __init__(self):
        self.rows, self.cols, self.vals = [], [], []

    def add(self, rows, cols, vals):
        self.rows.append(rows)
        self.cols.append(cols)
        self.vals.append(vals)

    def matrix(self, shape):
        return sp.csc_matrix((np.concatenate(self.vals),
                              (np.concatenate(self.rows), np.concatenate(self.cols))),
                             shape=shape)


class McCormickRelaxation(McCormickBase):
    """Persistent McCormick LP relaxation of (22.34) (see module docstring).

    Parameters
    ----------
    problem : EIVProblem
    box : ndarray, shape (p, 2)
        Initial theta box (must lie inside ``problem.theta_box`` for the result to be a
        relaxation of the EIV set restricted to that box).
    """

    def __init__(self, problem: EIVProblem, box):
        pr = problem
        self.problem = pr
        p, n, k = pr.p, pr.N, pr.n_groups
        phi, yt = pr.regressors()
        eta_idx = pr.eta_index()  # (m, na+1)
        self.e_lo = np.concatenate([-pr.deta, -pr.dx_group])
        self.e_hi = np.concatenate([pr.deta, pr.dx_group])
        a_prod, b_prod = self._products(pr, eta_idx)
        P = self.px.size
        w0 = p + n + k
        self.ncol = w0 + P
        self.pw = w0 + np.arange(P)
        t = _Triplets()
        rl, ru = self._equations(t, phi, yt, eta_idx, a_prod, b_prod, box)
        self.mc0 = nrow = len(rl)
        self.mc_rows = self._envelope_rows(t)
        nrow += 4 * P
        rl, ru = np.concatenate([rl, np.full(4 * P, -np.inf)]), \
            np.concatenate([ru, np.full(4 * P, np.inf)])
        lb = np.concatenate([np.asarray(box, float)[:, 0], self.e_lo, np.zeros(P)])
        ub = np.concatenate([np.asarray(box, float)[:, 1], self.e_hi, np.zeros(P)])
        self.lp = HighsLP(t.matrix((nrow, self.ncol)), rl, ru, lb, ub,
                          options=_node_options(pr))
        self._by_x = None  # filled by set_box (McCormickBase._positions)
        self.box = np.full((p, 2), np.nan)
        self.set_box(box)

    def _products(self, pr, eta_idx):
        """The product columns' factors: ``px`` (theta index) and ``pe`` (error column)
        of the ``a_i eta`` products, one per (equation, i), then of the ``b_j dx_var[g]``
        products, one per distinct (j, g). A product whose error is fixed at zero (bound
        0, e.g. no input errors: an output-error record) is exactly zero and gets no column.
        Returns the product of each (equation, i), shape (m, na), and of each (equation, j),
        (m, nbp): indices into ``px``, or -1 for a product that is zero."""
        p, n, k, na = pr.p, pr.N, pr.n_groups, pr.na
        m = eta_idx.shape[0]
        dx_idx = pr.dx_index()  # (m, nbp)
        ax = np.repeat(np.arange(na), m)  # theta index, ordered (i, equation)
        ae = p + eta_idx[:, 1:].T.ravel()  # eta column
        pair = np.tile(np.arange(dx_idx.shape[1]), (m, 1)) * k + dx_idx  # (m, nbp)
        upairs, inv = np.unique(pair.ravel(), return_inverse=True)
        bx = na + upairs // k
        be = p + n + upairs % k
        px = np.concatenate([ax, bx]).astype(np.int64)
        pe = np.concatenate([ae, be]).astype(np.int64)
        live = self._can_be_nonzero(pe)
        index = np.cumsum(live) - 1
        index[~live] = -1
        self.px, self.pe = px[live], pe[live]
        return index[: ax.size].reshape(na, m).T, index[ax.size:][inv].reshape(m, -1)

    def _equations(self, t, phi, yt, eta_idx, a_prod, b_prod, box):
        """The equation rows (and the gain row) into the triplets ``t``; their bounds.
        ``a_prod``, ``b_prod``: the products of each equation (:meth:`_products`)."""
        pr = self.problem
        p = pr.p
        m = phi.shape[0]
        w0 = p + pr.N + pr.n_groups  # the first product column
        eqr = np.arange(m)
        for q in range(p):  # theta part of the equations
            t.add(eqr, np.full(m, q), phi[:, q])
        t.add(eqr, p + eta_idx[:, 0], -np.ones(m))
        for prod, sign in ((a_prod, -1.0), (b_prod, 1.0)):
            for j in range(prod.shape[1]):
                on = prod[:, j] >= 0
                t.add(eqr[on], w0 + prod[on, j], np.full(int(on.sum()), sign))
        # tolerance policy: every equation is relaxed outward by FEASIBILITY_RTOL times the
        # magnitudes of its terms over the initial (largest) box, so node certificates of
        # "empty" and of bounds hold beyond the tolerance, never for the data taken exactly
        thmax = np.max(np.abs(np.asarray(box, dtype=float)), axis=1)
        thmax = np.where(np.isfinite(thmax), thmax, np.max(np.abs(pr.theta_box), axis=1))
        tau = FEASIBILITY_RTOL * equation_scale(pr, thmax)
        rl, ru = [-yt - tau], [-yt + tau]
        g = pr.gain_row()
        if g is not None:
            # the gain equality (22.8) is a model fact with exact coefficients: not relaxed
            t.add(np.full(p, m), np.arange(p), g[0])
            rl.append([g[1]])
            ru.append([g[1]])
        return np.concatenate(rl), np.concatenate(ru)

    def _envelope_rows(self, t):
        """The 4 McCormick rows of every product (after the equations, from row
        :attr:`mc0`): entries ``w`` (1), ``e`` and ``x`` (coefficients set by
        :meth:`set_box`; the structural nonzeros are kept). Returns their rows (P, 4)."""
        P = self.px.size
        p = self.p
        eL, eU = self.e_lo[self.pe - p], self.e_hi[self.pe - p]
        # row r = mc0 + 4 q + s, s = 0..3
        mc_rows = self.mc0 + 4 * np.arange(P)[:, None] + np.arange(4)[None, :]  # (P, 4)
        for s in range(4):
            r = mc_rows[:, s]
            x_coef = -(eL if s in (0, 2) else eU)
            t.add(np.concatenate([r, r, r]), np.concatenate([self.pw, self.pe, self.px]),
                  np.concatenate([np.ones(P), np.ones(P), x_coef]))
        return mc_rows

    @property
    def p(self) -> int:
        return self.problem.p
