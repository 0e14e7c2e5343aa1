"""``output_saturation``: the sensor clips its reading to ``[lo, hi]``.

Distinct from input ``saturation`` (which limits what enters the linear block): here the
model output is ``clip(yhat, lo, hi)`` and a measured sample at a limit only says that the
true output is beyond it. Such samples are fitted one-sided (``yhat >= y - e`` at the top,
``yhat <= y + e`` at the bottom); a sample counts as *at the limit* when it lies within
``2 %`` of ``hi - lo`` of it. Searched: ``lo`` in ``[-1.02, 0] max|y|`` and ``hi`` in
``[0, 1.02] max|y|`` (the readings lie inside the sensor range, which contains 0) on a
product grid of at least 12 x 12 points, then Nelder-Mead: the error is flat for limits
beyond the data and falls like ``H - hi`` below a true limit ``H``, so the grid must be
finer than the gap to start in that basin.

No certified lower bound is given for this candidate (the LP fits the prediction before
the clip); its achieved error is exact, as for every candidate.
"""

import numpy as np

from .base import Effect, Param

#: Samples within this fraction of ``hi - lo`` from a limit are at the limit.
MARGIN = 0.02


class _FineParam(Param):
    def grid(self, size):
        return np.linspace(self.lo, self.hi, max(int(size), 12))


class OutputSaturation(Effect):
    name = "output_saturation"
    default = False
    param_names = ("lo", "hi")
    description = "sensor saturation: the output is clip(yhat, lo, hi)"

    def search_space(self, ctx):
        y = 1.02 * ctx.y_max
        return (_FineParam("lo", -y, 0.0), _FineParam("hi", 0.0, y))

    def transform_output(self, yhat, theta):
        lo, hi = sorted(float(v) for v in theta)
        return np.clip(yhat, lo, hi)

    def one_sided(self, y, theta):
        lo, hi = sorted(float(v) for v in theta)
        m = MARGIN * (hi - lo)
        sides = np.zeros(np.shape(y), int)
        sides[y >= hi - m] = 1
        sides[y <= lo + m] = -1
        return sides

    def value(self, theta, coefs):
        return tuple(sorted(float(v) for v in theta))
