"""The solver layer: one module per solver, statuses as constants, one registry.

LPs (the polytopic bounds, the exact method's node and witness LPs) are solved by HiGHS
(:mod:`.highs`, with :mod:`.safe_lp` for the certified bounds and infeasibility and
:mod:`.highs_process` for quiet instances and the time limits of their runs). The convex relaxations
are *formulated* in PICOS and solved on the conic data extracted once from them
(:mod:`.conic`), re-used across many objectives, by a conic backend:

* ``"clarabel"`` (:mod:`.clarabel`; the default, a dependency): Clarabel's own API;
* ``"cvxopt"`` (:mod:`.cvxopt`; a dependency of PICOS): ``cvxopt.solvers.conelp``;
* ``"qics"`` (``pip install qics``) and ``"mosek"`` (MOSEK with a licence):
  PICOS' own solve on the same data (:class:`~.picos_generic.PicosConic`).

:func:`available_solvers` is computed once per process (an import and, for MOSEK, a licence
check); :func:`get_solver` refuses an unknown or unavailable name with
:class:`~hammerbound.exceptions.SolverNotAvailableError` naming the available ones. Every
backend's statuses are constants of :mod:`hammerbound.status`. SMCP (which PICOS also
reaches) is not listed: measured, PICOS' SMCP interface raised on 3 of 4 objectives of a
small order-1 relaxation. Solver output is never trusted as a bound: see
:func:`~hammerbound.solvers.conic.verified_lower_bound`.
"""

from __future__ import annotations

from functools import lru_cache

from ..exceptions import SolverNotAvailableError
from .base import Backend
from .clarabel import CLARABEL_STATUS, ClarabelBackend, ClarabelConic
from .conic import ConicData, ConicSolution, extract_conic_data, verified_lower_bound
from .cvxopt import CVXOPT_STATUS, CvxoptBackend
from .picos_generic import PICOS_STATUS, PicosBackend

#: Every backend hammerbound knows, in order of preference (``"clarabel"``, the default,
#: first). Which of them this machine has: :func:`available_solvers`.
BACKENDS = {
    "clarabel": ClarabelBackend(),
    "cvxopt": CvxoptBackend(),
    "qics": PicosBackend("qics", "qics"),
    "mosek": PicosBackend("mosek", "mosek", licensed=True),
}

#: native status -> status constant, per backend (``"picos"``: the PICOS-solved ones).
STATUS_MAP = {"clarabel": CLARABEL_STATUS, "cvxopt": CVXOPT_STATUS, "picos": PICOS_STATUS}


def normalise_status(backend: str, native: str) -> str:
    """The status constant of a native status word of ``backend`` (FAILED if unknown)."""
    table = STATUS_MAP.get(backend, PICOS_STATUS if backend in BACKENDS else {})
    return table.get(str(native), "failed")


@lru_cache(maxsize=1)
def _available() -> tuple[str, ...]:
    return tuple(name for name, b in BACKENDS.items() if b.available())


def available_solvers() -> list[str]:
    """Names of the conic backends usable on this machine (``"clarabel"`` first).

    Computed once per process: installing a solver later needs a new interpreter.
    """
    return list(_available())


def get_solver(name: str | Backend | None = "clarabel") -> Backend:
    """The backend ``name`` (a backend passes through; ``None``: the default, Clarabel).

    Raises
    ------
    SolverNotAvailableError
        For an unknown name or a backend not installed/licensed here; the message lists
        the available ones.
    """
    if isinstance(name, Backend):
        return name
    key = "clarabel" if name is None else str(name).lower().strip()
    avail = available_solvers()
    if key not in BACKENDS:
        raise SolverNotAvailableError(
            f"unknown solver {name!r}; available solvers here: {', '.join(avail)} (known: "
            f"{', '.join(BACKENDS)}).")
    if key not in avail:
        raise SolverNotAvailableError(
            f"solver {name!r} is not installed or not licensed here; available solvers: "
            f"{', '.join(avail)} ('pip install {BACKENDS[key].module}' adds it"
            + (", with a MOSEK licence" if key == "mosek" else "") + ").")
    return BACKENDS[key]


__all__ = [
    "BACKENDS",
    "STATUS_MAP",
    "Backend",
    "ConicData",
    "ConicSolution",
    "ClarabelConic",
    "available_solvers",
    "extract_conic_data",
    "get_solver",
    "normalise_status",
    "verified_lower_bound",
]
