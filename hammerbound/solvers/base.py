"""The interface every conic backend implements (:class:`Backend`)."""

from __future__ import annotations

import importlib

from .conic import ConicData


class Backend:
    """A conic solver usable by the relaxations.

    A backend validates its native options (:meth:`check_options`) and returns, for one
    :class:`~hammerbound.solvers.conic.ConicData`, an object whose
    ``solve(q, q0) -> ConicSolution`` minimises ``q'x + q0`` over it (:meth:`conic`),
    re-used across the objectives of one relaxation. Backends are small picklable objects:
    worker processes receive them as they are, without looking the solver up again.

    Attributes
    ----------
    name : str
        Registry name (``"clarabel"``, ``"cvxopt"`` ...).
    module : str
        Python module whose import makes the backend usable.
    """

    name = "?"
    module = ""

    def available(self) -> bool:
        """Whether the backend's Python package can be imported (and, where a solver
        needs one, a licence is there)."""
        try:
            importlib.import_module(self.module)
        except ImportError:
            return False
        return True

    def check_options(self, options: dict | None) -> dict:
        """Validated copy of the native options; :class:`SolverOptionError` for bad ones."""
        return dict(options or {})

    def conic(self, data: ConicData, options: dict | None = None):
        """An object with ``solve(q, q0) -> ConicSolution`` for ``data``."""
        raise NotImplementedError

    def __eq__(self, other):
        return type(other) is type(self) and other.name == self.name

    def __hash__(self):
        return hash((type(self).__name__, self.name))

    def __repr__(self):
        return f"<hammerbound solver backend {self.name!r}>"
