"""Any conic solver PICOS knows (QICS, SMCP, MOSEK ...) on :class:`ConicData`.

The relaxations hand every backend the same :class:`~hammerbound.solvers.conic.ConicData`
(``min q'x + q0``, ``A x + s = b``, ``s`` in a product of zero, non-negative, second-order
and PSD cones). :class:`PicosConic` rebuilds that problem in PICOS once (one variable
``x``; one constraint per cone block: ``A x == b``, ``A x <= b``, ``|s_rest| <= s_0`` or
``smat(b - A x) >> 0``), solves it with ``picos.Problem.solve(solver=name)`` for each
objective and maps PICOS' duals back to the dual vector ``z`` of the conic form, which
:func:`~hammerbound.solvers.conic.verified_lower_bound` certifies. A dual in a convention
other than the expected one only weakens the certificate, never makes a bound wrong.
"""

from __future__ import annotations

import contextlib
import io
import re
import time

import numpy as np
import scipy.sparse as sp

from ..exceptions import SolverOptionError
from ..status import FAILED, INACCURATE, INFEASIBLE, LIMIT, OPTIMAL
from .base import Backend
from .conic import ConicData, ConicSolution, smat_transform, svec_transform

#: PICOS solution status (``claimedStatus`` / ``primalStatus``) -> status constant.
PICOS_STATUS = {
    "optimal": OPTIMAL,
    "feasible": INACCURATE,
    "premature": LIMIT,
    "infeasible": INFEASIBLE,
    "unbounded": FAILED,
    "failure": FAILED,
    "unknown": FAILED,
}

#: PICOS options a caller may pass through ``solver_options`` (``picos.Options`` names).
PICOS_OPTIONS = {"max_iterations", "abs_ipm_opt_tol", "rel_ipm_opt_tol", "rel_prim_fsb_tol",
                 "rel_dual_fsb_tol", "abs_prim_fsb_tol", "abs_dual_fsb_tol", "timelimit",
                 "mosek_params", "qics_params"}


def check_picos_options(solver: str, options: dict | None) -> dict:
    """Validated copy of ``options`` (names of :data:`PICOS_OPTIONS`, numeric tolerances)."""
    opts = dict(options or {})
    bad = set(opts) - PICOS_OPTIONS
    if bad:
        raise SolverOptionError(f"unknown {solver} option(s) {sorted(bad)} (passed to PICOS); "
                                f"valid: {sorted(PICOS_OPTIONS)}.")
    for k, v in opts.items():
        if k.endswith("_params"):
            if not isinstance(v, dict):
                raise SolverOptionError(f"{solver} option {k!r} must be a dict; got {v!r}.")
        elif k == "max_iterations":
            if not isinstance(v, (int, np.integer)) or v < 1:
                raise SolverOptionError(f"{solver} option {k!r} must be an int >= 1; got {v!r}.")
        elif not isinstance(v, (int, float)) or isinstance(v, bool) or not v > 0:
            raise SolverOptionError(f"{solver} option {k!r} must be a number > 0; got {v!r}.")
    return opts


class PicosConic:
    """``data`` as a PICOS problem solved by PICOS' ``solver`` for many objectives."""

    def __init__(self, data: ConicData, solver: str, options: dict | None = None):
        import picos

        self.data = data
        self.solver = solver
        self.options = check_picos_options(solver, options)
        P = picos.Problem()
        x = picos.RealVariable("x", data.n)
        self._cons = []
        A = sp.csr_matrix(data.A)
        for kind, dim, sl in data.cone_slices():
            Ak, bk = A[sl], data.b[sl]
            Ax = picos.Constant(Ak) * x
            if kind == "z":
                con = P.add_constraint(Ax == picos.Constant(bk))
            elif kind == "l":
                con = P.add_constraint(Ax <= picos.Constant(bk))
            elif kind == "q":
                s = picos.Constant(bk) - Ax
                con = P.add_constraint(abs(s[1:]) <= s[0])
            else:  # smat(b - A x) >> 0, vec column-major
                E = smat_transform(dim)
                S = (picos.Constant(E @ bk) - picos.Constant(E @ Ak) * x).reshaped((dim, dim))
                con = P.add_constraint(S.hermitianized >> 0)
            self._cons.append((kind, dim, sl, con))
        self._P, self._x = P, x

    def _dual_vector(self) -> np.ndarray | None:
        z = np.zeros(self.data.m)
        for kind, dim, sl, con in self._cons:
            d = con.dual
            if d is None:
                return None
            if type(d).__name__ == "spmatrix":  # a sparse CVXOPT dual (e.g. from SMCP)
                import cvxopt

                d = cvxopt.matrix(d)
            d = np.array(d, dtype=float)
            if kind == "z":
                z[sl] = -d.ravel()  # PICOS' equality dual has the opposite sign
            elif kind in ("l", "q"):
                z[sl] = d.ravel()
            else:
                z[sl] = svec_transform(dim) @ d.reshape(dim, dim).ravel(order="F")
        return z

    def solve(self, q=None, q0: float = 0.0) -> ConicSolution:
        """Minimise ``q'x + q0`` over the constraints of the data."""
        import picos

        q = self.data.q if q is None else np.asarray(q, dtype=float)
        self._P.set_objective("min", picos.Constant(q.reshape(1, -1)) * self._x)
        t0 = time.perf_counter()
        chatter = io.StringIO()  # stdout belongs to the program (SMCP prints from Python)
        try:
            with contextlib.redirect_stdout(chatter):
                sol = self._P.solve(solver=self.solver, primals=None, duals=None,
                                    **self.options)
        except (picos.SolutionFailure, ArithmeticError, ValueError) as exc:
            return ConicSolution(FAILED, str(exc), None, None, np.nan, np.nan, None,
                                 time.perf_counter() - t0)
        dt = time.perf_counter() - t0
        native = claimed = str(sol.claimedStatus)
        said = re.sub(r"\x1b\[[0-9;]*m", "", chatter.getvalue()).strip()
        if said:
            native += f" ({self.solver} said: {' / '.join(said.splitlines())[:120]})"
        status = PICOS_STATUS.get(str(sol.primalStatus), FAILED)
        if status == OPTIMAL and claimed != "optimal":
            status = INACCURATE
        x = np.asarray(self._x.value, dtype=float).ravel() if self._x.value is not None \
            else None
        z = self._dual_vector()
        pv = float(q @ x) + q0 if x is not None else np.nan
        dv = float(-self.data.b @ z) + q0 if z is not None else np.nan
        return ConicSolution(status, native, x, z, pv, dv, None, dt)


class PicosBackend(Backend):
    """A conic solver reached through PICOS' own ``solve(solver=name)`` (:class:`PicosConic`).

    ``solver_options`` are PICOS options (:data:`PICOS_OPTIONS`, e.g.
    ``{"rel_ipm_opt_tol": 1e-9}``, or the solver's native ones as ``{"qics_params": {...}}``).
    """

    def __init__(self, name: str, module: str, licensed: bool = False):
        self.name = name
        self.module = module
        self.licensed = licensed

    def available(self) -> bool:
        if not super().available():
            return False
        import picos

        if self.name not in picos.available_solvers():
            return False
        if self.licensed:  # e.g. MOSEK: installed is not enough
            try:
                import mosek

                mosek.Env().checkoutlicense(mosek.feature.pts)
            except Exception:  # noqa: BLE001 - any failure means "not usable"
                return False
        return True

    def check_options(self, options):
        return check_picos_options(self.name, options)

    def conic(self, data, options=None):
        return PicosConic(data, self.name, self.check_options(options))
