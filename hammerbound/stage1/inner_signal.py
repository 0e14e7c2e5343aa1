"""The hand-off from stage 1 to stage 2 (section 22.4, (22.25)-(22.33)).

:class:`InnerSignalBounds` holds the exact bounds on the two inner PRBS levels that stage 1
implies for a PRBS ``+-u*`` (Result 1). It owns everything stage 2 needs from a PRBS record:

* :func:`read_prbs_level` reads ``u*`` from the input (or checks a given one);
* :meth:`InnerSignalBounds.transform` gives the central inner signal ``x^c_t`` and its
  radius ``Delta x_t`` (22.31)-(22.33);
* :meth:`InnerSignalBounds.input_groups` labels the samples that share one unknown inner
  value (``inner_signal="two-level"``: one per PRBS level, what Result 1 implies);
* :meth:`InnerSignalBounds.stage2_record` packs all of it into a :class:`Stage2Record`: an
  :class:`~hammerbound.IOData` (input ``x^c``, the measured output, the record's ``dt``,
  names and units) plus the input bounds and groups, ready for
  ``LinearEIVSetEstimator.fit(record.data, input_bound=record.input_bound,
  input_groups=record.input_groups)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..data.iodata import IOData
from ..data.validation import as_real
from ..exceptions import DataValidationError, ParameterValidationError
from ..results import IntervalSet

__all__ = ["INNER_SIGNALS", "InnerSignalBounds", "Stage2Record", "read_prbs_level"]

#: How stage 2 treats the inner-signal uncertainty: one error per sample (the chapter,
#: (22.31)-(22.34)) or one shared error per PRBS level (Result 1).
INNER_SIGNALS = ("independent", "two-level")


def read_prbs_level(u, prbs_level=None) -> float:
    """``u*`` of a PRBS input taking the two values ``+-u*``.

    With ``prbs_level`` given it is checked (a number > 0) and returned; otherwise it is read
    from ``u``, which must then take exactly two values of opposite sign and equal size.

    Raises
    ------
    DataValidationError
        ``u`` is not a two-level PRBS (the message names the distinct values).
    ParameterValidationError
        ``prbs_level`` is not a positive number.
    """
    if prbs_level is not None:
        return as_real("prbs_level", prbs_level, positive=True,
                       want="prbs_level must be a number u* > 0 (or None to read it from "
                            "the input), e.g. prbs_level=1.0")
    levels = np.unique(np.asarray(u, dtype=float))
    if levels.size != 2 or not np.isclose(levels[0], -levels[1], rtol=1e-9, atol=0):
        # as many digits as tell them apart (4 digits showed 2 + 1e-9 and 2 as "2. 2.",
        # trial 13)
        shown = "[" + " ".join(_distinct_text(levels[:5])) + "]"
        more = " ..." if levels.size > 5 else ""
        hint = ("Pass prbs_level=u* for a two-level signal with rounding noise." if levels.size == 2
                else "The two-stage method needs a PRBS +-u* for stage 2; for an ordinary "
                     "record (steps, sines, closed-loop data) use procedure='one-record' to "
                     "identify both blocks from it (with the steady-state points, if "
                     "given, used jointly).")
        raise DataValidationError(
            f"the PRBS input must take exactly two values +-u*; got {levels.size} distinct "
            f"value(s) {shown}{more}. {hint}")
    return float(levels[1])


def _distinct_text(values) -> list[str]:
    """``values`` (sorted, distinct) with the fewest significant digits (4 to 17) that
    print them all differently."""
    for digits in range(4, 18):
        text = [f"{v:.{digits}g}" for v in values]
        if len(set(text)) == len(text):
            return text
    return [repr(float(v)) for v in values]


@dataclass(frozen=True)
class Stage2Record:
    """What stage 1 hands to stage 2 for one PRBS record.

    Attributes
    ----------
    data : IOData
        Input: the central inner signal ``x^c_t`` (named ``"x"``, unit of the output);
        output: the measured output; the record's ``dt``, ``t0``, output name and unit.
    input_bound : ndarray of shape (N,)
        ``Delta x_t`` (22.31)-(22.33).
    input_groups : ndarray of shape (N,) or None
        Shared input-error labels (``"two-level"``: 0 at ``+u*``, 1 at ``-u*``), or None for
        independent per-sample errors (the chapter).
    inner_signal : str
        ``"independent"`` or ``"two-level"``.
    """

    data: IOData
    input_bound: np.ndarray
    input_groups: np.ndarray | None
    inner_signal: str


@dataclass(frozen=True)
class InnerSignalBounds:
    """Exact bounds on the inner PRBS levels for a PRBS ``+-u*`` (22.25)-(22.30).

    ``x_hi`` is ``xbar* = m_r (u* - c_r)`` (input ``+u*``), ``x_lo`` is
    ``x_* = m_l (-u* + c_l)`` (input ``-u*``; the chapter's (22.26) has a sign typo, we follow
    (22.1)). Each is ``(min, max)``.
    """

    u_star: float
    x_hi: tuple
    x_lo: tuple
    #: Largest slope ``max(m_l, m_r)`` of every feasible backlash (``None``: unknown). A PRBS
    #: sample within ``1e-9 u*`` of a level, but not exactly on it, has an inner value up to
    #: ``slope_max |u - level|`` away from the bounds at the level; the radius is widened
    #: by that much, and with ``slope_max=None`` only exact levels are accepted.
    slope_max: float | None = None

    @property
    def intervals(self) -> IntervalSet:
        """The two inner levels as an :class:`~hammerbound.results.IntervalSet`:
        ``x(+u*)`` = ``x_hi`` and ``x(-u*)`` = ``x_lo``."""
        return IntervalSet(("x(+u*)", "x(-u*)"), [self.x_hi, self.x_lo],
                           method="inner-signal bounds")

    @property
    def center(self) -> tuple[float, float]:
        """Central values ``(xbar^c, x_^c)`` (22.29)-(22.30)."""
        return tuple(float(v) for v in self.intervals.center)

    @property
    def radius(self) -> tuple[float, float]:
        """Uncertainty bounds ``(Delta xbar, Delta x_)`` (22.29)-(22.30)."""
        return tuple(float(v) for v in self.intervals.radius)

    def transform(self, u) -> tuple[np.ndarray, np.ndarray]:
        """Central inner signal ``x^c_t`` and radius ``Delta x_t`` for a PRBS ``u`` (22.31)-(22.33)."""
        u = np.asarray(u, dtype=float)
        if u.ndim != 1:
            raise DataValidationError("u must be a 1-D PRBS signal.")
        tol = 1e-9 * self.u_star if self.slope_max is not None else 0.0
        hi = np.abs(u - self.u_star) <= tol
        lo = np.abs(u + self.u_star) <= tol
        if not np.all(hi | lo):
            i = int(np.flatnonzero(~(hi | lo))[0])
            raise DataValidationError(
                f"u[{i}] = {u[i]:g} is not a PRBS level +-{self.u_star:g}; the inner-signal "
                "bounds (22.31)-(22.33) hold only for a two-level input. For a record of "
                "another input, fit the identifier with procedure='one-record' on it (its "
                "output envelope takes any input)."
            )
        (ch, cl), (rh, rl) = self.center, self.radius
        radius = np.where(hi, rh, rl)
        if self.slope_max is not None:
            # outward: the inner value at u differs from the one at the level by <= m |du|
            off = np.where(hi, np.abs(u - self.u_star), np.abs(u + self.u_star))
            radius = radius + self.slope_max * off
        return np.where(hi, ch, cl), radius

    def input_groups(self, u, inner_signal: str = "independent") -> np.ndarray | None:
        """Labels of the samples that share one unknown inner value.

        ``"two-level"``: Result 1 makes the inner signal of a PRBS take exactly two values,
        so every sample at ``+u*`` shares one error (label 0) and every sample at ``-u*``
        another (label 1). ``"independent"``: None (one error per sample, as the chapter).
        """
        if inner_signal not in INNER_SIGNALS:
            raise ParameterValidationError(
                f"inner_signal must be one of {INNER_SIGNALS}; got {inner_signal!r}.")
        if inner_signal == "independent":
            return None
        return (np.asarray(u, dtype=float) < 0).astype(int)

    def stage2_record(self, data: IOData, inner_signal: str = "independent") -> Stage2Record:
        """The stage-2 record of a PRBS record ``data`` (input ``+-u*``, measured output).

        The returned :class:`Stage2Record` keeps the record's ``dt``, ``t0``, output name
        and unit; its input is the central inner signal (22.31)-(22.33).
        """
        if not isinstance(data, IOData):
            raise DataValidationError(
                f"stage2_record needs an IOData (the PRBS record); got {type(data).__name__}.")
        xc, dx = self.transform(data.u)
        groups = self.input_groups(data.u, inner_signal)
        inner = IOData(xc, data.y, data.dt, input_name="x", output_name=data.output_name,
                       input_unit=data.output_unit, output_unit=data.output_unit, t0=data.t0,
                       sample_index=data.sample_index, time_unit=data.time_unit)
        return Stage2Record(inner, dx, groups, inner_signal)
