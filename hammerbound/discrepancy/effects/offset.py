"""``offset``: a constant ``o`` added to the output (an LP coefficient, searched exactly)."""

import numpy as np

from .base import Effect


class Offset(Effect):
    name = "offset"
    linear_names = ("o",)
    description = "constant o added to the output"

    def output_columns(self, n, theta):
        return np.ones((n, 1))
