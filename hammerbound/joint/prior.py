"""The a priori box of the one-record problem and what the record cannot identify.

Every bound of the one-record method lies inside an a priori box of
``[theta, m_l, c_l, m_r, c_r, z0]``. Its parts are either the chapter's model (``m > 0``,
``c >= 0``, a stable ``A``: ``|a_i| <= binom(na, i)``), or assumptions that are printed
with every result and can be replaced by the user:

* ``|b_j| <= b_bound`` (default ``1e4``, as stage 2);
* ``m_l, m_r <= m_max`` (default ``100`` times the slope ``(range(y) + 2 deta) / range(u)``
  the record allows, its outputs' range widened by their errors; with the unit gain (22.8)
  the backlash slopes carry the gain of the system);
* ``c_l, c_r <= c_max`` (default the input's range: a dead band wider than every input
  move is never crossed after the first line the record touches).

A default limit is a guess, and a wrong one can hold up other ends: a state that starts
on the left line far from the record's inputs identifies ``m_l c_l`` with ``c_l`` above the
input's range, and ``c_l <= c_max`` then pushed ``m_l`` above its true value (review).
So the fit is run again with every default limit that an end reaches
:data:`WIDEN_FACTOR` times wider (:meth:`GammaPrior.widened`), once, and that fit is
reported; a limit reached again is named in the warning, with the other ends resting on
it.

``z0``, the first inner value, needs no assumption: it lies in the band ``[R_0, L_0]``.

An interval end that the data do not move away from an *assumed* limit is not
identified by the record: :func:`unidentified` names the cause (an input that never
reverses, or reverses by less than the dead band) so the caller can report it.
"""

from __future__ import annotations

from math import comb

import numpy as np

from ..exceptions import DataValidationError
from .modes import band_range

__all__ = ["ASSUMED_LIMIT_RTOL", "LIMIT_RTOL", "WIDEN_FACTOR", "GammaPrior", "at_prior_limit",
           "default_gamma_box", "record_box", "reversal_summary", "unidentified"]

DEFAULT_B_BOUND = 1.0e4
M_FACTOR = 1.0e2
#: how much wider a default backlash limit gets when an end reaches it (see the module)
WIDEN_FACTOR = 8.0


def default_gamma_box(u, y, deta) -> np.ndarray:
    """The default a priori box of ``(m_l, c_l, m_r, c_r)`` (rows; see the module)."""
    du = float(np.ptp(u))
    dy = float(np.ptp(y)) + 2.0 * float(np.max(deta))
    if du <= 0:
        raise DataValidationError(
            "the input is constant: a record must move the input to identify anything.")
    m_max = M_FACTOR * dy / du
    return np.array([[0.0, m_max], [0.0, du], [0.0, m_max], [0.0, du]])


def record_box(na, b_count, u, gamma_box, theta_box=None, b_bound=DEFAULT_B_BOUND):
    """The full a priori box ``[theta, m_l, c_l, m_r, c_r, z0]``."""
    if theta_box is None:
        rows = [(-comb(na, i), comb(na, i)) for i in range(1, na + 1)]
        rows += [(-b_bound, b_bound)] * b_count
        theta_box = np.asarray(rows, dtype=float).reshape(-1, 2)
    g = np.asarray(gamma_box, dtype=float)
    return np.vstack([theta_box, g, [band_range(float(u[0]), g)]])


def reversal_summary(u) -> dict:
    """How far the input moves back after rising, and forward after falling.

    ``down``: the largest fall from a running maximum (what can cross the dead band from
    the right line to the left one); ``up``: the largest rise from a running minimum.
    """
    u = np.asarray(u, dtype=float)
    down = up = 0.0
    hi = lo = float(u[0])
    for v in u.tolist():
        hi, lo = max(hi, v), min(lo, v)
        down = max(down, hi - v)
        up = max(up, v - lo)
    return {"down": down, "up": up, "monotone": down == 0.0 or up == 0.0}


#: An end within this fraction (of the limit's magnitude or the row's width) of a
#: *default* a priori limit -- an assumption, not the record's answer -- is taken as set
#: by it and reported as not identified (infinite; the outward direction). New-user
#: trial 11: ``b1 >= -9999.975`` under the default ``|b_j| <= 1e4`` was reported as a
#: finite bound of the relaxation, though it came from ``b2 <= 1e4`` through the gain
#: equality, and the warning said b1 was not bounded.
ASSUMED_LIMIT_RTOL = 1e-3
#: ... and of any other a priori limit (one the user gave, or the model's own)
LIMIT_RTOL = 1e-6


def at_prior_limit(bound, prior, i, j, rtol=LIMIT_RTOL) -> bool:
    """Whether ``bound`` sits at the a priori limit ``prior[i, j]``: within ``rtol`` of
    the limit's magnitude or of the row's width, whichever is larger (relative, so the
    units of the record do not matter: an absolute ``1e-6`` took every identified end of a
    slope below ``1e-6`` for one at its limit). Default limits (assumptions) use
    :data:`ASSUMED_LIMIT_RTOL`."""
    lim = prior[i, j]
    return abs(bound - lim) <= rtol * max(abs(lim), prior[i, 1] - prior[i, 0])


def unidentified(u, names, bounds, prior, assumed, *, stopped_by_time=False, lps_stopped=0,
                 method="exact", rtol=LIMIT_RTOL) -> list[tuple[str, str]]:
    """``(name, cause)`` of every interval end stuck at an *assumed* a priori limit.

    ``bounds`` and ``prior`` have rows ``names``; ``assumed`` is a boolean (rows, 2)
    array marking the prior limits that are assumptions (not the chapter's model);
    ``stopped_by_time``: the time limit stopped the search; ``lps_stopped``: that many
    relaxation LPs ended before optimality (their own time limit, or a solver failure);
    either is then the cause named, unless the input never reverses (which no time
    changes); ``method``: the method that ran (the
    exact one is suggested only after the LP method); ``rtol``: of :func:`at_prior_limit`.
    """
    rev = reversal_summary(u)
    out = []
    for i, name in enumerate(names):
        for j in (0, 1):
            if not assumed[i, j]:
                continue
            if not at_prior_limit(bounds[i, j], prior, i, j, rtol):
                continue
            if rev["monotone"]:  # first: no time or LP changes this (recheck 52b)
                cause = ("the input never reverses, so only one line of the backlash is "
                         "ever active")
            elif stopped_by_time:
                cause = ("the time limit stopped the search before the record bounded it "
                         "(raise total_time_limit)")
            elif lps_stopped:
                cause = (f"{lps_stopped} LP(s) of the relaxation ended before optimality "
                         "(at their time limit, at most hammerbound.joint.relaxation."
                         "LP_TIME_LIMIT s, or HiGHS could not solve them), so the search "
                         "may not have bounded it; "
                         "rescaling the data or a narrower gamma_box may help")
            elif name.startswith("c") or name.startswith("m"):
                fix = ("a narrower gamma_box from what you know of the actuator, or "
                       "method='exact', usually bounds it" if method == "lp" else
                       "a narrower gamma_box from what you know of the actuator usually "
                       "bounds it")
                cause = (f"the relaxation does not bound it below the assumed limit. "
                         f"Either the input never moves back by more than the dead band "
                         f"(largest reversals: {rev['down']:.4g} down, {rev['up']:.4g} up), "
                         f"or the relaxation over the wide a priori box is too weak to tell: "
                         f"{fix}")
            else:
                cause = "the record does not excite this parameter"
            out.append((name, cause))
    return out


class GammaPrior:
    """The a priori box of the backlash, with which limits are assumptions."""

    def __init__(self, box, user_given):
        self.box = np.asarray(box, dtype=float)
        self.user_given = bool(user_given)

    def assumed(self):
        """Limits that are assumptions (upper limits; all of them when the user gave
        the box)."""
        a = np.zeros((4, 2), dtype=bool)
        a[:, 1] = True
        if self.user_given:
            a[:, 0] = self.box[:, 0] > 0
        return a

    def widened(self, rows) -> GammaPrior:
        """The default box with the upper limits of ``rows`` (indices into ``m_l, c_l,
        m_r, c_r``) :data:`WIDEN_FACTOR` times wider; a box the user gave stays."""
        if self.user_given:
            return self
        box = self.box.copy()
        for i in rows:
            box[i, 1] = box[i, 0] + WIDEN_FACTOR * (box[i, 1] - box[i, 0])
        return GammaPrior(box, user_given=False)

    def describe(self, reached=()) -> str:
        """The box as an assumption, each limit rounded inward (the box shown is never
        wider than the one used). ``reached``: names of the ends the search left at a
        default limit; then the finite intervals hold only inside the box, which is said
        here too (adversary 52: a true c_l above its default limit left m_l's finite
        interval off the truth, with the warning's word alone)."""
        who = "given" if self.user_given else "assumed (default; pass gamma_box to change)"
        text = (f"backlash box {who}: {self.limits()} (c_l, c_r >= 0: the dead band "
                "[-c_l, c_r] holds u = 0)")
        if not reached or self.user_given:
            return text
        return (f"{text}; the search reached its limit of {', '.join(reached)} (reported as "
                "not identified), so every finite interval holds only if the true backlash "
                "lies in this box")

    def limits(self) -> str:
        """``m_l in [lo, hi], ...``: the box's rows, each limit rounded inward."""
        from ..tables import rounded_text

        return ", ".join(
            f"{name} in [{rounded_text(lo, down=False)}, {rounded_text(hi, down=True)}]"
            for name, (lo, hi) in zip(("m_l", "c_l", "m_r", "c_r"), self.box, strict=True))
