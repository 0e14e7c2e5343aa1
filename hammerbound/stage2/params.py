"""Validation of the constructor parameters of :class:`~hammerbound.LinearEIVSetEstimator`
(scikit-learn convention: at ``fit``, not in ``__init__``)."""

from __future__ import annotations

import numbers

import numpy as np

from .._compat import is_given, warn_renamed
from ..data.validation import as_real
from ..exceptions import ParameterValidationError
from ..relaxations.exact.limits import check_limits
from ..relaxations.moment.size import check_work

__all__ = ["METHODS", "check_params"]

METHODS = ("moment", "lp", "exact")


def check_params(est) -> None:
    """Validate the constructor parameters of a :class:`LinearEIVSetEstimator` (at fit)."""
    for name in ("na", "nb"):
        v = getattr(est, name)
        if not isinstance(v, numbers.Integral) or isinstance(v, bool) or v < 0:
            raise ParameterValidationError(f"{name} must be an integer >= 0; got {v!r}.")
    nk = est.nk
    if nk is not None and (not isinstance(nk, numbers.Integral) or isinstance(nk, bool)
                           or nk < 0):
        raise ParameterValidationError(
            f"nk (input delay) must be an integer >= 0; got {nk!r}.")
    if is_given(est.b0):
        warn_renamed("LinearEIVSetEstimator(b0=...)", "nk=0 (direct term b0) or nk=1",
                     stacklevel=4)
        if not isinstance(est.b0, (bool, np.bool_)):
            raise ParameterValidationError(
                f"b0 must be True or False (better: nk=0 for a direct term); got "
                f"{est.b0!r}.")
        if est.b0 and nk not in (None, 0, 1):
            raise ParameterValidationError(
                f"b0=True means a direct term (nk=0) but nk={nk}: pass only nk.")
    check_limits(est.tol, est.max_nodes, est.time_limit, est.total_time_limit)
    if est.nb == 0 and est._nk() != 0:
        raise ParameterValidationError(
            "B has no coefficient: use nb >= 1 or nk=0 (the direct term b0)."
        )
    if est.method not in METHODS:
        raise ParameterValidationError(
            f"method must be one of {METHODS}; got {est.method!r}."
        )
    r = est.relaxation_order
    if not isinstance(r, numbers.Integral) or isinstance(r, bool) or r < 1:
        raise ParameterValidationError(
            f"relaxation_order must be an integer >= 1 (the chapter uses 2); got {r!r}."
        )
    if est.on_failure not in ("box", "raise"):
        raise ParameterValidationError(
            f"on_failure must be 'box' or 'raise'; got {est.on_failure!r}."
        )
    if est.relaxation_basis not in ("sparse", "full"):
        raise ParameterValidationError(
            f"relaxation_basis must be 'sparse' or 'full'; got {est.relaxation_basis!r}."
        )
    check_work("relaxation_max_work", est.relaxation_max_work)
    as_real("steady_state_gain", est.steady_state_gain, nonzero=True, or_none=True,
            example="1.0")
    if not (isinstance(est.n_jobs, numbers.Integral) and (est.n_jobs >= 1 or est.n_jobs == -1)):
        raise ParameterValidationError(f"n_jobs must be a positive integer or -1; got {est.n_jobs!r}.")
    if est.solver_options is not None and not isinstance(est.solver_options, dict):
        from ..exceptions import SolverOptionError

        raise SolverOptionError(
            f"solver_options must be a dict of native solver options or None; got "
            f"{type(est.solver_options).__name__}."
        )
    if est.method == "moment":
        # an unknown or unavailable backend (and bad options) are refused before any work,
        # naming the available backends (not in __init__: scikit-learn estimators validate
        # in fit, and set_params bypasses __init__)
        from ..solvers import get_solver

        get_solver(est.solver).check_options(est.solver_options)
