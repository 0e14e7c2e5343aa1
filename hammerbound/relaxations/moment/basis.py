"""Polynomial form of the EIV set (22.34) and the monomial bases of its moment relaxation.

Helpers of :mod:`.moment`: sparse polynomials as ``{monomial: coefficient}`` dicts
(monomials are sorted tuples of variable indices), the problem in scaled variables
(:class:`_ScaledPOP`), and the per-clique moment / localizing / equality constraints for the
``"full"`` and the term-sparse ``"sparse"`` bases (:func:`_clique_constraints`).
"""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp

from ..problem import EIVProblem

# ---------------------------------------------------------------------------------------
# polynomials: dict {monomial (sorted tuple of variable indices): coefficient}
# ---------------------------------------------------------------------------------------


def _pmul(p, q):
    out = {}
    for m1, c1 in p.items():
        for m2, c2 in q.items():
            m = tuple(sorted(m1 + m2))
            out[m] = out.get(m, 0.0) + c1 * c2
    return {m: c for m, c in out.items() if c != 0.0}


def _padd(*ps):
    out = {}
    for p in ps:
        for m, c in p.items():
            out[m] = out.get(m, 0.0) + c
    return {m: c for m, c in out.items() if c != 0.0}


def _pscale(p, s):
    return {m: c * s for m, c in p.items()}


def _pdeg(p):
    return max((len(m) for m in p), default=0)


def _monomials(variables, max_deg):
    """All monomials (sorted tuples) of degree <= max_deg in ``variables``."""
    variables = sorted(variables)
    out = [()]
    for d in range(1, max_deg + 1):
        out += list(itertools.combinations_with_replacement(variables, d))
    return out


# ---------------------------------------------------------------------------------------
# the polynomial optimisation problem in scaled variables
# ---------------------------------------------------------------------------------------


class _ScaledPOP:
    """EIV set (22.34) in scaled variables ``v in [-1, 1]^n``.

    ``theta = c0 + T u`` with ``u = v[:q]``; ``eta_s = deta_s * v[eta_var[s]]``,
    ``dx[k] = dx_group[k] * v[dx_var[k]]`` (``-1`` when ``dx_group[k] == 0``).
    """

    def __init__(self, problem: EIVProblem, box: np.ndarray):
        p = problem.p
        mid = 0.5 * (box[:, 0] + box[:, 1])
        half = 0.5 * (box[:, 1] - box[:, 0])
        self.box = box
        self.extra_ineqs = []  # polynomials g >= 0 (theta-only)
        fixed = half <= 0
        g = problem.gain_row()
        elim = None
        if g is not None:
            row, rhs = g
            score = np.abs(row) * half
            if np.any(score > 0):
                elim = int(np.argmax(score))
        free = [k for k in range(p) if k != elim and not fixed[k]]
        q = len(free)
        T = np.zeros((p, q))
        c0 = mid.copy()
        for j, k in enumerate(free):
            T[k, j] = half[k]
        if elim is not None:
            row, rhs = g
            # theta_e = (rhs - sum_{k != e} row_k theta_k) / row_e
            others = np.array([k for k in range(p) if k != elim])
            c0[elim] = (rhs - row[others] @ c0[others]) / row[elim]
            T[elim] = -(row[others] @ T[others]) / row[elim]
            # box of the eliminated coefficient: half^2 - (theta_e - mid_e)^2 >= 0, scaled
            lin = {(j,): T[elim, j] / half[elim] for j in range(q) if T[elim, j] != 0}
            lin[()] = (c0[elim] - mid[elim]) / half[elim]
            self.extra_ineqs.append(_padd({(): 1.0}, _pscale(_pmul(lin, lin), -1.0)))
        self.elim = elim
        self.c0, self.T, self.q = c0, T, q
        n = q
        eta_needed = np.unique(problem.eta_index())
        self.eta_var = -np.ones(problem.N, dtype=int)
        for s in eta_needed:
            self.eta_var[s] = n
            n += 1
        self.dx_var = -np.ones(problem.n_groups, dtype=int)
        for k in np.unique(problem.dx_index()):
            if problem.dx_group[k] > 0:
                self.dx_var[k] = n
                n += 1
        self.n = n
        # equations
        phi, yt = problem.regressors()
        eta_idx = problem.eta_index()
        dx_idx = problem.dx_index()
        na = problem.na
        self.equations = []
        self.cliques = []
        theta_lin = [
            _padd({(): c0[k]}, {(j,): T[k, j] for j in range(q) if T[k, j] != 0})
            for k in range(p)
        ]
        for e in range(yt.size):
            # r_t(theta) - eta_t - sum a_i eta_{t-i} + sum b_j dx_g = 0
            r = _padd({(): yt[e]}, *[_pscale(theta_lin[k], phi[e, k]) for k in range(p)])
            terms = [r]
            s0 = eta_idx[e, 0]
            terms.append({(self.eta_var[s0],): -problem.deta[s0]})
            cvars = set(range(q)) | {self.eta_var[s0]}
            for i in range(1, na + 1):
                s = eta_idx[e, i]
                v = self.eta_var[s]
                cvars.add(v)
                terms.append(_pmul(theta_lin[i - 1], {(v,): -problem.deta[s]}))
            for jj in range(dx_idx.shape[1]):
                k = dx_idx[e, jj]
                v = self.dx_var[k]
                if v < 0:
                    continue
                cvars.add(v)
                terms.append(_pmul(theta_lin[na + jj], {(v,): problem.dx_group[k]}))
            h = _padd(*terms)
            scale = max(abs(c) for c in h.values()) if h else 1.0
            self.equations.append((_pscale(h, 1.0 / scale), frozenset(cvars)))
        # merge identical clique variable sets
        by_set = {}
        for h, cv in self.equations:
            by_set.setdefault(cv, []).append(h)
        self.cliques = [(sorted(cv), hs) for cv, hs in by_set.items()]


#: Monomial bases of the moment matrices (see :class:`MomentRelaxation`).
BASES = ("full", "sparse")


def _sparse_basis(theta_vars, noise_vars, order):
    """Term-sparse basis: ``theta^a e^b`` with ``|b| <= 1`` and ``|a| + |b| <= order``,
    without the pure-theta monomials of degree ``order >= 2`` (order 2: ``1, theta, e,
    theta e``)."""
    out = [()]
    for d in range(1, order + 1):
        for a in itertools.combinations_with_replacement(theta_vars, d):
            if d < order or order == 1:
                out.append(a)
        for a in itertools.combinations_with_replacement(theta_vars, d - 1):
            for e in noise_vars:
                out.append(tuple(sorted(a + (e,))))
    return out


def _clique_constraints(cvars, hs, pop, order, basis):
    """``[(g, basis)]`` of one clique: localizing matrices ``M(g y)`` over ``basis`` (the
    moment matrix is ``g = 1``) and ``(None, multipliers)`` for the equalities.

    ``basis="full"``: every monomial of degree ``<= order`` (localizing: ``<= order - 1``;
    equality multipliers: ``<= 2 order - 2``), as in Lasserre (2006).
    ``basis="sparse"``: the moment matrix over :func:`_sparse_basis`; a localizing product
    ``g b b'`` or an equality product ``h alpha`` is kept only when all its monomials are
    entries of that moment matrix (so no moment appears that the matrix does not bound).
    """
    if basis == "full" or order == 1:
        mb = _monomials(cvars, order)
        lb = _monomials(cvars, order - 1)
        out = [({(): 1.0}, mb)]
        out += [({(): 1.0, (v, v): -1.0}, lb) for v in cvars]
        out += [(g, lb) for g in pop.extra_ineqs]
        out.append((None, _monomials(cvars, 2 * order - 2)))
        return out
    tv = [v for v in cvars if v < pop.q]
    nv = [v for v in cvars if v >= pop.q]
    mb = _sparse_basis(tv, nv, order)
    mm = {tuple(sorted(a + b)) for a in mb for b in mb}
    cand = _monomials(cvars, order - 1)

    def loc_basis(g):
        keep = []
        for c in cand:
            trial = keep + [c]
            if all(tuple(sorted(m + c + b)) in mm for m in g for b in trial):
                keep.append(c)
        return keep

    out = [({(): 1.0}, mb)]
    for v in nv:  # noise boxes: (1 - e^2) times the largest basis inside the matrix
        g = {(): 1.0, (v, v): -1.0}
        lb = loc_basis(g)
        if lb:
            out.append((g, lb))
    # theta boxes (and the eliminated coefficient's box): scalar constraints (identical
    # in every clique, so added once by the caller)
    for g in [{(): 1.0, (v, v): -1.0} for v in tv] + list(pop.extra_ineqs):
        out.append((g, [()]))
    support = set().union(*[set(h) for h in hs]) if hs else set()
    mult = [a for a in _monomials(cvars, 2 * order - 2)
            if all(tuple(sorted(m + a)) in mm for m in support)]
    out.append((None, mult))
    return out


def _affine(y, rows, cols, vals, dim, name):
    """PICOS affine ``dim x dim`` expression with ``vec`` coefficients over ``y`` (column
    0 of the lists is the constant); built directly, without a dense product."""
    import cvxopt
    from picos.expressions import AffineExpression

    rows = np.asarray(rows, dtype=int)
    cols = np.asarray(cols, dtype=int)
    vals = np.asarray(vals, dtype=float)
    is_c = cols == 0
    A = sp.coo_matrix((vals[~is_c], (rows[~is_c], cols[~is_c] - 1)),
                      shape=(dim * dim, y.dim)).tocsc()
    A.sum_duplicates()
    A.eliminate_zeros()
    Ac = A.tocoo()
    cst = np.zeros(dim * dim)
    np.add.at(cst, rows[is_c], vals[is_c])
    coefs = {y: cvxopt.spmatrix(Ac.data.tolist(), Ac.row.tolist(), Ac.col.tolist(),
                                (dim * dim, y.dim))}
    if np.any(cst != 0):
        coefs[()] = cvxopt.matrix(cst)
    return AffineExpression(name, (dim, dim), coefs)
