"""Cheap certified bounds of a long record from its windows.

Every contiguous window ``[s, e)`` of the record is itself a one-record problem whose first
inner value ``x_s`` is unknown: it lies in the band ``[R_s, L_s]`` at ``u_s`` (the play
operator keeps every inner value in the band), so the window's problem with that band as
its a priori ``z0`` row holds every parameter point of the whole record (with ``x_s`` from
the record's own trajectory and the window's part of the noise). Hence

* a window whose relaxation is certified infeasible certifies the whole box empty;
* a window's certified bounds of ``theta`` and the backlash hold for the whole record
  (its ``z0`` bounds hold for the record only when ``s = 0``).

The simplex cost of one relaxation LP grows faster than the record (measured on the
chapter's random-step record, Delta eta = 0.05, one OBBT round of 18 LPs: 0.55 s at
N = 300, 5.8 s at N = 1000), so OBBT over windows of a few hundred samples brings a box of
a long record close to its fixed point at a fraction of the cost, and the rounds over the
whole record then start from there.
"""

from __future__ import annotations

import numpy as np

from .modes import band_range
from .problem import RecordProblem

__all__ = ["WINDOW", "window_problem", "windows"]

#: samples per window (and records up to ``1.5 * WINDOW`` are not split). Measured with
#: ``method="lp"`` on the chapter's system: a multilevel PRBS of 300 samples at Delta eta =
#: 0.005 (noise at the bound) took over 10 min without windows and 14 s with windows of
#: 150; a random-step record of 300 samples at 0.05, 27.6 s without and about the same
#: with; at N = 1000 windows of 150 and 300 took about the same time; every width was the
#: same to 1e-6.
WINDOW = 150


def windows(problem: RecordProblem, length: int = WINDOW) -> list[tuple[int, int]]:
    """``(s, e)`` windows of about ``length`` samples that cover every equation of the
    record (consecutive windows overlap by the ``n0`` samples an equation looks back);
    empty for a record shorter than ``1.5 * length``."""
    N, n0 = problem.N, problem.n0
    if N < 1.5 * length:
        return []
    count = int(round(N / length))
    edges = np.linspace(0, N, count + 1).round().astype(int)
    return [(max(0, int(a) - n0) if i else 0, int(b))
            for i, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True))]


def window_problem(problem: RecordProblem, box, s: int, e: int) -> RecordProblem:
    """The one-record problem of samples ``[s, e)`` over ``box`` (rows of the record's
    box): the same parameters, and for ``s > 0`` the band at ``u_s`` over the box's
    backlash as the a priori range of its first inner value."""
    box = np.array(box, dtype=float)
    p = problem.p
    if s > 0:
        box[p + 4] = band_range(float(problem.u[s]), box[p: p + 4])
    return RecordProblem(problem.u[s:e], problem.y[s:e], problem.deta[s:e], problem.na,
                         problem.nb, problem.nk, box, steady=problem.steady,
                         gain=problem.gain)
