"""Result objects shared by every stage-2 bounding method."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class BoundInfo:
    """How one end of one parameter interval was obtained.

    Attributes
    ----------
    param : str
        Parameter name (``"a1"``, ``"b2"`` ...).
    sense : {"min", "max"}
    bound : float
        The *guaranteed* bound reported to the user (a lower bound of the true minimum
        for ``"min"``, an upper bound of the true maximum for ``"max"``).
    solver_value : float
        The solver's own objective value (not guaranteed), NaN if none.
    status : str
        Normalised status: ``"optimal"``, ``"inaccurate"`` (bound repaired from the dual),
        ``"limit"`` (time/node/iteration limit, outer bound still valid),
        ``"infeasible"``.
    certified : bool
        True when ``bound`` is backed by a rigorous certificate (dual bound with a
        rounding/infeasibility correction).
    time : float
        Wall time in seconds.
    iterations : int or None
    gap : float or None
        For the exact method: ``|bound - best verified feasible value|``.
    witness : ndarray or None
        For the exact method: a verified-feasible theta attaining the inner value.
    nodes : int or None
    message : str
    """

    param: str
    sense: str
    bound: float
    solver_value: float = float("nan")
    status: str = "optimal"
    certified: bool = True
    time: float = 0.0
    iterations: int | None = None
    gap: float | None = None
    witness: np.ndarray | None = None
    nodes: int | None = None
    message: str = ""
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True)
class IntervalResult:
    """Parameter uncertainty intervals (22.35) from one method.

    ``bounds`` has shape ``(p, 2)`` (columns: lower, upper); ``infos`` holds ``2 p``
    :class:`BoundInfo` in the order (p0 min, p0 max, p1 min, ...).
    """

    bounds: np.ndarray
    infos: tuple
    method: str
    param_names: tuple
    time: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def center(self) -> np.ndarray:
        return self.bounds.mean(axis=1)

    @property
    def radius(self) -> np.ndarray:
        return 0.5 * (self.bounds[:, 1] - self.bounds[:, 0])

    @property
    def width(self) -> np.ndarray:
        return self.bounds[:, 1] - self.bounds[:, 0]

    def contains(self, theta, tol: float = 0.0) -> bool:
        """Whether ``theta`` lies in every interval (a NaN entry raises DataValidationError)."""
        from ..data.validation import as_theta

        theta = as_theta(theta, self.bounds.shape[0], self.param_names)
        return bool(np.all(theta >= self.bounds[:, 0] - tol) and np.all(theta <= self.bounds[:, 1] + tol))
