"""Clarabel on :class:`~hammerbound.solvers.conic.ConicData` (the default conic backend).

PSD constraints are passed as Clarabel ``PSDTriangleConeT`` blocks: the upper triangle,
column by column, off-diagonal entries scaled by ``sqrt(2)`` (the ``svec`` of
:mod:`hammerbound.solvers.conic`), so Clarabel's dual ``z`` is the conic form's dual vector
as it is. :class:`ClarabelConic` analyses the KKT structure once and re-solves for many
objectives.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ..exceptions import SolverOptionError
from ..status import FAILED, INACCURATE, INFEASIBLE, LIMIT, OPTIMAL
from .base import Backend
from .conic import ConicData, ConicSolution

#: Clarabel native status -> status constant.
CLARABEL_STATUS = {
    "Solved": OPTIMAL,
    "AlmostSolved": INACCURATE,
    "PrimalInfeasible": INFEASIBLE,
    "AlmostPrimalInfeasible": INACCURATE,
    "DualInfeasible": FAILED,
    "AlmostDualInfeasible": FAILED,
    "MaxIterations": LIMIT,
    "MaxTime": LIMIT,
    "CallbackTerminated": LIMIT,
    "NumericalError": FAILED,
    "InsufficientProgress": FAILED,
    "Unsolved": FAILED,
}


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

    make = {"z": clarabel.ZeroConeT, "l": clarabel.NonnegativeConeT,
            "q": clarabel.SecondOrderConeT, "s": clarabel.PSDTriangleConeT}
    return [make[kind](dim) for kind, dim in cones]


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
        return ConicSolution(
            CLARABEL_STATUS.get(native, FAILED), native, np.asarray(sol.x, dtype=float),
            np.asarray(sol.z, dtype=float), float(sol.obj_val) + q0,
            float(sol.obj_val_dual) + q0, int(sol.iterations), dt,
        )


class ClarabelBackend(Backend):
    """Clarabel (interior point, Rust; a dependency of hammerbound: always available)."""

    name = "clarabel"
    module = "clarabel"

    def check_options(self, options):
        opts = dict(options or {})
        clarabel_settings(opts)
        return opts

    def conic(self, data, options=None):
        return ClarabelConic(data, self.check_options(options))
