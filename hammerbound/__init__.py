"""hammerbound: guaranteed (set-membership) identification of Hammerstein systems with
input backlash, after the two-stage procedure of Cerone, Piga & Regruto.

Stage 1 (:class:`BacklashSetEstimator`) bounds the backlash from steady-state data; stage 2
(:class:`LinearEIVSetEstimator`) bounds the linear block from PRBS data as an
errors-in-variables problem; :class:`HammersteinBacklashIdentifier` runs both.
"""

from .backlash import BacklashSetEstimator, InnerSignalBounds
from .eiv import LinearEIVSetEstimator
from .exceptions import (
    DataScaleError,
    DataValidationError,
    DataWarning,
    EmptyFeasibleSetError,
    HammerboundError,
    IllPosedBacklashError,
    NotEnoughAmplitudesError,
    ParameterValidationError,
    RelaxationTooLargeError,
    ResultOneViolationError,
    SearchLimitWarning,
    SolverError,
    SolverNotAvailableError,
    SolverOptionError,
    UnboundedSetError,
)
from .experiments import chapter_example, prbs_experiment, square_wave_experiment
from .feasible_set import FeasibleSet, PolygonFeasibleSet
from .hammerstein import HammersteinBacklashIdentifier
from .iodata import IOData
from .relaxations.problem import EIVProblem, check_theta
from .solvers import available_solvers
from .systems import Backlash, HammersteinSystem, simulate_backlash

try:
    from importlib.metadata import PackageNotFoundError, version

    __version__ = version("hammerbound")
except PackageNotFoundError:  # pragma: no cover - running from a source tree, not installed
    __version__ = "0+unknown"

__all__ = [
    "Backlash",
    "BacklashSetEstimator",
    "DataScaleError",
    "DataValidationError",
    "DataWarning",
    "EIVProblem",
    "EmptyFeasibleSetError",
    "FeasibleSet",
    "HammerboundError",
    "HammersteinBacklashIdentifier",
    "HammersteinSystem",
    "IOData",
    "IllPosedBacklashError",
    "InnerSignalBounds",
    "LinearEIVSetEstimator",
    "NotEnoughAmplitudesError",
    "ParameterValidationError",
    "PolygonFeasibleSet",
    "RelaxationTooLargeError",
    "ResultOneViolationError",
    "SearchLimitWarning",
    "SolverError",
    "SolverNotAvailableError",
    "SolverOptionError",
    "UnboundedSetError",
    "available_solvers",
    "chapter_example",
    "check_theta",
    "prbs_experiment",
    "simulate_backlash",
    "square_wave_experiment",
    "__version__",
]
