"""``polynomial``: a static polynomial ``x + a2 x^2 + a3 x^3`` on the input.

Normalisation: the linear coefficient is 1 - the linear block's numerator absorbs the
gain (with ``refit="linear"``), so ``a2`` and ``a3`` are the quadratic and cubic terms
relative to the linear one. They are searched jointly (2-D grid, then Nelder-Mead): with
a refitted numerator ``B`` the model is bilinear in ``(B, a2, a3)``, so they cannot be
LP columns without giving every power its own numerator (a more general, less specific
class).
"""


from .base import Effect, Param


class Polynomial(Effect):
    name = "polynomial"
    default = False
    param_names = ("a2", "a3")
    description = "static polynomial x + a2 x^2 + a3 x^3 on the input"
    acts_on_input = True

    def search_space(self, ctx):
        u = ctx.u_max
        return (Param("a2", -1.0 / u, 1.0 / u), Param("a3", -1.0 / u**2, 1.0 / u**2))

    def transform_input(self, x, theta):
        a2, a3 = float(theta[0]), float(theta[1])
        return x + a2 * x * x + a3 * x * x * x
