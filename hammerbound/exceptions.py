"""Typed errors raised by hammerbound.

Every error subclasses a built-in exception so that callers can catch either the
precise hammerbound type or the generic one (``ValueError``, ``RuntimeError``...).
Messages always say what to change.
"""

from __future__ import annotations


class HammerboundError(Exception):
    """Base class of every error raised on purpose by hammerbound."""


class DataValidationError(HammerboundError, ValueError):
    """Input data are malformed (NaN/inf, wrong shape, mismatched lengths ...)."""


class ParameterValidationError(HammerboundError, ValueError):
    """A hyper-parameter or model parameter is out of its valid range."""


class DataScaleError(DataValidationError):
    """The data's magnitudes lie outside the range the arithmetic can certify (see
    :func:`hammerbound.data.validation.check_scale`); rescale the signals and bounds."""


class NotEnoughAmplitudesError(DataValidationError):
    """A backlash side has fewer than two distinct input amplitudes (Remark 22.2)."""


class OutputPathError(HammerboundError, OSError):
    """An output path cannot be written (missing or read-only parent, directory or special
    file in the way); raised before any work starts.

    Attributes
    ----------
    path : str
        The output path as given.
    """

    def __init__(self, message: str, *, path=None):
        super().__init__(message)
        self.path = None if path is None else str(path)

    def __str__(self) -> str:  # OSError's own __str__ would format errno/strerror
        return str(self.args[0]) if self.args else ""


class OutputExistsError(OutputPathError, FileExistsError):
    """An output file (or a report's file) exists already and overwriting was not asked for."""


class EmptyFeasibleSetError(HammerboundError, ValueError):
    """No parameter of the model class explains the data within the error bounds.

    Attributes
    ----------
    side : str or None
        ``"left"``/``"right"`` for stage 1, ``None`` for stage 2.
    first_index : int or None
        Index (in the caller's data) of the first measurement that empties the set.
    relaxation : str or None
        ``"lp"`` when the LP outer set (:func:`hammerbound.relaxations.lp_bounds`) is
        certified empty, another method's name when only a tighter relaxation is, None when
        not said.
    """

    def __init__(self, message: str, *, side: str | None = None, first_index: int | None = None,
                 relaxation: str | None = None):
        super().__init__(message)
        self.side = side
        self.first_index = first_index
        self.relaxation = relaxation


class IllPosedBacklashError(HammerboundError, ValueError):
    """The backlash (22.1) is operated beyond the crossing of its two lines (m_l != m_r)."""


class ResultOneViolationError(HammerboundError, ValueError):
    """A PRBS level u* does not satisfy Result 1 (u* inside the dead zone or past the crossing)."""


class UnboundedSetError(HammerboundError, ValueError):
    """A parameter's interval reaches the a priori box: the data do not bound it there
    (supply more data or a box), or a search stopped there before it could tell (the
    message says which; give it more time)."""


class SolverError(HammerboundError, RuntimeError):
    """A numerical solver failed and no guaranteed bound could be recovered."""


class SolverNotAvailableError(HammerboundError, ValueError):
    """An unknown or uninstalled solver backend was requested."""


class SolverOptionError(HammerboundError, TypeError):
    """Unknown or ill-typed solver options."""


class RelaxationTooLargeError(HammerboundError, ValueError):
    """The moment relaxation would exceed its size budget; use method "lp" or "exact"."""


class SearchLimitWarning(UserWarning):
    """A bound search stopped at a node/time limit; the reported bound is still guaranteed
    (an outer bound, never wider than the LP bound) but may be looser than the exact one."""


class DataWarning(UserWarning):
    """The data were read, but something in them may not be used as you meant (e.g. a
    column that looks like a time base was not recognised); the message says how to be
    explicit."""


class NotIdentifiedWarning(UserWarning):
    """The record does not bound a parameter (e.g. an input that never reverses by more
    than the backlash's dead band): the warning names the parameters and the cause; their
    interval ends are reported as infinite (or, with a box you gave, as its limits)."""
