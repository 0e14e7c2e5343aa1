"""The tolerance policy in one place (see ``docs/tolerances.md``).

Every decision of the form "is this within the bound?" is made in floating point. The
policy: a bound ``|e| <= D`` is tested as ``|e| <= D + feasibility_tol(...)`` where the
tolerance is *relative to the magnitudes of the terms* that make up ``e`` and ``D``. A
tolerance only ever relaxes a feasibility test (it widens a set, never shrinks it); a set
is declared empty, or data inconsistent, only when the violation is certified to exceed it.

``FEASIBILITY_RTOL`` is far above the rounding error of evaluating a constraint in double
precision (``~1e-16`` per term) and far below any noise bound a user can mean, so a
relaxed set differs from the exact one only in digits that carry no information.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ARITHMETIC_RTOL", "FEASIBILITY_RTOL", "feasibility_tol"]

#: Relative outward tolerance of every feasibility decision that passes through a
#: numerical solver (LP/SDP: their own feasibility tolerances are ~1e-9 of scaled data).
FEASIBILITY_RTOL = 1e-9

#: Relative outward tolerance of decisions computed directly in double precision with a
#: bounded number of operations and an exact (rational) check before "empty" -- the
#: stage-1 polygons. ~5e4 unit roundoffs: far above the rounding of the data and of the
#: computation, and small enough that the widening stays below 1e-9 of the parameters.
ARITHMETIC_RTOL = 1e-11


def feasibility_tol(*magnitudes, rtol: float = FEASIBILITY_RTOL) -> float | np.ndarray:
    """Outward tolerance for a constraint whose terms have the given magnitudes.

    ``feasibility_tol(|y|, |m u|, |beta|, D)`` is ``rtol * (|y| + |m u| + |beta| + D)``
    (element-wise for arrays), ``rtol`` being :data:`FEASIBILITY_RTOL` unless given (use
    :data:`ARITHMETIC_RTOL` for solver-free double-precision decisions). Pass every term
    that enters the constraint, including the bound itself, so the tolerance follows the
    data's scale.
    """
    total = 0.0
    for m in magnitudes:
        total = total + np.abs(m)
    return rtol * total
