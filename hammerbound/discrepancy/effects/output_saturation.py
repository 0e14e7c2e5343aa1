"""``output_saturation``: the sensor clips its reading to ``[lo, hi]``.

Distinct from input ``saturation`` (which limits what enters the linear block): here the
model output is ``clip(yhat, lo, hi)`` and a measured sample at a limit only says that the
true output is beyond it. Such samples are fitted one-sided (``yhat >= y - e`` at the top,
``yhat <= y + e`` at the bottom). A sample counts as *at the limit* when it lies within
the output bound ``Delta`` of it (``y_t >= hi - Delta`` or ``y_t <= lo + Delta``, relaxed
outward by the tolerance policy): a clipped reading is ``hi + eta_t`` with ``|eta_t| <=
Delta``, so every clipped sample is at the limit whatever the noise, and the one-sided row
is exact for it. For a sample with ``|y_t - hi| <= e`` the condition ``|y_t - clip(yhat_t,
lo, hi)| <= e`` is equivalent to ``yhat_t >= y_t - e``, and it implies it for every sample,
so treating an unclipped sample near the limit one-sided only relaxes the LP; the achieved
error is recomputed from the clipped model either way. Searched: ``lo`` in ``[-1.02, 0] max|y|`` and ``hi`` in
``[0, 1.02] max|y|`` (the readings lie inside the sensor range, which contains 0) on a
product grid of at least 12 x 12 points, then Nelder-Mead: the error is flat for limits
beyond the data and falls like ``H - hi`` below a true limit ``H``, so the grid must be
finer than the gap to start in that basin.

No certified lower bound is given for this candidate (the LP fits the prediction before
the clip); its achieved error is exact, as for every candidate.
"""

import numpy as np

from ...tolerances import feasibility_tol
from .base import Effect, Param


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

    def one_sided(self, y, theta, output_bound):
        lo, hi = sorted(float(v) for v in theta)
        m = output_bound + feasibility_tol(lo, hi, output_bound)  # outward: relaxes the LP
        sides = np.zeros(np.shape(y), int)
        sides[y >= hi - m] = 1
        sides[y <= lo + m] = -1  # near both limits: either row alone is a relaxation
        return sides

    def value(self, theta, coefs, model=None):
        return tuple(sorted(float(v) for v in theta))
