"""``delay``: an extra input delay ``q^-d`` (integer ``d >= 1``, every value tried)."""

import numpy as np

from .base import Effect, Param


class Delay(Effect):
    name = "delay"
    param_names = ("d",)
    description = "q^-d (integer d >= 1) extra input delay"

    def search_space(self, ctx):
        return (Param("d", 1, max(1, ctx.max_delay), integer=True),)

    def series_filter(self, theta):
        d = int(round(theta[0]))
        return np.r_[np.zeros(d), 1.0], np.array([1.0])

    def value(self, theta, coefs):
        return float(int(round(theta[0])))
