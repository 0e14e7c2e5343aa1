"""``relay``: relay with hysteresis on the input, plus the offset its off level makes.

The relay output is ``1`` (on) after the input rose above ``h`` and ``0`` (off) after it
fell below ``-h`` (switching thresholds ``-h, +h``; between them it keeps its state; at
rest it is off). Searched: ``h`` in ``[0.01, 0.8] max|u|`` (1-D grid, then Brent).

Output levels ``y_off, y_on``: their difference is a gain, absorbed by the refitted
numerator (normalised: levels ``0, 1``); the off level has acted on the linear block
since ever (the data start from rest with the relay off), so it is a constant ``o`` on
the output, fitted exactly as an LP column. For a true linear block ``G`` the refitted
numerator is ``(y_on - y_off) G`` and ``o = G(1) y_off``. The reported value is ``(h, o)``.

The error is piecewise constant in ``h`` (it changes only when ``h`` crosses an input
value), so a local refinement cannot move between plateaus: the grid is dense
(``max(4 grid_size, 64)`` points). Only thresholds symmetric about 0 are searched: a joint
2-D search of two thresholds on such plateaus would need data-driven starting points.
"""

import numpy as np

from .base import Effect, Param


def relay(u, h):
    """Relay with hysteresis, thresholds -h/+h, levels 0 (off, at rest) / 1 (on)."""
    x = np.asarray(u, dtype=float)
    up, down = (x > h).tolist(), (x < -h).tolist()
    out = [0.0] * x.size
    s = 0.0
    for t in range(x.size):
        if up[t]:
            s = 1.0
        elif down[t]:
            s = 0.0
        out[t] = s
    return np.array(out)


class _DenseParam(Param):
    """A parameter whose error is piecewise constant: searched on a dense grid."""

    def grid(self, size):
        return np.linspace(self.lo, self.hi, max(4 * int(size), 64))


class Relay(Effect):
    name = "relay"
    default = False
    param_names = ("h",)
    linear_names = ("o",)
    description = ("relay with hysteresis on the input: on (1) above h, off (0) below -h, "
                   "plus the output offset o of its off level")
    acts_on_input = True

    def search_space(self, ctx):
        return (_DenseParam("h", 0.01 * ctx.u_max, 0.8 * ctx.u_max),)

    def transform_input(self, x, theta):
        return relay(x, abs(float(theta[0])))

    def output_columns(self, n, theta):
        return np.ones((n, 1))
