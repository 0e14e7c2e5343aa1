"""``extra_pole``: a unit-gain first-order factor ``(1 - p) / (1 - p q^-1)`` in series."""

import numpy as np

from .base import Effect, Param


class ExtraPole(Effect):
    name = "extra_pole"
    param_names = ("p",)
    description = "(1 - p) / (1 - p q^-1) in series, -1 < p < 1"

    def search_space(self, ctx):
        return (Param("p", -0.9, 0.98),)

    def series_filter(self, theta):
        p = float(theta[0])
        return np.array([1.0 - p]), np.array([1.0, -p])
