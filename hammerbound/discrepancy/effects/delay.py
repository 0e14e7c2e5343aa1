"""``delay``: an extra input delay ``q^-d`` (integer ``d >= 1``, every value tried).

The reported value is the **total input delay** of the refined model: the number of
leading zero coefficients of its numerator ``B`` (the model's own delay, plus ``d``, plus
the leading refitted coefficients pinned to zero because the data do not need them: see
``pins_leading``), i.e. the first sample at which the input acts on the output. A model
with a direct term and a true total delay of 4 is thus reported as ``d = 4`` whichever
``q^-d`` the search passed through. For a black-box model, whose own delay is unknown,
it is the added ``d``.
"""

import numpy as np

from .base import Effect, Param


def _no_numerator(model) -> bool:
    """Whether ``model`` has no numerator to count a total delay in (a black box): the
    reported value is then the added ``d``."""
    return model is None or model.B is None or not np.any(model.B)


class Delay(Effect):
    name = "delay"
    param_names = ("d",)
    description = "q^-d (integer d >= 1) extra input delay"
    pins_leading = True

    def value_note(self, model=None) -> str:
        """The value is the total delay of a model with a numerator, the added ``d`` of a
        black box (see :meth:`value`)."""
        if _no_numerator(model):
            return " samples added"
        return " samples in all, the model's own delay included"

    def search_space(self, ctx):
        return (Param("d", 1, max(1, ctx.max_delay), integer=True),)

    def series_filter(self, theta):
        d = int(round(theta[0]))
        return np.r_[np.zeros(d), 1.0], np.array([1.0])

    def value(self, theta, coefs, model=None):
        d = int(round(theta[0]))
        if _no_numerator(model):
            return float(d)
        return float(np.flatnonzero(model.B)[0])
