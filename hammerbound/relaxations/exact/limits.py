"""The stopping rules of the exact method, checked where a user can pass them: the
estimator (at fit) and :func:`~.bnb.exact_bounds` itself."""

from __future__ import annotations

import numbers

from ...data.validation import as_real
from ...exceptions import ParameterValidationError

__all__ = ["check_limits"]


def _seconds(value) -> bool:
    return (isinstance(value, numbers.Real) and not isinstance(value, bool)
            and bool(value >= 0))


def check_limits(tol, max_nodes, time_limit, total_time_limit=None) -> None:
    """``tol`` a finite number > 0, ``max_nodes`` an integer >= 0, ``time_limit`` (and
    ``total_time_limit`` unless None) seconds >= 0; else ParameterValidationError. A
    ``tol <= 0`` asks for a gap no search can close: every end would run to its limits."""
    as_real("tol", tol, positive=True,
            want="tol must be a finite number > 0 (the relative gap at which an interval "
                 "end stops, e.g. tol=1e-4)")
    if not isinstance(max_nodes, numbers.Integral) or isinstance(max_nodes, bool) \
            or max_nodes < 0:
        raise ParameterValidationError(
            f"max_nodes must be an integer >= 0; got {max_nodes!r}.")
    if not _seconds(time_limit):
        raise ParameterValidationError(
            f"time_limit must be a number of seconds >= 0; got {time_limit!r}.")
    if total_time_limit is not None and not _seconds(total_time_limit):
        raise ParameterValidationError(
            f"total_time_limit must be None or a number of seconds >= 0; got "
            f"{total_time_limit!r}.")
