"""hammerbound: guaranteed (set-membership) identification of Hammerstein systems with
input backlash, after the two-stage procedure of Cerone, Piga & Regruto.

Stage 1 (:class:`BacklashSetEstimator`) bounds the backlash from steady-state data; stage 2
(:class:`LinearEIVSetEstimator`) bounds the linear block from PRBS data as an
errors-in-variables problem; :class:`HammersteinBacklashIdentifier` runs both.
"""

from . import _compat
from .data.iodata import IOData
from .exceptions import (
    DataScaleError,
    DataValidationError,
    DataWarning,
    EmptyFeasibleSetError,
    HammerboundError,
    IllPosedBacklashError,
    NotEnoughAmplitudesError,
    NotIdentifiedWarning,
    ParameterValidationError,
    RelaxationTooLargeError,
    ResultOneViolationError,
    SearchLimitWarning,
    SolverError,
    SolverNotAvailableError,
    SolverOptionError,
    UnboundedSetError,
)
from .hammerstein.identifier import HammersteinBacklashIdentifier
from .model_selection import OrderSelectionCV
from .relaxations.problem import EIVProblem, check_theta
from .results import IntervalSet
from .solvers import available_solvers
from .stage1.estimator import BacklashSetEstimator, InnerSignalBounds
from .stage1.feasible_set import FeasibleSet, PolygonFeasibleSet
from .stage2.estimator import LinearEIVSetEstimator
from .systems.experiments import (
    chapter_example,
    eiv_example,
    prbs_experiment,
    square_wave_experiment,
)
from .systems.models import Backlash, HammersteinSystem, simulate_backlash
from .systems.records import ordinary_record

_compat.install()


def __getattr__(name):
    # ``hammerbound.experiments`` etc. as attributes (old layout): deprecated, see _compat
    if name in _compat.MOVED:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

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
    "IntervalSet",
    "LinearEIVSetEstimator",
    "NotEnoughAmplitudesError",
    "NotIdentifiedWarning",
    "OrderSelectionCV",
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
    "eiv_example",
    "ordinary_record",
    "prbs_experiment",
    "simulate_backlash",
    "square_wave_experiment",
    "__version__",
]
