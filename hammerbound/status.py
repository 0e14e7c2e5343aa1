"""The statuses of an interval end, as named constants (one vocabulary for every result).

Every end of every reported interval is a *guaranteed* bound whatever its status; the
status says how it was obtained. The constants are plain strings (like cvxpy's), so a
status compares equal to the word it stands for (``OPTIMAL == "optimal"``) and is written
as that word to JSON.

=================  =====================================================================
constant           meaning
=================  =====================================================================
``OPTIMAL``        solved to optimality (exact method: to within its ``tol``)
``INACCURATE``     the solver stopped inaccurate; the bound is repaired from its dual
``LIMIT``          a time, node or iteration limit stopped the search: a certified outer
                   bound, possibly looser than the exact one
``BOX``            the end is set by the a priori box (``theta_box``, the stability box
                   under A1): guaranteed under that assumption, not by the data
``RELAXATION``     the certified bound of a relaxation, not searched to tightness (e.g.
                   the LP bound a moment end keeps where its certificate is not tighter)
``NOT_IDENTIFIED`` the data do not bound this end: reported as infinite
``INFEASIBLE``     the solver reported the subproblem infeasible
``FAILED``         no usable solve: the fallback bound (LP / a priori box) is reported
=================  =====================================================================
"""

from __future__ import annotations

from .exceptions import ParameterValidationError

__all__ = ["BOX", "FAILED", "INACCURATE", "INFEASIBLE", "LIMIT", "NOT_IDENTIFIED", "OPTIMAL",
           "RELAXATION", "STATUSES", "check_status", "describe"]

OPTIMAL = "optimal"
INACCURATE = "inaccurate"
LIMIT = "limit"
BOX = "box"
RELAXATION = "relaxation"
NOT_IDENTIFIED = "not identified"
INFEASIBLE = "infeasible"
FAILED = "failed"

#: Every status, in the order above.
STATUSES = (OPTIMAL, INACCURATE, LIMIT, BOX, RELAXATION, NOT_IDENTIFIED, INFEASIBLE, FAILED)

#: How a non-optimal end was obtained, as printed in the ``status`` column of the tables.
_WORDS = {
    INACCURATE: "from dual (solver inaccurate)",
    LIMIT: "at time/node limit (outer bound)",
    BOX: "from a priori box",
    RELAXATION: "relaxation",
    NOT_IDENTIFIED: "not identified",
    INFEASIBLE: "infeasible",
    FAILED: "failed",
}


def check_status(status) -> str:
    """``status`` if it is one of :data:`STATUSES`, else a ParameterValidationError naming them."""
    if not isinstance(status, str) or status not in STATUSES:
        raise ParameterValidationError(f"unknown interval-end status {status!r}; expected one of "
                         f"{', '.join(map(repr, STATUSES))}.")
    return status


def describe(status: str) -> str:
    """The words of a non-optimal status in the tables (``""`` for :data:`OPTIMAL`)."""
    return "" if status == OPTIMAL else _WORDS[check_status(status)]
