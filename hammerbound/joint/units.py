"""The units the one-record method searches in: input and output of order one.

A record in other units -- the input times ``su``, the output times ``sy`` -- has the same
one-record set with ``m_l, m_r`` times ``sy / su``, ``c_l, c_r`` times ``su``, the first
inner value ``z0`` (and the inner signal, in output units through the unit gain (22.8))
times ``sy``; ``theta`` is unchanged. :func:`~.bounds.record_bounds` runs on the record
scaled by the powers of two that bring ``u`` and ``y`` to order one (exact in floating
point, as :mod:`hammerbound.relaxations.units` for stage 2) and maps everything back.
Measured before: the chapter's random-step record (N = 150, Delta eta = 0.05) took 65 s
with ``u``, ``y`` as simulated and 373 s with ``u * 100``, ``y * 1e-3`` (a valve in %
driving a flow in m3/s), at the same widths.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..relaxations.units import power_of_two_scale, rows_times
from .problem import RecordProblem, Witness


@dataclass(frozen=True)
class RecordUnits:
    """Input factor ``u`` and output factor ``y`` of a record's search units."""

    u: float
    y: float

    @classmethod
    def of(cls, problem: RecordProblem) -> RecordUnits:
        su = [np.abs(problem.u)]
        sy = [np.abs(problem.y), problem.deta]
        if problem.steady is not None:
            su.append(np.abs(problem.steady[0]))
            sy += [np.abs(problem.steady[1]), problem.steady[2]]
        return cls(power_of_two_scale(max(float(np.max(v, initial=0.0)) for v in su)),
                   power_of_two_scale(max(float(np.max(v, initial=0.0)) for v in sy)))

    @property
    def identity(self) -> bool:
        return self.u == 1.0 and self.y == 1.0

    def factors(self, p: int) -> np.ndarray:
        """Per row of the problem's box ``[theta (p), m_l, c_l, m_r, c_r, z0]``: the factor
        from the data's units to the search's."""
        m = self.y / self.u
        return np.concatenate([np.ones(p), [m, self.u, m, self.u, self.y]])

    def problem(self, pr: RecordProblem) -> RecordProblem:
        """The problem in the search's units."""
        if self.identity:
            return pr
        st = pr.steady
        if st is not None:
            st = (st[0] * self.u, st[1] * self.y, st[2] * self.y)
        box = pr.box * self.factors(pr.p)[:, None]
        return replace(pr, u=pr.u * self.u, y=pr.y * self.y, deta=pr.deta * self.y,
                       box=box, steady=st)

    def back(self, v, p: int):
        """Rows (or a vector) of ``[theta, m_l, c_l, m_r, c_r, z0]`` (or a prefix of them)
        in the data's units."""
        return rows_times(v, 1.0 / self.factors(p))

    def witness_back(self, w: Witness | None, p: int) -> Witness | None:
        """A witness of the search in the data's units (the same object if none)."""
        if w is None or self.identity:
            return w
        return replace(w, gamma=w.gamma / self.factors(p)[p: p + 4], z0=w.z0 / self.y,
                       x=w.x / self.y, eta=w.eta / self.y)
