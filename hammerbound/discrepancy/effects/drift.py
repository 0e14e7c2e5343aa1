"""``drift``: a slow gain and offset drift of the output over the record.

The output is ``(1 + g t/n) (yhat + o1 t/n)`` (``t = 0 .. n-1``, ``n`` the record
length; the sensor gain drifts and multiplies everything it reads, including an offset
that builds up): at the start the model is unchanged, at the end its gain is ``1 + g``
times larger and an offset ``o1`` has built up. ``g`` is searched (1-D grid in ``[-0.5, 0.5]``, then Brent);
its gain multiplies the rows of the LP (:meth:`~.base.Effect.output_gain`), so for each
``g`` the refitted coefficients and ``o1`` are exact. A constant offset is the ``offset``
candidate (combine them for a drift that starts off zero).
"""

import numpy as np

from .base import Effect, Param


class Drift(Effect):
    name = "drift"
    default = False
    param_names = ("g",)
    linear_names = ("o1",)
    description = "output (1 + g t/n) (yhat + o1 t/n): slow gain and offset drift"

    def search_space(self, ctx):
        return (Param("g", -0.5, 0.5),)

    def output_gain(self, n, theta):
        return 1.0 + float(theta[0]) * np.arange(n) / n

    def transform_output(self, yhat, theta):
        return yhat * self.output_gain(yhat.size, theta)

    def output_columns(self, n, theta):
        return (np.arange(n) / n)[:, None]
