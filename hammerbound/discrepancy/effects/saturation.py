"""``saturation``: ``clip(u, -s, s)`` on the input."""

import numpy as np

from .base import Effect, Param


class Saturation(Effect):
    name = "saturation"
    param_names = ("s",)
    description = "clip(u, -s, s) on the input"
    acts_on_input = True

    def search_space(self, ctx):
        return (Param("s", 0.05 * ctx.u_max, 0.999 * ctx.u_max),)

    def transform_input(self, x, theta):
        s = float(theta[0])
        return np.clip(x, -s, s)
