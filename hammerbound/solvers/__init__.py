"""Solver backends for the convex relaxations.

Relaxations are *formulated* as PICOS problems; a backend either solves the PICOS problem
(:meth:`Backend.picos_solve`) or, for speed, solves the conic data extracted once from it
(:meth:`Backend.conic`, re-used across many objectives). Backends:

* ``"clarabel"`` (default): Clarabel through :class:`ClarabelSolver` (PICOS ``ad_hoc_solver``);
* ``"cvxopt"``: PICOS' built-in CVXOPT interface / ``cvxopt.solvers.conelp``;
* ``"mosek"``: PICOS' MOSEK interface, only when MOSEK is installed and licensed.

Solver output is never trusted as a bound: see :func:`~hammerbound.solvers.conic.verified_lower_bound`.
"""

from __future__ import annotations

import time

import numpy as np

from ..exceptions import SolverNotAvailableError, SolverOptionError
from .clarabel_picos import (
    CLARABEL_STATUS,
    ClarabelConic,
    ClarabelSolver,
    ConicSolution,
    clarabel_settings,
)
from .conic import ConicData, extract_conic_data, smat_transform, verified_lower_bound

CVXOPT_STATUS = {
    "optimal": "optimal",
    "unknown": "inaccurate",
    "primal infeasible": "infeasible",
    "dual infeasible": "failed",
}

MOSEK_STATUS = {
    "optimal": "optimal",
    "feasible": "inaccurate",
    "premature": "limit",
    "infeasible": "infeasible",
    "unknown": "failed",
}

#: native status -> {"optimal", "inaccurate", "infeasible", "limit", "failed"} per backend.
STATUS_MAP = {"clarabel": CLARABEL_STATUS, "cvxopt": CVXOPT_STATUS, "mosek": MOSEK_STATUS}

_CVXOPT_OPTIONS = {"maxiters", "abstol", "reltol", "feastol", "refinement", "show_progress"}


def normalise_status(backend: str, native: str) -> str:
    """Map a native status string of ``backend`` to the hammerbound vocabulary."""
    return STATUS_MAP.get(backend, {}).get(str(native), "failed")


def _forget_strategy(problem):
    """Drop PICOS' cached solution strategy (it may reference another, ad hoc, solver)."""
    if hasattr(problem, "_strategy"):
        problem._strategy = None


class Backend:
    """Common interface of a solver backend.

    Attributes
    ----------
    name : str
    """

    name = "?"
    #: Python module whose import makes the backend usable.
    module = None

    def available(self) -> bool:
        """Whether the backend's Python package can be imported."""
        import importlib

        try:
            importlib.import_module(self.module)
        except ImportError:
            return False
        return True

    def check_options(self, options: dict | None) -> dict:
        """Validate solver options; raise :class:`SolverOptionError` for unknown ones."""
        return dict(options or {})

    def picos_solve(self, problem, options: dict | None = None):
        """Solve a PICOS problem with this backend and return the PICOS solution."""
        raise NotImplementedError

    def conic(self, data: ConicData, options: dict | None = None):
        """Return an object with ``solve(q, q0) -> ConicSolution`` for ``data``."""
        raise NotImplementedError

    def __repr__(self):
        return f"<hammerbound solver backend {self.name!r}>"


class ClarabelBackend(Backend):
    name = "clarabel"
    module = "clarabel"

    def check_options(self, options):
        opts = dict(options or {})
        clarabel_settings(opts)
        return opts

    def picos_solve(self, problem, options=None):
        opts = self.check_options(options)
        _forget_strategy(problem)
        problem.options.ad_hoc_solver = ClarabelSolver.with_options(**opts)
        try:
            return problem.solve(primals=None, duals=None)
        finally:
            problem.options.ad_hoc_solver = None
            _forget_strategy(problem)

    def conic(self, data, options=None):
        return ClarabelConic(data, self.check_options(options))


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
            return ConicSolution("failed", str(exc), None, None, np.nan, np.nan, None,
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
            CVXOPT_STATUS.get(native, "failed"), native, x, z,
            (pv + q0) if pv is not None else np.nan, (dv + q0) if dv is not None else np.nan,
            int(res.get("iterations", 0) or 0), dt,
        )


class CvxoptBackend(Backend):
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

    def picos_solve(self, problem, options=None):
        import cvxopt

        opts = self.check_options(options)
        old = dict(cvxopt.solvers.options)
        _forget_strategy(problem)
        try:
            kw = {}
            if "maxiters" in opts:
                kw["max_iterations"] = opts["maxiters"]
            if "abstol" in opts:
                kw["abs_ipm_opt_tol"] = opts["abstol"]
            if "reltol" in opts:
                kw["rel_ipm_opt_tol"] = opts["reltol"]
            if "feastol" in opts:
                kw["rel_prim_fsb_tol"] = opts["feastol"]
                kw["rel_dual_fsb_tol"] = opts["feastol"]
            return problem.solve(solver="cvxopt", primals=None, duals=None, **kw)
        finally:
            cvxopt.solvers.options.clear()
            cvxopt.solvers.options.update(old)

    def conic(self, data, options=None):
        return _CvxoptConic(data, self.check_options(options))


class MosekBackend(Backend):
    name = "mosek"

    def available(self) -> bool:
        try:
            import mosek

            env = mosek.Env()
            env.checkoutlicense(mosek.feature.pts)
        except Exception:  # noqa: BLE001 - any failure means "not usable"
            return False
        return True

    def picos_solve(self, problem, options=None):
        opts = dict(options or {})
        _forget_strategy(problem)
        return problem.solve(solver="mosek", primals=None, duals=None, mosek_params=opts)

    def conic(self, data, options=None):
        raise SolverNotAvailableError(
            "the direct conic path is not implemented for MOSEK; use 'clarabel' or 'cvxopt'."
        )


_BACKENDS = {"clarabel": ClarabelBackend, "cvxopt": CvxoptBackend, "mosek": MosekBackend}


def available_solvers() -> list[str]:
    """Names of the backends usable on this machine (``"clarabel"`` first)."""
    return [name for name, cls in _BACKENDS.items() if cls().available()]


def get_solver(name: str = "clarabel") -> Backend:
    """Backend by name.

    Raises
    ------
    SolverNotAvailableError
        For an unknown name or a backend that is not installed/licensed; the message lists
        the available ones.
    """
    key = str(name).lower().strip() if name is not None else "clarabel"
    avail = available_solvers()
    if key not in _BACKENDS:
        raise SolverNotAvailableError(
            f"unknown solver {name!r}; available solvers: {', '.join(avail) or 'none'}."
        )
    backend = _BACKENDS[key]()
    if not backend.available():
        raise SolverNotAvailableError(
            f"solver {name!r} is not installed or not licensed here; available solvers: "
            f"{', '.join(avail) or 'none'}."
        )
    return backend


__all__ = [
    "STATUS_MAP",
    "Backend",
    "ClarabelSolver",
    "ConicData",
    "ConicSolution",
    "available_solvers",
    "extract_conic_data",
    "get_solver",
    "normalise_status",
    "verified_lower_bound",
]
