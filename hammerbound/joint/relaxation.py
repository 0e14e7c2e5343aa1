"""LP relaxation of the one-record set over a box of ``[theta, m_l, c_l, m_r, c_r, z0]``.

Over a box, :func:`~.modes.inner_structure` writes every inner value as a linear form in the
*inner variables* ``beta = (m_l, d_l, m_r, d_r, z0, v_1 .. v_K)`` (``d = m c``; ``v_k`` the
ambiguous samples). Each equation of :mod:`.problem` becomes linear in ``theta``, ``eta``
and the products ``b_j beta_k``, ``a_i eta_t``; those (and ``d = m c``) are replaced by
variables held by their McCormick envelopes over the box. Two families of valid rows make
the relaxation strong from wide boxes:

* **RLT rows** -- the gain equality (22.8) ``sum_j b_j = g (1 + sum_i a_i)`` multiplied by
  every inner variable: ``sum_j (b_j beta_k) = g beta_k + g sum_i (a_i beta_k)``. They tie
  the products to their factors (the scale split between the backlash slopes and ``B``
  that the gain fixes), which plain McCormick envelopes of a wide ``b`` box do not;
* **branch rows** -- every inner value lies in its band ``R_t <= x_t <= L_t``; an ambiguous
  sample that cannot move up is below its previous state, one that cannot move down is
  above it; the backlash is well-posed (``L >= R``) over the record's input range.

Every row holds at every point of the set, so the LP bounds are outer bounds; equation
rows are widened by the tolerance policy (:mod:`hammerbound.tolerances`), McCormick
right-hand sides are rounded outward, and the bound of each LP is certified from its duals
(:class:`~hammerbound.solvers.highs.HighsLP`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..solvers.highs import HighsLP
from ..solvers.safe_lp import round_down as _round_down
from ..solvers.safe_lp import round_up as _round_up
from ..tolerances import FEASIBILITY_RTOL
from .hull_rows import hull_rows
from .modes import AMBIG, DOWN, INIT, LEFT, RIGHT, UP, InnerStructure, inner_structure, line_range
from .problem import RecordProblem

__all__ = ["JointRelaxation", "build_relaxation", "gain_tolerance", "solve_lp"]


#: A solve that runs more than this many simplex iterations per row and column of the LP
#: is stopped and solved again from scratch by the dual simplex (without the cap). HiGHS's
#: simplex can stall from a carried or previous basis: seen on a closed-loop record with
#: the play operator's envelope rows (:mod:`.hull_rows`), 1e6 iterations in the LP's 60 s
#: where a cold solve takes 2-4e3 (0.2 s). A cold solve takes about one iteration per row.
ITERATION_CAP = 5


def solve_lp(lp, primal=False):
    """Solve with a certified bound (``primal``: after a change of the cost only). An LP
    that HiGHS refuses is recovered inside :meth:`~hammerbound.solvers.highs.HighsLP.solve`
    (from scratch, primal simplex, IPM); refused every time it gives no bound (``-inf``,
    status "failed"): never a wrong one. A solve past :data:`ITERATION_CAP` is solved
    again from scratch, within the time the first solve had: both together stop at its
    :attr:`~hammerbound.solvers.highs.HighsLP.stop` (one LP's time limit in all)."""
    import highspy

    m, n = lp.A.shape
    before = lp.h.getOptionValue("simplex_iteration_limit")
    before = before[1] if isinstance(before, tuple) else before  # (status, value) in highspy
    lp.h.setOptionValue("simplex_iteration_limit", int(ITERATION_CAP * (m + n)))
    try:
        res = lp.solve(primal=primal)
    finally:
        lp.h.setOptionValue("simplex_iteration_limit", int(before))
    if lp.h.getModelStatus() != highspy.HighsModelStatus.kIterationLimit:
        return res
    lp.h.clearSolver()
    deadline = lp.deadline
    lp.deadline = lp.stop if deadline is None else min(deadline, lp.stop)
    try:
        again = lp.solve(primal=False)
    finally:
        lp.deadline = deadline
    again.iterations += res.iterations
    stopped = f"stopped after {res.iterations} simplex iterations; solved again from scratch"
    again.note = "; ".join(x for x in (res.note, stopped, again.note) if x)
    return again


def round_down(v):
    """Outward (downward) rounding of computed data; exact zeros stay zero (rounding 0
    would put denormal coefficients into the LP, which HiGHS refuses to run)."""
    v = np.asarray(v, dtype=float)
    return np.where(v == 0.0, 0.0, _round_down(v))


def round_up(v):
    """Outward (upward) rounding; exact zeros stay zero (see :func:`round_down`)."""
    v = np.asarray(v, dtype=float)
    return np.where(v == 0.0, 0.0, _round_up(v))


#: HiGHS options of every relaxation LP. Without presolve an infeasible LP ends in the
#: dual simplex with a dual ray (a certificate at no extra cost) and a node stopped by its
#: cutoff keeps valid duals; with presolve, HiGHS often found infeasibility there, without a
#: ray, and the certificate took a phase-1 LP. Measured on the chapter's record at N = 300
#: (c_r max, 323 nodes): 31.7 s with presolve, 21.9 s without, same bound.
#: Each LP also stops after LP_TIME_LIMIT seconds (its bound then comes from whatever duals
#: it has, maybe none: the caller keeps the box it had). Seen on a valve loop of 108
#: samples: one relaxation LP ran for over 15 minutes in a worker process (the same loop
#: took 112 s in all in a fresh process, where the deadline had stopped the search at
#: another box). One LP takes 0.03 s at N = 300 and 0.3-1 s at N = 1000.
#: Devex dual pricing instead of HiGHS's default (dual steepest edge, whose weights are
#: recomputed after every warm start): measured on a random-step record at N = 300,
#: Delta eta = 0.3, the first 300 nodes of an end's branch-and-bound took 8.8 s of LP time
#: instead of 14.8 s and an lp fit 21.9 s instead of 26.8 s, with the same bounds. Options
#: only change speed: every bound is certified from the duals afterwards.
LP_TIME_LIMIT = 60.0
LP_OPTIONS = {"presolve": "off", "simplex_dual_edge_weight_strategy": 1}

#: The play operator's envelope rows at ambiguous samples (:mod:`.hull_rows`), except in
#: the partition of the a priori box (:func:`.tighten.outer_leaves`). Measured on
#: random-step records of the chapter's system (N = 300, Delta eta = 0.3, exact method,
#: 60 s, one job, same run): median gap / width 0.32 and 0.35 against 0.46 and 0.50
#: without them, c_l 2.3x and c_r 1.9x narrower; at 0.05 the same or narrower. On a
#: closed-loop record (N = 300) whose partition they did not help, they made the
#: partition's LPs about 2x slower, hence its exception (there: 704 s against 582 s of CPU,
#: the same intervals).
HULL_ROWS = True

# positions of the inner variables in beta
B_ML, B_DL, B_MR, B_DR, B_Z0 = range(5)

# Keys of the LP's rows and columns: what each one *is* (the noise of sample t, the
# product of b_j with the value of ambiguous sample t, the band row of sample t, ...), so
# that a node's basis can be carried to a child whose LP has other columns and rows (a
# child split on a sample's branch loses that sample's value variable): see
# :func:`carry_basis`. A key is ``kind * 2**40 + a * 2**20 + b`` (a, b < 2**20; the
# McCormick rows of a product add 0..3 times _SUB to its column key).
_SUB = 2**38


def key(kind, a=0, b=0):
    """The key code of a row or column (arrays broadcast)."""
    return (np.int64(kind) << 40) + (np.asarray(a, dtype=np.int64) << 20) \
        + np.asarray(b, dtype=np.int64)


# kinds of columns and rows
(K_BOX, K_V, K_PROD, K_ETA, K_Q, K_EQ, K_GAIN, K_RLT, K_MC_D, K_BAND, K_BAND0, K_ONE,
 K_DEC, K_WELL, K_STEADY, K_HULL) = range(1, 17)


class _Rows:
    """COO triplets and row bounds of an LP under construction."""

    def __init__(self):
        self.r, self.c, self.v, self.lo, self.hi, self.keys = [], [], [], [], [], []
        self.m = 0

    def add(self, rows, cols, vals, lo, hi, key=-1):
        """Add rows given as (k,) arrays of bounds and flat triplets (row offsets 0..k-1);
        ``key``: their :func:`key` codes (one, or one per row; -1: none)."""
        lo = np.atleast_1d(np.asarray(lo, dtype=float))
        self.keys.append(np.broadcast_to(np.asarray(key, dtype=np.int64), lo.shape))
        self.r.append(np.asarray(rows, dtype=np.int64) + self.m)
        self.c.append(np.asarray(cols, dtype=np.int64))
        self.v.append(np.asarray(vals, dtype=float))
        self.lo.append(lo)
        self.hi.append(np.atleast_1d(np.asarray(hi, dtype=float)))
        start = self.m
        self.m += lo.size
        return np.arange(start, self.m)

    def mccormick(self, w, x, e, xl, xu, el, eu, key):
        """Envelope rows of the products ``w = x e`` (arrays of columns and bounds);
        ``key``: the products' column keys (the rows get ``key`` and 1..3 in :data:`_SUB`)."""
        w, x, e = (np.atleast_1d(np.asarray(a, dtype=np.int64)) for a in (w, x, e))
        xl, xu, el, eu = (np.broadcast_to(np.asarray(a, dtype=float), w.shape) for a in
                          (xl, xu, el, eu))
        k = w.size
        rows = np.repeat(np.arange(4 * k).reshape(k, 4), 3, axis=1).ravel()
        cols = np.column_stack([w, e, x] * 4).ravel()
        one = np.ones(k)
        vals = np.column_stack([one, -xl, -el, one, -xu, -eu, one, -xu, -el, one, -xl, -eu])
        lo = np.column_stack([round_down(-xl * el), round_down(-xu * eu),
                              -np.inf * one, -np.inf * one]).ravel()
        hi = np.column_stack([np.inf * one, np.inf * one,
                              round_up(-xu * el), round_up(-xl * eu)]).ravel()
        k4 = np.asarray(key, dtype=np.int64)[:, None] + _SUB * np.arange(4)
        return self.add(rows, cols, vals.ravel(), lo, hi, key=k4.ravel())

    def matrix(self, n):
        r = np.concatenate(self.r) if self.r else np.zeros(0, dtype=np.int64)
        c = np.concatenate(self.c) if self.c else np.zeros(0, dtype=np.int64)
        v = np.concatenate(self.v) if self.v else np.zeros(0)
        A = sp.csc_matrix((v, (r, c)), shape=(self.m, n))
        A.sum_duplicates()
        return A, np.concatenate(self.lo), np.concatenate(self.hi)

    def row_keys(self):
        return np.concatenate(self.keys) if self.keys else np.zeros(0, dtype=np.int64)


def _prod_range(xl, xu, el, eu):
    c = np.stack([xl * el, xl * eu, xu * el, xu * eu])
    return round_down(c.min(axis=0)), round_up(c.max(axis=0))


@dataclass
class JointRelaxation:
    """A built relaxation: the LP, the columns of the box variables and of the inner
    variables, and the structure it was built on.

    ``box_cols`` are the LP columns of ``[theta, m_l, c_l, m_r, c_r, z0]`` (the rows of
    the box); ``beta_cols`` those of ``(m_l, d_l, m_r, d_r, z0, v_1..v_K)``;
    ``col_keys``, ``row_keys`` what each column and row is (:func:`key`).
    """

    lp: HighsLP
    box_cols: np.ndarray
    beta_cols: np.ndarray
    structure: InnerStructure
    products: dict
    col_keys: np.ndarray | None = None
    row_keys: np.ndarray | None = None


def _inner_ranges(problem, box, st):
    """Bounds of the inner variables ``beta`` over the box."""
    p = problem.p
    ml, cl, mr, cr, z0 = (box[p + i] for i in range(5))
    dl = _prod_range(ml[0], ml[1], cl[0], cl[1])
    dr = _prod_range(mr[0], mr[1], cr[0], cr[1])
    lo = [ml[0], dl[0], mr[0], dr[0], z0[0]] + [a.lo for a in st.ambiguous]
    hi = [ml[1], dl[1], mr[1], dr[1], z0[1]] + [a.hi for a in st.ambiguous]
    return np.array(lo, dtype=float), np.array(hi, dtype=float)


def _form_terms(st, u, s):
    """Linear form of the inner value at sample(s) ``s``: (beta index, coefficient) lists
    of equal length per sample, as arrays (n, 2) of index and (n, 2) of coefficient."""
    s = np.asarray(s)
    kind, src = st.kind[s], st.src[s]
    idx = np.zeros((s.size, 2), dtype=np.int64)
    val = np.zeros((s.size, 2))
    r = kind == RIGHT
    idx[r] = [B_MR, B_DR]
    val[r, 0], val[r, 1] = u[src[r]], -1.0
    left = kind == LEFT
    idx[left] = [B_ML, B_DL]
    val[left, 0], val[left, 1] = u[src[left]], 1.0
    ini = kind == INIT
    idx[ini] = [B_Z0, B_Z0]
    val[ini] = [1.0, 0.0]
    amb = kind == AMBIG
    idx[amb, 0] = 5 + src[amb]
    idx[amb, 1] = 5 + src[amb]
    val[amb] = [1.0, 0.0]
    return idx, val


def _state_form(st, u, kind, src):
    """Linear form ((beta index, coefficient) pairs) of a state ``(kind, src)``."""
    if kind == RIGHT:
        return [(B_MR, u[src]), (B_DR, -1.0)]
    if kind == LEFT:
        return [(B_ML, u[src]), (B_DL, 1.0)]
    if kind == INIT:
        return [(B_Z0, 1.0)]
    return [(5 + src, 1.0)]


def _scale(problem, box):
    """Magnitude of the terms of every equation over the box (tolerance policy)."""
    p, na = problem.p, problem.na
    y, deta, t = problem.y, problem.deta, np.arange(problem.n0, problem.N)
    amax = np.max(np.abs(box[:na]), axis=1) if na else np.zeros(0)
    bmax = np.max(np.abs(box[na:p]), axis=1)
    xmax = max(abs(line_range(float(uu), box[p], box[p + 1], 1.0)[i])
               for uu in (problem.u.min(), problem.u.max()) for i in (0, 1))
    xmax = max(xmax, *(abs(line_range(float(uu), box[p + 2], box[p + 3], -1.0)[i])
                       for uu in (problem.u.min(), problem.u.max()) for i in (0, 1)),
               float(np.max(np.abs(box[p + 4]))))
    s = np.abs(y[t]) + deta[t]
    for i in range(1, na + 1):
        s = s + amax[i - 1] * (np.abs(y[t - i]) + deta[t - i])
    return s + float(np.sum(bmax)) * xmax


def build_relaxation(problem: RecordProblem, box, *, structure=None, decisions=None,
                     options=None, deadline=None, hull=None) -> JointRelaxation:
    """The LP relaxation over ``box`` (rows as :attr:`RecordProblem.box`); ``decisions``
    (``{t: branch}``, :func:`~.modes.inner_structure`) restrict it to the parameters that
    take those branches; ``hull``: the envelope rows of :mod:`.hull_rows` (None:
    :data:`HULL_ROWS`). Each solve stops after :data:`LP_TIME_LIMIT` s or at ``deadline``
    (:func:`time.time` stamp), keeping the bound its duals certify."""
    box = np.asarray(box, dtype=float)
    p = problem.p
    st = inner_structure(problem.u, box[p: p + 5], decisions) if structure is None \
        else structure
    cols = _Columns(problem, box, st)
    rows = _Rows()
    _equation_rows(rows, problem, box, st, cols)
    _gain_rows(rows, problem, box, cols)
    _envelope_rows(rows, problem, box, cols)
    _branch_rows(rows, problem, st, cols.beta)
    if HULL_ROWS if hull is None else hull:
        hull_rows(rows, problem, box, st, cols.beta, lambda t, j: key(K_HULL, t, j))
    _steady_rows(rows, problem, cols.beta)
    A, rl, ru = rows.matrix(cols.n)
    lp = HighsLP(A, rl, ru, np.concatenate(cols.lo), np.concatenate(cols.hi),
                 options={**LP_OPTIONS, **(options or {})}, run_limit=LP_TIME_LIMIT,
                 deadline=deadline)
    return JointRelaxation(lp, np.arange(p + 5), cols.beta, st,
                           {"prod": cols.prod, "eta": cols.eta, "q": cols.q},
                           np.concatenate(cols.keys), rows.row_keys())


class _Columns:
    """The LP's columns over a box, in this order: the box variables ``[theta, m_l, c_l,
    m_r, c_r, z0]``, ``d_l, d_r``, the values ``v`` of the ambiguous samples, the products
    ``theta_j beta_k`` (:attr:`prod`, (p, 5 + K)), the noise ``eta`` (N) and the products
    ``a_i eta_t`` (:attr:`q`), with their bounds and keys."""

    def __init__(self, problem, box, st):
        p = problem.p
        self.blo, self.bhi = blo, bhi = _inner_ranges(problem, box, st)
        self.lo, self.hi, self.keys, self.n = [], [], [], 0
        self.add(box[:, 0], box[:, 1], key(K_BOX, np.arange(p + 5)))  # theta .. z0
        col_dl, col_dr = self.add(blo[[B_DL, B_DR]], bhi[[B_DL, B_DR]],
                                  key(K_BOX, np.arange(p + 5, p + 7)))
        # the key of each inner variable: its position for the first five, 5 + t for the
        # value of ambiguous sample t
        self.bkey = np.concatenate([np.arange(5), 5 + np.array([a.t for a in st.ambiguous],
                                                               dtype=np.int64)])
        col_v = self.add(blo[5:], bhi[5:], key(K_V, self.bkey[5:]))
        self.beta = np.concatenate([[p, col_dl, p + 2, col_dr, p + 4], col_v]).astype(np.int64)
        self.dl_dr = (col_dl, col_dr)
        self._products(problem, box)

    def add(self, lo, hi, keys):
        """Append columns with bounds ``lo``, ``hi`` and keys; their indices."""
        lo = np.atleast_1d(np.asarray(lo, dtype=float))
        self.lo.append(lo)
        self.hi.append(np.broadcast_to(np.asarray(hi, dtype=float), lo.shape))
        self.keys.append(np.broadcast_to(np.asarray(keys, dtype=np.int64), lo.shape))
        idx = np.arange(self.n, self.n + lo.size)
        self.n += lo.size
        return idx

    def _products(self, problem, box):
        """The products ``b_j beta_k``, ``a_i beta_k`` (RLT), the noise and ``a_i eta_t``."""
        p, na, N = problem.p, problem.na, problem.N
        nbeta = self.beta.size
        self.th_lo, self.th_hi = th_lo, th_hi = box[:p, 0], box[:p, 1]
        jj, kk = np.meshgrid(np.arange(p), np.arange(nbeta), indexing="ij")
        self.jj, self.kk = jj, kk = jj.ravel(), kk.ravel()
        self.pl, self.ph = _prod_range(th_lo[jj], th_hi[jj], self.blo[kk], self.bhi[kk])
        self.prod_keys = key(K_PROD, jj, self.bkey[kk])
        self.prod = self.add(self.pl, self.ph, self.prod_keys).reshape(p, nbeta)
        self.eta = self.add(-problem.deta, problem.deta, key(K_ETA, np.arange(N)))
        self.t_eq = t_eq = np.arange(problem.n0, N)
        self.qi = np.repeat(np.arange(na), t_eq.size)
        self.qt = np.concatenate([t_eq - i for i in range(1, na + 1)]) if na \
            else np.zeros(0, dtype=np.int64)
        ql, qh = _prod_range(th_lo[self.qi], th_hi[self.qi], -problem.deta[self.qt],
                             problem.deta[self.qt])
        self.q_keys = key(K_Q, self.qi, self.qt)
        self.q = self.add(ql, qh, self.q_keys)


def _equation_rows(rows, problem, box, st, cols):
    """The equations of :mod:`.problem`, linear in the columns, widened by the tolerance
    policy."""
    na, y, t_eq = problem.na, problem.y, cols.t_eq
    m = t_eq.size
    er, ec, ev = [np.arange(m)], [cols.eta[t_eq]], [-np.ones(m)]
    for i in range(1, na + 1):
        er += [np.arange(m), np.arange(m)]
        ec += [np.full(m, i - 1), cols.q[(i - 1) * m: i * m]]
        ev += [y[t_eq - i], -np.ones(m)]
    for jpos, lag in enumerate(problem.b_lags):
        idx, val = _form_terms(st, problem.u, t_eq - lag)
        for c in range(2):
            er.append(np.arange(m))
            ec.append(cols.prod[na + jpos, idx[:, c]])
            ev.append(-val[:, c])
    tau = FEASIBILITY_RTOL * _scale(problem, box)
    rows.add(np.concatenate(er), np.concatenate(ec), np.concatenate(ev),
             round_down(-y[t_eq] - tau), round_up(-y[t_eq] + tau), key=key(K_EQ, t_eq))


def gain_tolerance(g, theta_box) -> float:
    """The outward tolerance of the gain equality (22.8) ``sum b - g sum a = g`` over the
    box ``theta_box`` of ``theta`` (rows): the row of the relaxation holds within it."""
    return FEASIBILITY_RTOL * (abs(g) + float(np.sum(np.max(np.abs(theta_box), axis=1)))
                               * max(1, abs(g)))


def _gain_rows(rows, problem, box, cols):
    """The gain equality (22.8) and its RLT rows (multiplied by every inner variable)."""
    p, na = problem.p, problem.na
    nbc, nbeta = p - na, cols.beta.size
    blo, bhi = cols.blo, cols.bhi
    g = float(problem.gain)
    gvals = np.concatenate([-g * np.ones(na), np.ones(nbc)])
    gtol = gain_tolerance(g, box[:p])
    rows.add(np.zeros(p, dtype=np.int64), np.arange(p), gvals, g - gtol, g + gtol,
             key=key(K_GAIN))
    pmax = np.maximum(np.abs(cols.pl), np.abs(cols.ph)).reshape(p, nbeta)
    for k in range(nbeta):
        c = np.concatenate([cols.prod[na:, k], cols.prod[:na, k], [cols.beta[k]]])
        vals = np.concatenate([np.ones(nbc), -g * np.ones(na), [-g]])
        bmax = max(abs(blo[k]), abs(bhi[k]))
        t = FEASIBILITY_RTOL * (float(np.sum(pmax[:, k])) + abs(g) * bmax) + gtol * bmax
        rows.add(np.zeros(c.size, dtype=np.int64), c, vals, -t, t, key=key(K_RLT, cols.bkey[k]))


def _envelope_rows(rows, problem, box, cols):
    """McCormick envelopes of the products ``theta_j beta_k``, ``a_i eta_t`` and ``d = m c``."""
    p, jj, kk, qi, qt = problem.p, cols.jj, cols.kk, cols.qi, cols.qt
    th_lo, th_hi = cols.th_lo, cols.th_hi
    rows.mccormick(cols.prod.ravel(), jj, cols.beta[kk], th_lo[jj], th_hi[jj], cols.blo[kk],
                   cols.bhi[kk], cols.prod_keys)
    rows.mccormick(cols.q, qi, cols.eta[qt], th_lo[qi], th_hi[qi], -problem.deta[qt],
                   problem.deta[qt], cols.q_keys)
    ml, cl, mr, cr = (box[p + i] for i in range(4))
    rows.mccormick(list(cols.dl_dr), [p, p + 2], [p + 1, p + 3], [ml[0], mr[0]],
                   [ml[1], mr[1]], [cl[0], cr[0]], [cl[1], cr[1]], key(K_MC_D, [0, 1]))


def _band(rows, u_t, coef_x, bc, x_terms, k):
    """``R_t <= x <= L_t`` for a linear form ``x`` (list of (column, coefficient)); row keys
    ``k`` and ``k + 1``."""
    cols = [c for c, _ in x_terms]
    vals = [v for _, v in x_terms]
    # x - m_r u + d_r >= 0
    rows.add(np.zeros(len(cols) + 2, dtype=np.int64), [*cols, bc[B_MR], bc[B_DR]],
             [*vals, -u_t, 1.0], 0.0, np.inf, key=k)
    # x - m_l u - d_l <= 0
    rows.add(np.zeros(len(cols) + 2, dtype=np.int64), [*cols, bc[B_ML], bc[B_DL]],
             [*vals, -u_t, -1.0], -np.inf, 0.0, key=k + 1)


def _branch_rows(rows, problem, st, bc):
    """Bands, the one-sided rows of ambiguous samples, and well-posedness."""
    u = problem.u
    _band(rows, u[0], 1.0, bc, [(bc[B_Z0], 1.0)], key(K_BAND0))
    for k, a in enumerate(st.ambiguous):
        v = bc[5 + k]
        _band(rows, u[a.t], 1.0, bc, [(v, 1.0)], key(K_BAND, a.t))
        s_terms = [(bc[i], c) for i, c in _state_form(st, u, a.src_kind, a.src)]
        cols = [v] + [c for c, _ in s_terms]
        vals = [1.0] + [-c for _, c in s_terms]
        if not a.up:  # x_t = min(L_t, S) <= S
            rows.add(np.zeros(len(cols), dtype=np.int64), cols, vals, -np.inf, 0.0,
                     key=key(K_ONE, a.t, 0))
        if not a.down:  # x_t = max(R_t, S) >= S
            rows.add(np.zeros(len(cols), dtype=np.int64), cols, vals, 0.0, np.inf,
                     key=key(K_ONE, a.t, 1))
    for d in st.decided:
        _decision_rows(rows, u[d.t], bc, _state_form(st, u, d.src_kind, d.src), d.branch,
                       key(K_DEC, d.t))
    for i, uu in enumerate((float(u.min()), float(u.max()))):  # (m_l - m_r) u + d_l + d_r >= 0
        rows.add(np.zeros(4, dtype=np.int64), [bc[B_ML], bc[B_MR], bc[B_DL], bc[B_DR]],
                 [uu, -uu, 1.0, 1.0], 0.0, np.inf, key=key(K_WELL, i))


def _decision_rows(rows, u_t, bc, s_form, branch, k):
    """The inequalities of a decided sample (:class:`~.modes.Decided`) with the state ``S``
    before it (a linear form): ``UP``: ``R_t >= S``; ``DOWN``: ``L_t <= S``; ``HOLD``: both
    ``R_t <= S`` and ``L_t >= S``."""
    s_cols = [bc[i] for i, _ in s_form]
    s_vals = [-c for _, c in s_form]
    r_cols, r_vals = [bc[B_MR], bc[B_DR], *s_cols], [u_t, -1.0, *s_vals]  # R_t - S
    l_cols, l_vals = [bc[B_ML], bc[B_DL], *s_cols], [u_t, 1.0, *s_vals]  # L_t - S
    zr, zl = np.zeros(len(r_cols), dtype=np.int64), np.zeros(len(l_cols), dtype=np.int64)
    if branch == UP:
        rows.add(zr, r_cols, r_vals, 0.0, np.inf, key=k)
    elif branch == DOWN:
        rows.add(zl, l_cols, l_vals, -np.inf, 0.0, key=k + 1)
    else:
        rows.add(zr, r_cols, r_vals, -np.inf, 0.0, key=k + 2)
        rows.add(zl, l_cols, l_vals, 0.0, np.inf, key=k + 3)


def _steady_rows(rows, problem, bc):
    """Steady-state points: ``|y_i - line(u_i)| <= deta_i`` (widened by the tolerance)."""
    if problem.steady is None:
        return
    us, ys, ds = problem.steady
    for i, (ui, yi, di) in enumerate(zip(us, ys, ds, strict=True)):
        tol = FEASIBILITY_RTOL * (abs(yi) + di) + di * FEASIBILITY_RTOL
        if ui > 0:
            cols, vals = [bc[B_MR], bc[B_DR]], [ui, -1.0]
        else:
            cols, vals = [bc[B_ML], bc[B_DL]], [ui, 1.0]
        rows.add(np.zeros(2, dtype=np.int64), cols, vals, round_down(yi - di - tol),
                 round_up(yi + di + tol), key=key(K_STEADY, i))
