"""One ordinary record is enough: the backlash and the linear block bounded jointly.

The two-stage method of the chapter needs two laboratory experiments (steady-state square
waves, then a PRBS at ``+-u*``). Here the whole record -- random steps, a sine, a
closed-loop log, or a record that holds steady-state holds and PRBS segments -- enters one
bounded-error problem (:mod:`.problem`) whose unknowns are the backlash ``(m_l, c_l, m_r,
c_r)``, the first inner value ``z0`` and the unit-gain linear block ``theta``:

* :mod:`.modes` writes the play operator symbolically over a parameter box (which line
  every sample is on, for all parameters in the box);
* :mod:`.relaxation` turns that into an LP relaxation (McCormick envelopes and RLT rows);
* :mod:`.search` bounds every parameter by OBBT and branch-and-bound;
* :mod:`.local` finds verified points (witnesses) by sequential linear programming;
* :mod:`.prior` holds the a priori box and names what a record cannot identify;
* :func:`record_bounds` runs all of it.

Use it through :class:`~hammerbound.HammersteinBacklashIdentifier` (``fit(u, y)`` without
steady-state data).
"""

from .bounds import record_bounds
from .prior import (
    ASSUMED_LIMIT_RTOL,
    LIMIT_RTOL,
    WIDEN_FACTOR,
    GammaPrior,
    at_prior_limit,
    default_gamma_box,
    record_box,
    reversal_summary,
    unidentified,
)
from .problem import GAMMA_NAMES, RecordProblem, Witness, verify_point

__all__ = [
    "ASSUMED_LIMIT_RTOL",
    "GAMMA_NAMES",
    "GammaPrior",
    "LIMIT_RTOL",
    "RecordProblem",
    "WIDEN_FACTOR",
    "Witness",
    "at_prior_limit",
    "default_gamma_box",
    "record_bounds",
    "record_box",
    "reversal_summary",
    "unidentified",
    "verify_point",
]
