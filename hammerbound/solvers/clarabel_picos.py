"""Clarabel as a PICOS solver (PICOS 2.6 ships no Clarabel interface).

Use it through PICOS' ``ad_hoc_solver`` option::

    P.options.ad_hoc_solver = ClarabelSolver
    P.solve()

PSD constraints are passed as Clarabel ``PSDTriangleConeT`` blocks: the upper triangle,
column by column, off-diagonal entries scaled by ``sqrt(2)`` (see
:mod:`hammerbound.solvers.conic`). The low-level :func:`solve_conic_clarabel` solves a
:class:`~hammerbound.solvers.conic.ConicData` directly and is what the relaxations use to
re-solve one formulation for many objectives without rebuilding it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from picos.constraints import (
    AffineConstraint,
    DummyConstraint,
    LMIConstraint,
    SOCConstraint,
)
from picos.expressions import AffineExpression
from picos.expressions.variables import CONTINUOUS_VARTYPES
from picos.modeling.footprint import Specification
from picos.modeling.solution import (
    PS_FEASIBLE,
    PS_INFEASIBLE,
    PS_UNBOUNDED,
    PS_UNKNOWN,
    SS_FAILURE,
    SS_INFEASIBLE,
    SS_OPTIMAL,
    SS_PREMATURE,
    SS_UNKNOWN,
)
from picos.solvers.solver import Solver

from ..exceptions import SolverOptionError
from .conic import ConicData, extract_conic_data, smat

#: Clarabel native status -> hammerbound status vocabulary.
CLARABEL_STATUS = {
    "Solved": "optimal",
    "AlmostSolved": "inaccurate",
    "PrimalInfeasible": "infeasible",
    "AlmostPrimalInfeasible": "inaccurate",
    "DualInfeasible": "failed",
    "AlmostDualInfeasible": "failed",
    "MaxIterations": "limit",
    "MaxTime": "limit",
    "CallbackTerminated": "limit",
    "NumericalError": "failed",
    "InsufficientProgress": "failed",
    "Unsolved": "failed",
}


@dataclass
class ConicSolution:
    """Raw outcome of one conic solve (any backend).

    Attributes
    ----------
    status : str
        Normalised status (``"optimal"``, ``"inaccurate"``, ``"infeasible"``, ``"limit"``,
        ``"failed"``).
    native_status : str
    x : ndarray, shape (n,) or None
    z : ndarray, shape (m,) or None
        Dual vector in the convention of :mod:`hammerbound.solvers.conic`.
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


def clarabel_settings(options: dict | None = None):
    """``clarabel.DefaultSettings`` with ``verbose=False`` and the given overrides.

    Raises
    ------
    SolverOptionError
        For an unknown option name or a value of the wrong type.
    """
    import clarabel

    settings = clarabel.DefaultSettings()
    settings.verbose = False
    known = {a for a in dir(settings) if not a.startswith("_") and a != "default"}
    for key, val in (options or {}).items():
        if key not in known:
            raise SolverOptionError(
                f"unknown Clarabel option {key!r}; valid options: {', '.join(sorted(known))}."
            )
        try:
            setattr(settings, key, val)
        except (TypeError, ValueError, OverflowError) as exc:
            raise SolverOptionError(f"bad value {val!r} for Clarabel option {key!r}: {exc}") from exc
    return settings


def clarabel_cones(cones):
    """Clarabel cone objects for the ``cones`` list of :class:`ConicData`."""
    import clarabel

    out = []
    for kind, dim in cones:
        if kind == "z":
            out.append(clarabel.ZeroConeT(dim))
        elif kind == "l":
            out.append(clarabel.NonnegativeConeT(dim))
        elif kind == "q":
            out.append(clarabel.SecondOrderConeT(dim))
        elif kind == "s":
            out.append(clarabel.PSDTriangleConeT(dim))
        else:  # pragma: no cover - extraction only produces the kinds above
            raise ValueError(f"unknown cone kind {kind!r}")
    return out


class ClarabelConic:
    """A Clarabel solver instance for one :class:`ConicData`, re-usable across objectives.

    The KKT structure is analysed once; :meth:`solve` only updates ``q``.
    """

    def __init__(self, data: ConicData, options: dict | None = None):
        import clarabel

        self.data = data
        self.settings = clarabel_settings(options)
        P = sp.csc_matrix((data.n, data.n))
        self._solver = clarabel.DefaultSolver(
            P, np.asarray(data.q, dtype=float), data.A.tocsc(), np.asarray(data.b, dtype=float),
            clarabel_cones(data.cones), self.settings,
        )
        self._q = np.asarray(data.q, dtype=float)

    def solve(self, q: np.ndarray | None = None, q0: float = 0.0) -> ConicSolution:
        """Minimise ``q'x + q0`` over the constraints of the data."""
        if q is not None:
            q = np.asarray(q, dtype=float)
            if not np.array_equal(q, self._q):
                self._solver.update(q=q)
                self._q = q
        t0 = time.perf_counter()
        sol = self._solver.solve()
        dt = time.perf_counter() - t0
        native = str(sol.status)
        status = CLARABEL_STATUS.get(native, "failed")
        x = np.asarray(sol.x, dtype=float)
        z = np.asarray(sol.z, dtype=float)
        return ConicSolution(
            status, native, x, z, float(sol.obj_val) + q0, float(sol.obj_val_dual) + q0,
            int(sol.iterations), dt,
        )


def solve_conic_clarabel(data: ConicData, q=None, q0: float = 0.0, options=None) -> ConicSolution:
    """One-shot Clarabel solve of ``min q'x + q0`` (default objective: ``data.q``)."""
    return ClarabelConic(data, options).solve(q, q0)


class ClarabelSolver(Solver):
    """PICOS interface to Clarabel (continuous affine / SOC / real LMI problems).

    PICOS 2.6 has no ``clarabel_params`` option, so Clarabel settings live on the class:
    ``P.options.ad_hoc_solver = ClarabelSolver.with_options(max_iter=50)``. The generic
    PICOS options (``max_iterations``, ``rel_ipm_opt_tol``, ``timelimit`` ...) are mapped.
    """

    SUPPORTED = Specification(
        objectives=[AffineExpression],
        variables=CONTINUOUS_VARTYPES,
        constraints=[DummyConstraint, AffineConstraint, SOCConstraint, LMIConstraint],
    )

    #: Clarabel settings applied on every solve (see :func:`clarabel_settings`).
    options: dict = {}

    @classmethod
    def with_options(cls, **options) -> type:
        """Subclass with fixed Clarabel settings (validated now)."""
        clarabel_settings(options)
        return type("ClarabelSolverWithOptions", (cls,), {"options": dict(options)})

    @classmethod
    def supports(cls, footprint, explain=False):
        result = Solver.supports(footprint, explain)
        if not result or (explain and not result[0]):
            return result
        if footprint not in cls.SUPPORTED:
            if explain:
                return False, cls.SUPPORTED.mismatch_reason(footprint)
            return False
        return (True, None) if explain else True

    @classmethod
    def default_penalty(cls):
        return 1.0

    @classmethod
    def test_availability(cls):
        cls.check_import("clarabel")

    @classmethod
    def names(cls):
        return "clarabel", "Clarabel", "Clarabel Interior Point Conic Solver", "hammerbound"

    @classmethod
    def penalty(cls, options):
        # PICOS has no ``penalty_clarabel`` option; use the default penalty.
        return cls.default_penalty()

    @classmethod
    def is_free(cls):
        return True

    def __init__(self, problem):
        super().__init__(problem)
        self.data = None

    def reset_problem(self):
        self.int = None
        self.data = None

    def _make_solution(self, value, primals, duals, primalStatus, dualStatus, problemStatus,
                       info=None, vectorizedPrimals=True):
        # PICOS' version looks the solver up in its own registry, which an ad hoc solver
        # is not part of.
        from picos.modeling import Solution

        return Solution(
            primals=primals, duals=duals, problem=self.ext, solver=self.name,
            primalStatus=primalStatus, dualStatus=dualStatus, problemStatus=problemStatus,
            searchTime=self.timer, info=info, vectorizedPrimals=vectorizedPrimals,
            reportedValue=value,
        )

    def _import_problem(self):
        self.data = extract_conic_data(self.ext)
        self.int = self.data

    def _update_problem(self):
        raise NotImplementedError

    def _solve(self):
        opts = dict(self.options)
        o = self.ext.options
        if o.rel_prim_fsb_tol is not None or o.rel_dual_fsb_tol is not None:
            opts.setdefault(
                "tol_feas",
                min(t for t in (o.rel_prim_fsb_tol, o.rel_dual_fsb_tol) if t is not None),
            )
        if o.abs_ipm_opt_tol is not None:
            opts.setdefault("tol_gap_abs", o.abs_ipm_opt_tol)
        if o.rel_ipm_opt_tol is not None:
            opts.setdefault("tol_gap_rel", o.rel_ipm_opt_tol)
        if o.max_iterations is not None:
            opts.setdefault("max_iter", int(o.max_iterations))
        if o.timelimit is not None:
            opts.setdefault("time_limit", float(o.timelimit))
        if self.verbosity() >= 1:
            opts.setdefault("verbose", True)
        self._handle_unsupported_options(
            "lp_root_method", "lp_node_method", "treememory", "max_fsb_nodes", "hotstart"
        )
        data = self.data
        with self._header(), self._stopwatch():
            sol = ClarabelConic(data, opts).solve()
        primals, duals = {}, {}
        if self.ext.options.primals is not False:
            for var, off in data.var_offsets.items():
                primals[var] = list(sol.x[off : off + var.dim])
        if self.ext.options.duals is not False:
            import cvxopt

            for con in self.ext.constraints.values():
                if isinstance(con, DummyConstraint):
                    duals[con] = cvxopt.spmatrix([], [], [], con.size)
                    continue
                kind, a, b = data.con_rows[con]
                zk = sol.z[a:b]
                if kind == "z":
                    dual = cvxopt.matrix(-zk, con.size) if zk.size > 1 else float(-zk[0])
                elif kind == "l":
                    dual = cvxopt.matrix(zk, con.size) if zk.size > 1 else float(zk[0])
                elif kind == "q":
                    dual = cvxopt.matrix(zk)
                else:
                    dim = con.greater.shape[0]
                    dual = cvxopt.matrix(smat(zk, dim))
                duals[con] = dual
        value = None
        if np.isfinite(sol.primal_value):
            value = sol.primal_value + data.q0
            if data.sense == "max":
                value = -value
        st = sol.native_status
        if st == "Solved":
            ps, ds, prob = SS_OPTIMAL, SS_OPTIMAL, PS_FEASIBLE
        elif st == "PrimalInfeasible":
            ps, ds, prob = SS_INFEASIBLE, SS_UNKNOWN, PS_INFEASIBLE
        elif st == "DualInfeasible":
            ps, ds, prob = SS_UNKNOWN, SS_INFEASIBLE, PS_UNBOUNDED
        elif st in ("AlmostSolved", "MaxIterations", "MaxTime", "InsufficientProgress"):
            ps, ds, prob = SS_PREMATURE, SS_PREMATURE, PS_UNKNOWN
        elif st == "NumericalError":
            ps, ds, prob = SS_FAILURE, SS_FAILURE, PS_UNKNOWN
        else:
            ps, ds, prob = SS_UNKNOWN, SS_UNKNOWN, PS_UNKNOWN
        return self._make_solution(
            value, primals, duals, ps, ds, prob,
            {"clarabel_status": st, "iterations": sol.iterations},
        )
