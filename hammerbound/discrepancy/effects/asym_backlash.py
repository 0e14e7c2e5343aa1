"""``asym_backlash``: the chapter's backlash (22.1) with four parameters ``m_l, c_l, m_r, c_r``.

Lines ``L(u) = m_l (u + c_l)`` and ``R(u) = m_r (u - c_r)``; state 0 at rest. The gain of
the linear block and the common scale of the two slopes are not separately identifiable
(``k m_l, k m_r`` with ``B / k`` gives the same output), so the search normalises the
slopes to a **mean slope of one**: ``m_l = 1 + s``, ``m_r = 1 - s``. Searched: ``s``
(slope asymmetry, in ``[-0.3, 0.3]``: slope ratios up to 1.86), ``c_l``, ``c_r`` (each in
``[0.002, 0.5] max|u|``, log) on a 3-D grid, then Nelder-Mead. With ``s = 0`` and
``c_l = c_r`` it is ``backlash``.

The reported value is ``(m_l, c_l, m_r, c_r)`` in the chapter's convention (22.8): the
refitted linear block's static gain ``k = B(1)/A(1)`` moves to the slopes,
``m_l = k (1 + s)``, ``m_r = k (1 - s)``, and the linear block of
:meth:`~hammerbound.discrepancy.RefinedModel.to_hammerstein` is ``B / k`` (unit static
gain). This needs ``k > 0`` and the backlash acting directly on the linear block (it is the
last input effect and the model has no backlash of its own); otherwise the mean-slope-one
values ``(1 + s, c_l, 1 - s, c_r)`` are reported (see
:meth:`~hammerbound.discrepancy.RefinedModel.chapter_gain`).

Where the input passes the crossing of two non-parallel lines ((22.1) is ill-posed there,
:func:`~hammerbound.systems.models.simulate_backlash` raises) the right line wins, so that the
search can evaluate any parameter value; such values fit badly and are not chosen. The
crossing is at ``u_c = -(m_l c_l + m_r c_r) / (m_l - m_r)``: a strongly asymmetric backlash
is only well defined on a narrow input range.
"""

import numpy as np

from ...systems.models import GAMMA_NAMES
from .base import Effect, Param


def play(u, ml, cl, mr, cr, x0=0.0):
    """Play operator (22.1) from state ``x0`` (right line first where the lines cross)."""
    L = (ml * (np.asarray(u, dtype=float) + cl)).tolist()
    R = (mr * (np.asarray(u, dtype=float) - cr)).tolist()
    out = [0.0] * len(L)
    prev = float(x0)
    for t in range(len(L)):
        if prev < R[t]:
            prev = R[t]
        elif prev > L[t]:
            prev = L[t]
        out[t] = prev
    return np.array(out)


class AsymBacklash(Effect):
    name = "asym_backlash"
    default = False
    param_names = ("s", "c_l", "c_r")
    description = ("backlash (22.1) with slopes m_l = 1 + s, m_r = 1 - s (mean slope 1) "
                   "and half-widths c_l, c_r on the input")
    acts_on_input = True
    seeded_by = ("backlash",)

    def seeds(self, fitted):
        """The symmetric backlash found (``s = 0``, ``c_l = c_r = c``): this class holds
        it, and its coarse 3-D grid alone missed it (new-user trial 14: 0.313 here against
        0.125 for ``backlash`` on the same record)."""
        if "backlash" not in fitted:
            return []
        c = float(fitted["backlash"][0])
        return [(0.0, c, c)]

    def search_space(self, ctx):
        u = ctx.u_max
        return (Param("s", -0.3, 0.3), Param("c_l", 0.002 * u, 0.5 * u, log=True),
                Param("c_r", 0.002 * u, 0.5 * u, log=True))

    def transform_input(self, x, theta):
        s, cl, cr = (float(v) for v in theta)
        return play(x, 1.0 + s, cl, 1.0 - s, cr)

    def value(self, theta, coefs, model=None):
        s, cl, cr = (float(v) for v in theta)
        k = None if model is None else model.chapter_gain(self.name)
        k = 1.0 if k is None else k
        return (k * (1.0 + s), cl, k * (1.0 - s), cr)

    def param_label(self):
        return ",".join(GAMMA_NAMES)  # the identifier's names (one name per concept)
