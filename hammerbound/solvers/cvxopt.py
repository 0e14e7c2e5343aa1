"""CVXOPT's ``conelp`` on :class:`~hammerbound.solvers.conic.ConicData`.

CVXOPT stores PSD blocks as full column-major matrices: the ``svec`` rows are expanded with
``smat_transform`` and the dual is folded back to ``svec`` for the certificate.
"""

from __future__ import annotations

import time

import numpy as np

from ..exceptions import SolverOptionError
from ..status import FAILED, INACCURATE, INFEASIBLE, OPTIMAL
from .base import Backend
from .conic import ConicData, ConicSolution, smat_transform

#: CVXOPT native status -> status constant.
CVXOPT_STATUS = {
    "optimal": OPTIMAL,
    "unknown": INACCURATE,
    "primal infeasible": INFEASIBLE,
    "dual infeasible": FAILED,
}

_CVXOPT_OPTIONS = {"maxiters", "abstol", "reltol", "feastol", "refinement", "show_progress"}


class _CvxoptConic:
    """``cvxopt.solvers.conelp`` on :class:`ConicData` (PSD blocks expanded to full)."""

    def __init__(self, data: ConicData, options: dict):
        import cvxopt
        import scipy.sparse as sp

        self.data = data
        self.options = options
        rows_eq, G_parts, h_parts, self.dims = [], [], [], {"l": 0, "q": [], "s": []}
        self._blocks = []
        for kind, dim, sl in data.cone_slices():
            A = data.A[sl]
            b = data.b[sl]
            if kind == "z":
                rows_eq.append((A, b))
                continue
            if kind == "s":
                E = smat_transform(dim)
                A = E @ A
                b = E @ b
                self.dims["s"].append(dim)
            elif kind == "q":
                self.dims["q"].append(dim)
            else:
                self.dims["l"] += dim
            G_parts.append(A)
            h_parts.append(b)
            self._blocks.append((kind, dim, sl))

        def to_cvx(M):
            M = sp.coo_matrix(M)
            return cvxopt.spmatrix(M.data.tolist(), M.row.tolist(), M.col.tolist(), M.shape)

        n = data.n
        if rows_eq:
            Aeq = sp.vstack([a for a, _ in rows_eq])
            beq = np.concatenate([b for _, b in rows_eq])
        else:
            Aeq, beq = sp.csr_matrix((0, n)), np.zeros(0)
        G = sp.vstack(G_parts) if G_parts else sp.csr_matrix((0, n))
        h = np.concatenate(h_parts) if h_parts else np.zeros(0)
        self._G, self._h = to_cvx(G), cvxopt.matrix(h)
        self._A, self._b = to_cvx(Aeq), cvxopt.matrix(beq)
        self._neq = beq.size

    def solve(self, q=None, q0=0.0) -> ConicSolution:
        import cvxopt

        data = self.data
        q = data.q if q is None else np.asarray(q, dtype=float)
        old = dict(cvxopt.solvers.options)
        cvxopt.solvers.options.clear()
        cvxopt.solvers.options["show_progress"] = False
        cvxopt.solvers.options.update(self.options)
        t0 = time.perf_counter()
        try:
            kw = {"A": self._A, "b": self._b} if self._neq else {}
            res = cvxopt.solvers.conelp(cvxopt.matrix(q), self._G, self._h, self.dims, **kw)
        except (ValueError, ArithmeticError) as exc:
            return ConicSolution(FAILED, str(exc), None, None, np.nan, np.nan, None,
                                 time.perf_counter() - t0)
        finally:
            cvxopt.solvers.options.clear()
            cvxopt.solvers.options.update(old)
        dt = time.perf_counter() - t0
        native = res["status"]
        z = np.zeros(data.m)
        zc = np.asarray(res["z"]).ravel() if res["z"] is not None else None
        yc = np.asarray(res["y"]).ravel() if res["y"] is not None else None
        if zc is None:
            z = None
        else:
            pos = 0
            eq_pos = 0
            for kind, dim, sl in data.cone_slices():
                if kind == "z":
                    z[sl] = yc[eq_pos : eq_pos + dim] if yc is not None else 0.0
                    eq_pos += dim
                elif kind == "s":
                    Zf = zc[pos : pos + dim * dim].reshape(dim, dim, order="F")
                    Zl = np.tril(Zf)
                    Zs = Zl + np.tril(Zf, -1).T
                    iu_r, iu_c = np.triu_indices(dim)
                    order = np.lexsort((iu_r, iu_c))
                    r, c = iu_r[order], iu_c[order]
                    z[sl] = np.where(r == c, Zs[r, c], np.sqrt(2.0) * Zs[r, c])
                    pos += dim * dim
                else:
                    z[sl] = zc[pos : pos + (sl.stop - sl.start)]
                    pos += sl.stop - sl.start
        x = np.asarray(res["x"]).ravel() if res["x"] is not None else None
        pv = res.get("primal objective")
        dv = res.get("dual objective")
        return ConicSolution(
            CVXOPT_STATUS.get(native, FAILED), native, x, z,
            (pv + q0) if pv is not None else np.nan, (dv + q0) if dv is not None else np.nan,
            int(res.get("iterations", 0) or 0), dt,
        )


class CvxoptBackend(Backend):
    """CVXOPT's ``conelp`` (pure Python/C, no licence)."""

    name = "cvxopt"
    module = "cvxopt"

    def check_options(self, options):
        opts = dict(options or {})
        bad = set(opts) - _CVXOPT_OPTIONS
        if bad:
            raise SolverOptionError(
                f"unknown CVXOPT option(s) {sorted(bad)}; valid: {sorted(_CVXOPT_OPTIONS)}."
            )
        for k, v in opts.items():
            if k in ("maxiters", "refinement") and not isinstance(v, (int, np.integer)):
                raise SolverOptionError(f"CVXOPT option {k!r} must be an int; got {v!r}.")
            if k in ("abstol", "reltol", "feastol") and not isinstance(v, (int, float)):
                raise SolverOptionError(f"CVXOPT option {k!r} must be a number; got {v!r}.")
        return opts

    def conic(self, data, options=None):
        return _CvxoptConic(data, self.check_options(options))
