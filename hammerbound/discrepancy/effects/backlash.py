"""``backlash``: play operator of half-width ``c`` (unit slopes, state 0 at rest)."""

from ...systems.models import simulate_backlash
from .base import Effect, Param


class SymmetricBacklash(Effect):
    """The candidate ``backlash``: a play operator of half-width ``c`` with unit slopes (not
    :class:`hammerbound.systems.models.Backlash`, the chapter's four-parameter backlash;
    that one is the candidate ``asym_backlash``)."""

    name = "backlash"
    param_names = ("c",)
    description = "play operator of half-width c (unit slopes) on the input"
    acts_on_input = True

    def search_space(self, ctx):
        return (Param("c", 0.002 * ctx.u_max, 0.5 * ctx.u_max, log=True),)

    def transform_input(self, x, theta):
        c = float(theta[0])
        return simulate_backlash(x, 1.0, c, 1.0, c, x0=0.0)


def __getattr__(name):
    # renamed in 0.2.0 (one class name per concept: systems.Backlash is the chapter's)
    if name == "Backlash":
        from ..._compat import warn_renamed

        warn_renamed("hammerbound.discrepancy.effects.backlash.Backlash",
                     "SymmetricBacklash")
        return SymmetricBacklash
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
