"""Stage 2's bounding methods on one :class:`EIVProblem` (22.34): the polytopic LP
(:func:`lp_bounds`), sparse moment relaxations (:func:`moment_bounds`) and the exact
branch-and-bound (:func:`exact_bounds`), with :func:`check_theta` to verify a point and
:func:`consistency` to decide whether the set is empty."""

from .exact.bnb import SearchOptions, exact_bounds
from .exact.consistency import Consistency, consistency
from .lp import lp_bounds
from .moment import moment_bounds
from .problem import EIVProblem, FeasibilityCheck, check_theta
from .result import BoundInfo, IntervalResult, IntervalSet

__all__ = [
    "BoundInfo",
    "Consistency",
    "EIVProblem",
    "FeasibilityCheck",
    "IntervalResult",
    "IntervalSet",
    "SearchOptions",
    "check_theta",
    "consistency",
    "exact_bounds",
    "lp_bounds",
    "moment_bounds",
]
