"""``backlash``: play operator of half-width ``c`` (unit slopes, state 0 at rest)."""

from ...systems.models import simulate_backlash
from .base import Effect, Param


class Backlash(Effect):
    name = "backlash"
    param_names = ("c",)
    description = "play operator of half-width c (unit slopes) on the input"
    acts_on_input = True

    def search_space(self, ctx):
        return (Param("c", 0.002 * ctx.u_max, 0.5 * ctx.u_max, log=True),)

    def transform_input(self, x, theta):
        c = float(theta[0])
        return simulate_backlash(x, 1.0, c, 1.0, c, x0=0.0)
