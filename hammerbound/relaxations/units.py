"""The units the exact method searches in: data of order one, by exact power-of-two scalings.

Two rescalings leave the EIV set (22.34) the same up to a relabelling of ``theta``:

* **outputs** (:func:`..problem.unit_scale`): ``y``, ``x`` and both error bounds times ``c``;
  every equation is multiplied by ``c``, ``theta`` is unchanged;
* **inputs** (:func:`input_scale`): ``x`` and the input-error bound times ``s``, every
  ``b_j`` divided by ``s`` (``b_j x = (b_j / s)(s x)``), the gain of (22.8) divided by
  ``s`` and the ``b_j`` rows of the a priori box as well.

With powers of two both are exact in floating point, so a bound or a witness found in the
scaled units maps back exactly (:class:`Units`). Why the inputs too: HiGHS's tolerances are
absolute, and the search's tolerance ``tol * max(1, |value|)`` is absolute below one. On data
in units whose gain is far from one (the chapter's stage 2 with ``x * 1e-4`` and
``y * 1e4``: ``b_j ~ 1e8``) the McCormick rows mixed coefficients of ``1e8`` with errors of
``1e-8`` and one fit ran for over 40 minutes; with a gain of ``1e-6`` the tolerance of the
``b_j`` ends (``1e-4``) was a hundred times the parameters themselves. In the scaled units
the ``b_j`` are of the order of the data's own gain scale ``max |y| / max |x|``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .problem import UNIT_SCALE_EXP, EIVProblem, unit_scale

# powers of two beyond this exponent are not used (no overflow or subnormal data)
_MAX_EXP = 500


def power_of_two_scale(mag: float) -> float:
    """``2**-e`` with ``2**e`` the power of two nearest ``mag`` (1.0 for magnitudes of order
    one, i.e. within ``2**+-UNIT_SCALE_EXP``, and for zero or non-finite ``mag``)."""
    if not (np.isfinite(mag) and mag > 0):
        return 1.0
    e = int(np.clip(np.round(np.log2(mag)), -_MAX_EXP, _MAX_EXP))
    return 1.0 if abs(e) <= UNIT_SCALE_EXP else float(2.0 ** -e)


def input_scale(problem: EIVProblem) -> float:
    """A power of two ``s`` that brings ``max(max |x|, max input error bound)`` to order
    one (1.0 if it already is, or if there is no input)."""
    mag = max(float(np.max(np.abs(problem.x), initial=0.0)),
              float(np.max(problem.input_bound, initial=0.0)))
    return power_of_two_scale(mag)


@dataclass(frozen=True)
class Units:
    """The output factor ``c`` and input factor ``s`` of a problem's search units (see the
    module docstring); ``na`` tells which entries of ``theta`` are ``a_i`` (unchanged)."""

    output: float
    input: float
    na: int

    @classmethod
    def of(cls, problem: EIVProblem, b_bounds=None) -> Units:
        """The units of ``problem``: the output scaled by :func:`..problem.unit_scale`; the
        input by :func:`input_scale`, or, given bounds of the ``b_j`` (e.g. the LP
        method's, shape (nb', 2)), by the power of two nearest their largest magnitude
        unless that is of order one (then the ``b_j`` are of order one in the search's
        units, and a tolerance relative to ``max(1, |b_j|)`` there is relative to the
        ``b_j`` of the record, whatever its units)."""
        c = unit_scale(problem)
        mag = 0.0 if b_bounds is None else float(np.max(np.abs(b_bounds), initial=0.0))
        if np.isfinite(mag) and mag > 0:
            s = 1.0 / power_of_two_scale(mag)
        else:
            s = input_scale(problem.scaled(c) if c != 1.0 else problem)
        return cls(c, s, problem.na)

    def problem(self, problem: EIVProblem) -> EIVProblem:
        """The problem in these units (the same object when both factors are one)."""
        if self.output != 1.0:
            problem = problem.scaled(self.output)
        if self.input == 1.0:
            return problem
        s, na = self.input, self.na
        box = problem.theta_box.copy()
        box[na:] /= s
        gain = problem.steady_state_gain
        return dataclasses.replace(
            problem, x=problem.x * s, input_bound=problem.input_bound * s,
            theta_box=box, steady_state_gain=None if gain is None else gain / s)

    def _b_factor(self, theta, factor):
        out = np.array(theta, dtype=float, copy=True)
        out[self.na:] = out[self.na:] * factor
        return out

    def to_search(self, theta):
        """A theta (p,) or a box (p, 2) in the search's units (``b_j / s``)."""
        return self._b_factor(theta, 1.0 / self.input)

    def back(self, theta):
        """A theta (p,) or a box (p, 2) of the search, in the data's units (``b_j * s``)."""
        return self._b_factor(theta, self.input)

    def factor(self, k: int) -> float:
        """What a value of parameter ``k`` (a bound, a gap) in the search's units is
        multiplied by in the data's (``s`` for a ``b_j``, 1 for an ``a_i``)."""
        return self.input if k >= self.na else 1.0

    def errors_back(self, eta, dx):
        """A witness's output and input errors in the data's units."""
        return eta / self.output, dx / (self.output * self.input)
