"""The units stage 2 is solved in: data of order one, by exact power-of-two scalings.

Two rescalings leave the EIV set (22.34) the same up to a relabelling of ``theta``:

* **outputs** (:func:`unit_scale`): ``y``, ``x`` and both error bounds times ``c``;
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

from .problem import EIVProblem

# powers of two beyond this exponent are not used (2**-e would overflow near 2**1024)
_MAX_EXP = 1000

#: Magnitudes from ``2**-UNIT_SCALE_EXP`` to ``2**UNIT_SCALE_EXP`` count as order one:
#: :func:`power_of_two_scale` leaves them alone.
UNIT_SCALE_EXP = 3


def power_of_two_scale(mag: float) -> float:
    """``2**-e`` with ``2**e`` the power of two nearest ``mag`` (1.0 for magnitudes of order
    one, i.e. within ``2**+-UNIT_SCALE_EXP``, and for zero or non-finite ``mag``)."""
    if not (np.isfinite(mag) and mag > 0):
        return 1.0
    e = int(np.clip(np.round(np.log2(mag)), -_MAX_EXP, _MAX_EXP))
    return 1.0 if abs(e) <= UNIT_SCALE_EXP else float(2.0 ** -e)


def rows_times(v, factors) -> np.ndarray:
    """A copy of ``v`` (a vector, or the rows of a box) with entry or row ``k`` multiplied
    by ``factors[k]`` (``factors`` may be longer than ``v``)."""
    v = np.asarray(v, dtype=float)
    f = np.asarray(factors, dtype=float)[: v.shape[0]]
    return v * (f[:, None] if v.ndim == 2 else f)


def unit_scale(problem: EIVProblem) -> float:
    """A power of two that brings the problem's output magnitude to order one (or 1.0).

    The magnitude is ``max(max |y|, max Delta eta)``: ``y_t`` and ``eta_t`` enter every
    equation of (22.34) with coefficient one, so it is the scale of the equations and of
    the McCormick rows. Solvers with absolute tolerances (HiGHS's ``1e-7``) act on
    :meth:`~.problem.EIVProblem.scaled` copies as if relatively. Measured on the two records
    with ``|y| ~ 1e-3`` and noise at the bound of the shared reproducers
    (``exact_small_scale.json``): unscaled, the exact method found no verified point for
    either end of any parameter of the first in 60 s per end (HiGHS stopped with an error
    on 336 node LPs, each solved again from scratch); scaled, the exact fits take 0.9 s and
    5.1 s with every end closed.
    """
    mag = max(float(np.max(np.abs(problem.y), initial=0.0)),
              float(np.max(problem.deta, initial=0.0)))
    return power_of_two_scale(mag)


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
        """The units of ``problem``: the output scaled by :func:`unit_scale`; the
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

    @classmethod
    def of_lp(cls, problem: EIVProblem, lp_bounds) -> Units:
        """The units of ``problem`` with the ``b_j``'s scale from ``lp_bounds`` (p, 2), the
        LP method's intervals (:meth:`of`), unless a ``b_j`` end sits at the a priori box:
        then they say nothing of that scale (``|b_j| <= 1e4`` for ``b_j ~ 1e-8`` gave a
        factor ``2**13`` and a 300 s fit) and the input's magnitude sets it."""
        from .lp import touches_box

        na = problem.na
        if touches_box(np.asarray(lp_bounds), problem.theta_box)[na:].any():
            return cls.of(problem)
        return cls.of(problem, b_bounds=np.asarray(lp_bounds)[na:])

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

    def factors(self, p: int) -> np.ndarray:
        """Per entry of ``theta`` (``p`` of them): the factor from the data's units to the
        search's (1 for an ``a_i``, ``1 / s`` for a ``b_j``)."""
        return np.concatenate([np.ones(self.na), np.full(p - self.na, 1.0 / self.input)])

    def to_search(self, theta):
        """A theta (p,) or a box (p, 2) in the search's units (``b_j / s``)."""
        return rows_times(theta, self.factors(len(theta)))

    def back(self, theta):
        """A theta (p,) or a box (p, 2) of the search, in the data's units (``b_j * s``)."""
        return rows_times(theta, 1.0 / self.factors(len(theta)))

    def errors_back(self, eta, dx):
        """A witness's output and input errors in the data's units."""
        return eta / self.output, dx / (self.output * self.input)
