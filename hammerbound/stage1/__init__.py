"""Stage 1 (section 22.3): the backlash's exact feasible set from steady-state square-wave
data (side polygons, vertices, edges, tight orthotope) and the inner-signal bounds it hands
to stage 2."""

from .estimator import BacklashSetEstimator
from .feasible_set import FeasibleSet, PolygonFeasibleSet
from .inner_signal import INNER_SIGNALS, InnerSignalBounds, Stage2Record, read_prbs_level

__all__ = ["INNER_SIGNALS", "BacklashSetEstimator", "FeasibleSet", "InnerSignalBounds",
           "PolygonFeasibleSet", "Stage2Record", "read_prbs_level"]
