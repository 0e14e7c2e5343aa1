"""``deadzone``: ``sign(u) max(|u| - w, 0)`` on the input."""

import numpy as np

from .base import Effect, Param


class Deadzone(Effect):
    name = "deadzone"
    param_names = ("w",)
    description = "sign(u) max(|u| - w, 0) on the input"
    acts_on_input = True

    def search_space(self, ctx):
        return (Param("w", 0.002 * ctx.u_max, 0.8 * ctx.u_max, log=True),)

    def transform_input(self, x, theta):
        w = float(theta[0])
        return np.sign(x) * np.maximum(np.abs(x) - w, 0.0)
