"""Conic data extracted from a PICOS problem and *verified* dual bounds.

Every backend of :mod:`hammerbound.solvers` works on the standard conic form used by
Clarabel::

    min  q' x + q0    s.t.  A x + s = b,   s in K = Z^{m0} x R_+^{m1} x SOC x ... x S_+ ...
    max  -b' z + q0   s.t.  q + A' z = 0,  z in K*                        (dual)

with positive semidefinite blocks stored as ``svec``: the upper triangle, column by
column, off-diagonal entries multiplied by ``sqrt(2)`` (so that ``svec(X)'svec(Y) =
<X, Y>``).

:func:`verified_lower_bound` turns *any* approximate dual vector ``z`` into a rigorous
lower bound of ``min q'x`` over every ``x`` that satisfies the constraints and the a priori
box ``|x_i| <= xub_i`` (Jansson, Chaykin & Keil, 2007, "Rigorous error bounds for the
optimal value in semidefinite programming"). For every such ``x`` with slack ``s = b - A x``::

    q'x = -b'z + <z, s> + r'x,       r = q + A'z
        >= -b'z + sum_K min(0, lambda_min(Z_K)) * trace_ub(S_K) - sum_i |r_i| xub_i

(for a PSD block ``<Z, S> >= lambda_min(Z) trace(S)`` because ``S >= 0``; the analogue for
the non-negative orthant and the second-order cone is used for the other blocks). The
floating-point evaluation is covered by a rounding margin, so the result is a lower bound of
the exact value whatever the accuracy of the solver that produced ``z``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

EPS = np.finfo(float).eps
SQRT2 = np.sqrt(2.0)


@dataclass
class ConicData:
    """A conic problem in Clarabel's standard form (see module docstring).

    Attributes
    ----------
    q : ndarray, shape (n,)
        Objective coefficients of the *minimisation* (a PICOS ``max`` is negated).
    q0 : float
        Objective constant (already sign-adjusted like ``q``).
    sense : {"min", "max"}
        Direction of the PICOS objective; the PICOS value is ``sign * (q'x + q0)``.
    A : scipy.sparse.csc_matrix, shape (m, n)
    b : ndarray, shape (m,)
    cones : list of tuple
        ``("z", k)`` zero cone, ``("l", k)`` non-negative orthant, ``("q", k)`` second-order
        cone, ``("s", n)`` PSD cone of ``n x n`` matrices (``n (n+1) / 2`` rows), in row order.
    var_offsets : dict
        PICOS variable -> column offset.
    con_rows : dict
        PICOS constraint -> ``(kind, start, stop)`` row range (bounds of variables are not
        listed).
    """

    q: np.ndarray
    q0: float
    sense: str
    A: sp.csc_matrix
    b: np.ndarray
    cones: list
    var_offsets: dict = field(default_factory=dict)
    con_rows: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return self.A.shape[1]

    @property
    def m(self) -> int:
        return self.A.shape[0]

    def cone_slices(self):
        """Yield ``(kind, dim, slice)`` for every cone block in row order."""
        start = 0
        for kind, dim in self.cones:
            size = dim * (dim + 1) // 2 if kind == "s" else dim
            yield kind, dim, slice(start, start + size)
            start += size

    def strip_picos(self) -> ConicData:
        """Copy without the PICOS references (cheap to pickle for worker processes)."""
        return ConicData(self.q, self.q0, self.sense, self.A, self.b, list(self.cones))


@dataclass
class ConicSolution:
    """Raw outcome of one conic solve (any backend).

    Attributes
    ----------
    status : str
        A constant of :mod:`hammerbound.status` (``OPTIMAL``, ``INACCURATE``,
        ``INFEASIBLE``, ``LIMIT``, ``FAILED``).
    native_status : str
        The solver's own word.
    x : ndarray, shape (n,) or None
    z : ndarray, shape (m,) or None
        Dual vector in the convention of this module.
    primal_value, dual_value : float
        ``q'x + q0`` and ``-b'z + q0`` as reported (not guaranteed).
    iterations : int or None
    time : float
    """

    status: str
    native_status: str
    x: np.ndarray | None
    z: np.ndarray | None
    primal_value: float
    dual_value: float
    iterations: int | None
    time: float


# ---------------------------------------------------------------------------------------
# svec helpers
# ---------------------------------------------------------------------------------------


def svec_transform(n: int) -> sp.csr_matrix:
    """Sparse ``T`` (n(n+1)/2 x n^2) with ``svec(X) = T vec(X)`` for column-major vec.

    Off-diagonal entries use ``(X_ij + X_ji) / sqrt(2)``, so ``T`` symmetrises on the fly.
    """
    rows, cols, vals = [], [], []
    k = 0
    for j in range(n):
        for i in range(j + 1):
            if i == j:
                rows.append(k)
                cols.append(i + j * n)
                vals.append(1.0)
            else:
                rows += [k, k]
                cols += [i + j * n, j + i * n]
                vals += [1.0 / SQRT2, 1.0 / SQRT2]
            k += 1
    return sp.csr_matrix((vals, (rows, cols)), shape=(n * (n + 1) // 2, n * n))


def smat_transform(n: int) -> sp.csr_matrix:
    """Sparse ``E`` (n^2 x n(n+1)/2) with ``vec(X) = E svec(X)`` (column-major, symmetric)."""
    rows, cols, vals = [], [], []
    k = 0
    for j in range(n):
        for i in range(j + 1):
            if i == j:
                rows.append(i + j * n)
                cols.append(k)
                vals.append(1.0)
            else:
                rows += [i + j * n, j + i * n]
                cols += [k, k]
                vals += [1.0 / SQRT2, 1.0 / SQRT2]
            k += 1
    return sp.csr_matrix((vals, (rows, cols)), shape=(n * n, n * (n + 1) // 2))


def smat(v: np.ndarray, n: int) -> np.ndarray:
    """Symmetric ``n x n`` matrix from its ``svec`` (shape ``(n (n+1) / 2,)``)."""
    X = np.zeros((n, n))
    iu = np.triu_indices(n)
    # triu_indices is row-major; svec is column-major over the upper triangle (= row-major
    # over the lower triangle), so order the pairs by (column, row)
    order = np.lexsort((iu[0], iu[1]))
    r, c = iu[0][order], iu[1][order]
    vals = np.where(r == c, v, v / SQRT2)
    X[r, c] = vals
    X[c, r] = vals
    return X


# ---------------------------------------------------------------------------------------
# extraction from PICOS
# ---------------------------------------------------------------------------------------


def extract_conic_data(problem) -> ConicData:
    """Convert a continuous PICOS problem with affine, SOC and LMI constraints to
    :class:`ConicData`.

    Parameters
    ----------
    problem : picos.Problem
        Affine objective; constraints of type ``AffineConstraint``, ``SOCConstraint``,
        ``LMIConstraint`` (real symmetric) or ``DummyConstraint``.

    Returns
    -------
    ConicData
    """
    from picos.constraints import (
        AffineConstraint,
        DummyConstraint,
        LMIConstraint,
        SOCConstraint,
    )

    from ..exceptions import SolverError

    offsets = {}
    n = 0
    for var in problem.variables.values():
        offsets[var] = n
        n += var.dim

    def gh(expr):
        G, h = expr.scipy_sparse_matrix_form(varOffsetMap=offsets, dense_b=True)
        G = sp.csr_matrix(G)
        if G.shape[1] != n:
            G = sp.csr_matrix((G.data, G.indices, G.indptr), shape=(G.shape[0], n))
        return G, np.asarray(h, dtype=float).ravel()

    blocks = {"z": [], "l": [], "q": [], "s": []}
    # variable bounds as non-negative rows (their duals are not reported)
    for var in problem.variables.values():
        bc = var.bound_constraint
        if bc:
            G, h = gh(bc.le0)
            blocks["l"].append((None, -G, -h, G.shape[0]))
    for con in problem.constraints.values():
        if isinstance(con, DummyConstraint):
            continue
        if isinstance(con, AffineConstraint):
            G, h = gh(con.le0)  # le0 = G x + h <= 0 (or == 0)
            kind = "z" if con.is_equality() else "l"
            # s = b - A x  with s = -(G x + h)  =>  A = G, b = -h
            blocks[kind].append((con, G, -h, G.shape[0]))
        elif isinstance(con, SOCConstraint):
            Gn, hn = gh(con.ne)
            Gu, hu = gh(con.ub)
            # s = (ub, ne) = b - A x
            A = sp.vstack([-Gu, -Gn]).tocsr()
            b = np.concatenate([hu, hn])
            blocks["q"].append((con, A, b, A.shape[0]))
        elif isinstance(con, LMIConstraint):
            if con.greater.complex if hasattr(con.greater, "complex") else False:
                raise SolverError("complex LMIs are not supported by the conic extraction.")
            Gg, hg = gh(con.greater)
            Gs, hs = gh(con.smaller)
            dim = con.greater.shape[0]
            T = svec_transform(dim)
            A = -(T @ (Gg - Gs)).tocsr()
            b = T @ (hg - hs)
            blocks["s"].append((con, A, b, dim))
        else:
            raise SolverError(
                f"constraint type {type(con).__name__} is not supported by the conic layer."
            )
    As, bs, cones, con_rows = [], [], [], {}
    row = 0
    for kind in ("z", "l", "q", "s"):
        for con, A, b, dim in blocks[kind]:
            As.append(A)
            bs.append(b)
            size = A.shape[0]
            if kind in ("z", "l") and cones and cones[-1][0] == kind:
                cones[-1] = (kind, cones[-1][1] + size)
            else:
                cones.append((kind, dim))
            if con is not None:
                con_rows[con] = (kind, row, row + size)
            row += size
    A = sp.vstack(As).tocsc() if As else sp.csc_matrix((0, n))
    b = np.concatenate(bs) if bs else np.zeros(0)
    direction, obj = problem.no
    c, c0 = gh(obj)
    c = np.asarray(c.todense()).ravel()
    sign = 1.0 if direction == "min" else -1.0
    return ConicData(sign * c, sign * float(c0[0]), direction, A, b, cones, offsets, con_rows)


# ---------------------------------------------------------------------------------------
# verified bound
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class VerifiedBound:
    """Rigorous lower bound of ``min q'x + q0`` (see :func:`verified_lower_bound`).

    Attributes
    ----------
    bound : float
        ``-inf`` if nothing could be certified.
    dual_value : float
        ``-b'z + q0`` (uncorrected).
    psd_correction, cone_correction, residual_correction, rounding : float
        The non-negative amounts subtracted (``inf`` if not finite).
    """

    bound: float
    dual_value: float
    psd_correction: float
    cone_correction: float
    residual_correction: float
    rounding: float


def slack_upper_bounds(data: ConicData, xub: np.ndarray) -> np.ndarray:
    """``|s_i| <= |b_i| + |A_i| xub`` for every row (shape ``(m,)``)."""
    return np.abs(data.b) + abs(data.A) @ xub


def verified_lower_bound(
    data: ConicData, q: np.ndarray, z: np.ndarray, xub: np.ndarray, q0: float = 0.0,
    sub: np.ndarray | None = None,
) -> VerifiedBound:
    """Rigorous lower bound of ``min q'x + q0`` over ``{x : A x + s = b, s in K, |x| <= xub}``.

    Parameters
    ----------
    data : ConicData
        Constraints ``A`` (m x n), ``b`` (m,), ``cones``.
    q : ndarray, shape (n,)
    z : ndarray, shape (m,)
        Any (approximate) dual vector; it need not be feasible.
    xub : ndarray, shape (n,)
        A priori bounds ``|x_i| <= xub_i`` valid for every point of interest.
    q0 : float
    sub : ndarray, shape (m,), optional
        Bounds ``|s_i| <= sub_i`` on the slacks; default :func:`slack_upper_bounds`.

    Returns
    -------
    VerifiedBound
    """
    z = np.asarray(z, dtype=float)
    q = np.asarray(q, dtype=float)
    xub = np.asarray(xub, dtype=float)
    if z.shape != (data.m,) or not np.all(np.isfinite(z)):
        return VerifiedBound(-np.inf, np.nan, np.inf, np.inf, np.inf, np.inf)
    if sub is None:
        sub = slack_upper_bounds(data, xub)
    At = data.A.T.tocsr()
    r = q + At @ z
    absA = abs(At)
    r_mag = np.abs(q) + absA @ np.abs(z)
    kmax = int(np.max(np.diff(At.indptr))) if At.shape[0] else 0
    gam = 2.0 * (kmax + 3) * EPS
    r_abs = np.abs(r) + gam * r_mag  # rigorous upper bound of |exact r| (up to 2nd order)
    res_corr = float(r_abs @ xub)
    dual_terms = -data.b * z
    dual_value = float(np.sum(dual_terms))
    psd_corr = 0.0
    cone_corr = 0.0
    for kind, dim, sl in data.cone_slices():
        zk = z[sl]
        if kind == "l":
            cone_corr += float(np.maximum(-zk, 0.0) @ sub[sl])
        elif kind == "q":
            viol = max(0.0, float(np.linalg.norm(zk[1:])) * (1 + 4 * dim * EPS) - zk[0])
            cone_corr += viol * float(sub[sl][0])
        elif kind == "s":
            Z = smat(zk, dim)
            lam = float(np.linalg.eigvalsh(Z)[0])
            err = 8.0 * dim * EPS * float(np.linalg.norm(Z)) + 1e-300
            lam_lo = lam - err
            if lam_lo < 0:
                # trace(S) = sum of diagonal svec entries of s
                idx = np.cumsum(np.arange(1, dim + 1)) - 1  # diagonal positions in svec
                tr_ub = float(np.sum(sub[sl][idx]))
                psd_corr += -lam_lo * tr_ub
    n_terms = data.m + data.n
    rounding = 4.0 * (n_terms + 2) * EPS * (
        float(np.sum(np.abs(dual_terms))) + abs(q0) + res_corr + psd_corr + cone_corr
    ) + 1e-300
    total = dual_value + q0 - psd_corr - cone_corr - res_corr - rounding
    if not np.isfinite(total):
        total = -np.inf
    return VerifiedBound(total, dual_value + q0, psd_corr, cone_corr, res_corr, rounding)


def repair_dual(data: ConicData, q: np.ndarray, z: np.ndarray, iter_lim: int = 5000) -> np.ndarray:
    """``z + dz`` with ``dz`` the least-squares solution of ``A' dz = -(q + A' z)`` (LSQR).

    An interior-point dual that stopped early leaves a residual ``r = q + A' z`` that
    :func:`verified_lower_bound` charges as ``sum |r_i| xub_i``. Moving ``z`` to cancel
    ``r`` trades that charge for (usually smaller) cone violations, which the bound charges
    too: the result is just another dual vector, so its bound is as rigorous as the
    original's and the caller keeps the better of the two.
    """
    from scipy.sparse.linalg import lsqr

    z = np.asarray(z, dtype=float)
    At = data.A.T.tocsr()
    r = np.asarray(q, dtype=float) + At @ z
    dz = lsqr(At, -r, atol=1e-15, btol=1e-15, iter_lim=iter_lim)[0]
    return z + dz


#: Margins (on the entries of nonnegative blocks and the eigenvalues of PSD blocks) of the
#: projections :func:`best_certificate` tries, and its rounds per margin. Measured on the
#: order-2 relaxation of the chapter example at N = 300 (a1 upper, Clarabel "AlmostSolved"):
#: the repaired dual lost 1.17e-3 of the exact width, three rounds at margin 0 7.4e-4, at
#: 1e-9 6.1e-4, two at 1e-8 5.4e-4; 1e-7 moved the dual value itself (4.5e-3).
PROJECTION_MARGINS = (0.0, 1e-9, 1e-8)
PROJECTION_ROUNDS = 3


def project_dual(data: ConicData, z: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """``z`` with its nonnegative and PSD blocks moved into their cones: entries, and
    eigenvalues, raised to at least ``margin`` (free and second-order rows unchanged)."""
    z = np.array(z, dtype=float)
    for kind, dim, sl in data.cone_slices():
        if kind == "l":
            z[sl] = np.maximum(z[sl], margin)
        elif kind == "s":
            lam, V = np.linalg.eigh(smat(z[sl], dim))
            if lam[0] < margin:
                X = (V * np.maximum(lam, margin)) @ V.T
                z[sl] = svec_transform(dim) @ X.ravel(order="F")
    return z


def best_certificate(data: ConicData, q: np.ndarray, z: np.ndarray, xub: np.ndarray,
                     q0: float = 0.0) -> VerifiedBound:
    """The best :func:`verified_lower_bound` over several dual vectors made from ``z``:
    ``z`` itself, its least-squares repair (:func:`repair_dual`), and alternating
    projections (:func:`project_dual` at each of :data:`PROJECTION_MARGINS`, then the
    repair, up to :data:`PROJECTION_ROUNDS` times). A dual that an interior-point method
    left inaccurate pays for its residual or for its cone violations; alternating trades
    one for the other down to both small. Every candidate is just another dual vector, so
    the bound kept is as rigorous as each."""
    best = verified_lower_bound(data, q, z, xub, q0)
    if not np.all(np.isfinite(np.asarray(z, dtype=float))):
        return best

    def keep(zz):
        nonlocal best
        vb = verified_lower_bound(data, q, zz, xub, q0)
        if vb.bound > best.bound:
            best = vb
        return zz

    try:  # each candidate is certified as soon as it is made: a later failure keeps it
        zr = keep(repair_dual(data, q, z))
        for margin in PROJECTION_MARGINS:
            zz = zr
            for _ in range(PROJECTION_ROUNDS):
                zz = keep(repair_dual(data, q, project_dual(data, zz, margin)))
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        pass
    return best
