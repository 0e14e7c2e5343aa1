"""Sparse Lasserre (moment) relaxations of the EIV parameter bounds (22.36)-(22.37).

The feasible set (22.34) is a basic semi-algebraic set in ``(theta, eta, dx)`` defined by
bilinear equalities (one per equation ``t``), boxes and the linear gain equality (22.8).
Its correlative sparsity is exploited as in Lasserre (2006) / Waki et al. (2006) and
Cerone, Piga & Regruto (reference [5] of the chapter): clique ``I_t`` holds theta and the
noise variables equation ``t`` touches (``eta_{t-i}``, ``i = 0..na`` and the input-error
variables ``dx[g(t-j)]``, see :meth:`EIVProblem.dx_index`). At relaxation order ``delta``:

* one moment matrix ``M_delta(y, I_t) >= 0`` per clique;
* localizing matrices ``M_{delta-1}((1 - v^2) y, I_t) >= 0`` for every (scaled) variable
  ``v`` of the clique (the boxes on eta, dx and theta);
* localizing equalities ``L_y(h_t x^alpha) = 0`` for ``|alpha| <= 2 delta - 2`` (``h_t`` is
  equation ``t``, degree 2);
* the gain equality (22.8) is removed by *facial reduction*: one coefficient is eliminated
  (it is affine in the others), its box becomes a degree-2 localizing constraint.

Monomials shared by several cliques are one moment variable. All variables are scaled to
``[-1, 1]``, so every moment of a feasible point satisfies ``|y_alpha| <= 1``; these a priori
bounds turn each (possibly inaccurate) dual solution into a *guaranteed* bound through
:func:`hammerbound.solvers.conic.verified_lower_bound` (the best over the solver's dual, its
least-squares repair and alternating cone projections:
:func:`~hammerbound.solvers.conic.best_certificate`). A bound that cannot be certified
falls back to the a priori box end; the solver's objective value is never reported.
"""

from __future__ import annotations

import time
from math import comb

import numpy as np
import scipy.sparse as sp

from ...exceptions import ParameterValidationError
from ...solvers import get_solver
from ...solvers.conic import (
    extract_conic_data,
)
from ..problem import EIVProblem
from ..result import IntervalResult, MomentDetails
from .basis import (  # noqa: F401 - re-exported for compatibility
    BASES,
    _affine,
    _clique_constraints,
    _monomials,
    _pmul,
    _ScaledPOP,
    _sparse_basis,
)
from .certify import Lines, ends, solve_all

#: Largest number of entries (rows x moment variables) of one block of equality rows
#: handed to PICOS (whose constants index their entries with 32 bits).
EQ_BLOCK_ENTRIES = 2**30


class _MomentIndex:
    """Column of each moment ``y_alpha`` (a sorted tuple of variable indices), numbered
    in the order met."""

    def __init__(self):
        self.index = {}

    def __call__(self, mono) -> int:
        j = self.index.get(mono)
        if j is None:
            j = self.index[mono] = len(self.index)
        return j


def _equality_rows(eqs, idx):
    """The equalities ``eqs`` (polynomials == 0) as ``Aeq y == -ecst`` over the moments
    ``y_alpha``, alpha != 0 (column ``idx - 1``): ``((vals, rows, cols), ecst)``, or
    ``(None, None)`` without equalities."""
    if not eqs:
        return None, None
    erows, ecols, evals, ecst = [], [], [], np.zeros(len(eqs))
    for i, h in enumerate(eqs):
        for mono, coef in h.items():
            j = idx(mono)
            if j == 0:
                ecst[i] += coef
            else:
                erows.append(i)
                ecols.append(j - 1)
                evals.append(coef)
    return (evals, erows, ecols), ecst


class MomentRelaxation:
    """Sparse moment relaxation of order ``delta`` of the EIV set, formulated in PICOS.

    Parameters
    ----------
    problem : EIVProblem
    order : int
        Relaxation order ``delta >= 1`` (moments up to degree ``2 delta``).
    theta_box : ndarray, shape (p, 2), optional
        A priori box (default ``problem.theta_box``).
    basis : {"sparse", "full"}, default "sparse"
        Monomials indexing each clique's moment matrix (scaled variables: ``theta`` the
        free coefficients, ``e`` the clique's noise variables ``eta``, ``dx``):

        * ``"full"``: every monomial of degree ``<= delta`` (Lasserre 2006, Waki et al.
          2006); localizing matrices ``(1 - v^2) M_{delta-1}`` for every clique variable and
          equality products ``h_t x^alpha``, ``|alpha| <= 2 delta - 2``;
        * ``"sparse"`` (term sparsity; differs from ``"full"`` for ``delta >= 2``): the
          equations are bilinear in ``theta x e``, so the basis is ``theta^a e^b`` with
          ``|b| <= 1``, ``|a| + |b| <= delta``, without the pure-theta monomials of
          degree ``delta`` (order 2: ``1, theta, e, theta e``, 24 instead of 45 monomials
          for ``na = nb = 2``). A noise box ``(1 - e^2) >= 0`` is localized on the largest
          basis whose products stay inside the moment matrix (order 2: ``1, theta``), the
          theta boxes are scalar, and an equality product ``h_t x^alpha = 0`` is kept when
          all its monomials are entries of the moment matrix. Every constraint is one of a
          valid relaxation, so this is a valid (possibly looser) relaxation; identical
          localizing matrices of overlapping cliques are added once. Measured equal to
          the exact intervals within ``1e-4`` of their width on the chapter example
          (``docs/benchmarks.md``).

    Attributes
    ----------
    picos_problem : picos.Problem
        The relaxation with a placeholder objective (minimise ``theta_1``).
    data : ConicData
        Conic form extracted once from :attr:`picos_problem`.
    n_moments : int
    n_psd_blocks : int
        Matrix blocks of side >= 2.
    psd_sides : dict
        Side -> number of blocks (side 1: scalar inequalities).
    """

    def __init__(self, problem: EIVProblem, order: int = 2, theta_box=None,
                 basis: str = "sparse"):
        if int(order) != order or order < 1:
            raise ParameterValidationError(f"order must be an integer >= 1; got {order!r}.")
        if basis not in BASES:
            raise ParameterValidationError(
                f"basis must be one of {', '.join(map(repr, BASES))}; got {basis!r}.")
        self.order = order = int(order)
        self.basis = basis
        box = problem.theta_box if theta_box is None else np.asarray(theta_box, dtype=float)
        if box.shape != (problem.p, 2) or not np.all(np.isfinite(box)) or np.any(
            box[:, 0] > box[:, 1]
        ):
            raise ParameterValidationError(
                f"theta_box must be a finite ({problem.p}, 2) array with lower <= upper."
            )
        self.problem = problem
        self.box = box
        self.pop = pop = _ScaledPOP(problem, box)
        idx = _MomentIndex()
        idx(())  # y_0 = 1, eliminated below
        for j in range(pop.q):
            idx((j,))
        blocks, eqs = self._constraints(pop, order, basis, idx)
        # equality moments are registered too (a moment outside every matrix is a free
        # variable, still bounded by |y| <= 1 for the certificate)
        triplets, ecst = _equality_rows(eqs, idx)
        self.index = idx.index
        self.n_moments = m = len(idx.index) - 1  # y_alpha, alpha != 0 (column j-1)
        Aeq = None if triplets is None else sp.csr_matrix(
            (triplets[0], (triplets[1], triplets[2])), shape=(len(eqs), m))
        self.picos_problem, self.y = self._picos(blocks, Aeq, ecst, m)
        sides = sorted({dim for *_, dim in blocks})
        self.psd_sides = {int(d): sum(1 for *_, dd in blocks if dd == d) for d in sides}
        self.n_psd_blocks = sum(1 for *_, dim in blocks if dim > 1)
        self.data = extract_conic_data(self.picos_problem)
        self.xub = np.ones(m)  # |y_alpha| <= 1 for every point of [-1, 1]^n

    def _constraints(self, pop, order, basis, idx):
        """The moment and localizing matrices (``(rows, cols, vals, dim)``: vec, column-
        major, over moment indices) and the equalities (polynomials, dict mono -> coef,
        ``== 0``) of every clique."""
        blocks, eqs = [], []
        seen = set()  # identical localizing matrices of overlapping cliques: once
        for cvars, hs in pop.cliques:
            for g, b in _clique_constraints(cvars, hs, pop, order, basis):
                if g is None:  # equalities h x^alpha = 0
                    eqs += [{tuple(sorted(m + a)): c for m, c in h.items()}
                            for h in hs for a in b]
                    continue
                key = (tuple(sorted(g.items())), tuple(b))
                if key not in seen:
                    seen.add(key)
                    blocks.append(self._loc_matrix(g, b, idx))
        if not pop.cliques:  # no equation: only theta-box constraints
            blocks.append(self._loc_matrix({(): 1.0}, _monomials(list(range(pop.q)), order),
                                           idx))
        return blocks, eqs

    def _picos(self, blocks, Aeq, ecst, m):
        """The PICOS problem over the moments ``y`` (m,) with a placeholder objective."""
        import picos

        y = picos.RealVariable("y", m)
        P = picos.Problem()
        for k, (rows, cols, vals, dim) in enumerate(blocks):
            expr = _affine(y, rows, cols, vals, dim, f"M{k}")
            P.add_constraint(expr >= 0 if dim == 1 else expr >> 0)
        if Aeq is not None:
            # PICOS holds a constant matrix as a vector of rows x columns entries with 32-bit
            # indices (cvxopt): above 2^31 the build crashed (a SystemError at N = 2000,
            # order 2), so the equalities go in blocks of rows below that
            step = max(1, EQ_BLOCK_ENTRIES // max(1, m))
            for r0 in range(0, Aeq.shape[0], step):
                P.add_constraint(picos.Constant(Aeq[r0:r0 + step].tocsc()) * y
                                 == picos.Constant(-ecst[r0:r0 + step]))
        P.set_objective("min", picos.Constant(self._objective(0)[0].reshape(1, -1)) * y)
        return P, y

    @staticmethod
    def _loc_matrix(g, basis, idx):
        """Coefficients of ``vec(M(g y))`` (column-major) as COO lists over moment indices."""
        dim = len(basis)
        rows, cols, vals = [], [], []
        for jcol, bj in enumerate(basis):
            for irow, bi in enumerate(basis):
                base = bi + bj
                for mono, coef in g.items():
                    rows.append(irow + jcol * dim)
                    cols.append(idx(tuple(sorted(base + mono))))
                    vals.append(coef)
        return rows, cols, vals, dim

    def _objective(self, k: int):
        """``theta_k = c0_k + q . y`` with ``q`` of shape (n_moments,)."""
        q = np.zeros(self.n_moments)
        for j in range(self.pop.q):
            q[self.index[(j,)] - 1] = self.pop.T[k, j]
        return q, float(self.pop.c0[k])

    def objectives(self):
        """The ``2 p`` minimisation objectives ``(k, sense, q, q0)``: ``min theta_k`` and
        ``min -theta_k``."""
        out = []
        for k in range(self.problem.p):
            q, c = self._objective(k)
            out.append((k, "min", q, c))
            out.append((k, "max", -q, -c))
        return out


def moment_bounds(
    problem: EIVProblem,
    order: int = 2,
    solver: str = "clarabel",
    solver_options: dict | None = None,
    n_jobs: int = 1,
    theta_box=None,
    *,
    on_failure: str = "box",
    fallback=None,
    max_work: float | None = None,
    warn_work: float | None = None,
    basis: str = "sparse",
    lp: IntervalResult | None = None,
    progress: bool = False,
) -> IntervalResult:
    """Guaranteed parameter uncertainty intervals (22.35) from the sparse moment relaxation.

    Solves the ``2 p`` relaxed problems ``min / max theta_k`` over the order-``order`` sparse
    Lasserre relaxation of (22.34) (see the module docstring) and certifies each bound from
    the dual solution (:func:`~hammerbound.solvers.conic.verified_lower_bound`).

    Parameters
    ----------
    problem : EIVProblem
        The EIV problem (22.34).
    order : int, default 2
        Relaxation order ``delta``.
    solver : str, default "clarabel"
        A conic backend of :func:`~hammerbound.solvers.available_solvers`
        (``"clarabel"``, ``"cvxopt"``, ``"qics"``, ``"mosek"``).
    solver_options : dict, optional
        Native solver options (e.g. ``{"max_iter": 50}`` for Clarabel).
    n_jobs : int, default 1
        Worker processes (joblib) over the ``2 p`` objectives.
    theta_box : ndarray, shape (p, 2), optional
        A priori box (default ``problem.theta_box``), e.g. from the polytopic LP bounds. The
        reported intervals always lie inside it.
    on_failure : {"box", "raise"}
        When no certificate can be computed for a bound: report the fallback end
        (``certified=False``: the bound is still guaranteed, by the fallback's certificate)
        or raise :class:`SolverError`.
    fallback : ndarray, shape (p, 2), optional
        Certified outer bounds already known: every reported interval is intersected with
        them, and an end whose certificate is not tighter (or missing, with
        ``on_failure="box"``) reports the fallback end. Default: the polytopic LP bounds
        (``lp`` when given, else computed here), intersected with ``theta_box`` when one
        is given, so no end is ever wider than the LP bound, nor from the a priori box
        where the LP bound is tighter.
    max_work : float, optional
        Budget on the relaxation's estimated seconds (one core: building it and the
        ``2 p`` solves), checked *before* it is built, with its estimated memory
        (:mod:`hammerbound.relaxations.moment.size`); default ``MOMENT_MAX_WORK = 3600``
        (with ``na = nb = 2`` sparse order 2 reaches it at N ~ 1800, the full order-2
        basis at N ~ 60, order 3 at N ~ 13; the memory check refuses sparse order 2 above
        N ~ 500 on 24 GB with 2 workers); ``inf`` skips the checks (and the warning).
    warn_work : float, optional
        Above this estimate (seconds, one core) a :class:`RuntimeWarning` says the
        relaxation will take minutes; default ``MOMENT_WARN_WORK = 60``.
    basis : {"sparse", "full"}, default "sparse"
        Monomial basis of the moment matrices (see :class:`MomentRelaxation`). Order 1:
        both are the same. Order 2: ``"sparse"`` (``1, theta, e, theta e`` per clique) is
        the one usable at the chapter's N = 100 (about 40x smaller PSD blocks); ``"full"``
        (every monomial of degree <= 2, Lasserre's dense-per-clique relaxation) is at
        least as tight and costs minutes already at N = 10-20.
    lp : IntervalResult, optional
        The polytopic LP result of ``problem`` (:func:`~hammerbound.relaxations.lp_bounds`)
        when already computed: its bounds are then the a priori box and the fallback
        (unless ``theta_box``/``fallback`` are given), and it is kept as ``result.lp``.
    progress : bool, default False
        Lines on stderr (never stdout): the relaxation's size once built, then each bound
        as its conic solve ends (with ``n_jobs > 1``: each worker's bounds as it ends).

    Returns
    -------
    IntervalResult
        ``bounds`` shape ``(p, 2)``; ``infos`` holds ``2 p`` :class:`BoundInfo` (p0 min,
        p0 max, ...) with their dual ``certificate``; method ``"moment"``. Each end's
        status says where its value comes from: the moment certificate when it is tighter
        than the fallback (``OPTIMAL``, or ``INACCURATE`` / ``LIMIT`` when the solver
        stopped early and the bound comes from its dual), else the fallback end:
        ``RELAXATION`` (the LP bound) or ``BOX`` (only where the fallback end is
        ``problem.theta_box`` itself). ``lp`` is the LP result used (given or computed
        here, else None); ``details`` has the relaxation's size and build time
        (:class:`~hammerbound.relaxations.result.MomentDetails`).

    Raises
    ------
    SolverNotAvailableError, SolverOptionError
        Unknown/missing solver or options.
    SolverError
        With ``on_failure="raise"`` when a bound cannot be certified.
    RelaxationTooLargeError
        The relaxation's estimated size exceeds ``max_work`` (the message gives the
        estimate and the alternatives ``method="lp"`` / ``"exact"``).
    """
    from .size import check_moment_budget, estimate_moment_relaxation, solve_processes

    max_work, warn_work = _check_args(on_failure, basis, max_work, warn_work)
    t_start = time.perf_counter()
    if lp is not None and theta_box is None:
        theta_box = lp.bounds
    if lp is not None and fallback is None:
        fallback = lp.bounds
    backend = get_solver(solver)
    opts = backend.check_options(solver_options)
    _check_box(problem, theta_box)
    if int(order) == order and order >= 1 and not max_work == np.inf:
        # (a bad order is reported by MomentRelaxation; max_work=inf: checked by the caller)
        size = estimate_moment_relaxation(problem, order, theta_box, basis=basis)
        check_moment_budget(size, max_work=max_work, warn_work=warn_work,
                            processes=solve_processes(n_jobs, problem.p))
    fallback, lp = _fallback(problem, fallback, lp, theta_box)
    # tolerance policy: the relaxation (and its dual certificate) is built on the data with
    # every equation relaxed outward by FEASIBILITY_RTOL x the magnitudes of its terms
    from ..problem import outward_problem

    scale_box = problem.theta_box if theta_box is None else np.asarray(theta_box, dtype=float)
    relax = MomentRelaxation(outward_problem(problem, scale_box), order, theta_box,
                             basis=basis)
    t_build = time.perf_counter() - t_start
    objs = relax.objectives()
    say = Lines(progress, t_start, objs, problem.param_names)
    say(f"order-{relax.order} {relax.basis} relaxation built in {t_build:.1f} s "
        f"({relax.n_moments} moments, {relax.n_psd_blocks} PSD blocks); solving "
        f"{len(objs)} bounds with {backend.name}")
    results = solve_all(relax, objs, backend, opts, solve_processes(n_jobs, problem.p),
                         say.done)
    bounds, infos = ends(problem, relax.box, objs, results, fallback, backend.name,
                          on_failure)
    names = problem.param_names
    return IntervalResult(
        param_names=tuple(names), bounds=bounds, infos=tuple(infos), method="moment",
        time=time.perf_counter() - t_start,
        status=tuple((infos[2 * k].status, infos[2 * k + 1].status) for k in range(len(names))),
        lp=lp,
        details=MomentDetails(
            order=relax.order, basis=relax.basis, solver=backend.name,
            n_moments=relax.n_moments, n_psd_blocks=relax.n_psd_blocks,
            psd_sides=dict(relax.psd_sides), nnz=int(relax.data.A.nnz),
            n_cliques=len(relax.pop.cliques), build_time=t_build,
            eliminated=None if relax.pop.elim is None else names[relax.pop.elim],
            n_rows=relax.data.m),
    )


def _check_args(on_failure, basis, max_work, warn_work):
    """Refuse bad options of :func:`moment_bounds`; the checked ``max_work`` and
    ``warn_work``."""
    from .size import MOMENT_WARN_WORK, check_work

    if max_work is not None:
        max_work = check_work("max_work", max_work)
    if warn_work is not None:
        warn_work = check_work("warn_work", warn_work, default=MOMENT_WARN_WORK)
    if on_failure not in ("box", "raise"):
        raise ParameterValidationError("on_failure must be 'box' or 'raise'.")
    if basis not in BASES:
        raise ParameterValidationError(
            f"basis must be one of {', '.join(map(repr, BASES))}; got {basis!r}.")
    return max_work, warn_work


def _check_box(problem, theta_box):
    """Refuse an a priori box that is not a finite ``(p, 2)`` array with lower <= upper."""
    if theta_box is not None:
        tb = np.asarray(theta_box, dtype=float)
        if tb.shape != (problem.p, 2) or not np.all(np.isfinite(tb)) or np.any(
            tb[:, 0] > tb[:, 1]
        ):
            raise ParameterValidationError(
                f"theta_box must be a finite ({problem.p}, 2) array with lower <= upper."
            )


def _fallback(problem, fallback, lp, theta_box):
    """The certified outer bounds no moment end is reported wider than (see
    :func:`moment_bounds`), and the LP result (computed here when needed)."""
    if fallback is None:
        # the polytopic LP bound is cheap and certified: a moment end is never reported
        # wider than it (nor from the a priori box where the LP bound is tighter)
        if lp is None:
            from ..lp import lp_bounds

            lp = lp_bounds(problem, check_box=False)
        fallback = lp.bounds
        if theta_box is not None:  # both are certified outer bounds: keep the tighter ends
            tb = np.asarray(theta_box, dtype=float)
            fallback = np.column_stack([np.maximum(fallback[:, 0], tb[:, 0]),
                                        np.minimum(fallback[:, 1], tb[:, 1])])
    fallback = np.asarray(fallback, dtype=float)
    if fallback.shape != (problem.p, 2):
        raise ParameterValidationError(
            f"fallback must be an array of shape ({problem.p}, 2); got {fallback.shape}.")
    return fallback, lp


def relaxation_size(n_vars_clique: int, order: int) -> int:
    """Side of the moment matrix of one clique: ``binom(n + delta, delta)``."""
    return comb(n_vars_clique + order, order)
